/* The functions of xtensa-lx 0.7 that are inline assembly in the crate,
   for `cargo fw-image` (upstream rustc rejects inline asm on Xtensa). The
   rewrite (xtask/src/rewrite.rs) turns `<module>::<name>` into a call to
   `xtensa_lx_<module>_<name>` with the same signature.

   call0 ABI: arguments in a2, a3, ...; the result in a2; return to a0.
   All in IRAM: the servo interrupt calls some of them, and flash is not
   reachable from an interrupt while the cache is busy.

   Left out on purpose, so that a use fails the link with the name of the
   missing symbol: what the lx106 does not have (CCOMPARE1..3, the OCD
   register read `rer`, PRID), and set_stack_pointer, which only works
   inline. */

#include "function.inc"

/* lib.rs */
FUNC xtensa_lx_set_vecbase          /* (base: *const u32) */
    wsr.vecbase a2
    ret
FUNC xtensa_lx_get_stack_pointer    /* -> *const u32: a leaf keeps the caller's sp */
    mov     a2, a1
    ret
FUNC xtensa_lx_get_program_counter  /* -> *const u32: the return address, in the caller */
    mov     a2, a0
    ret
FUNC xtensa_lx_debug_break
    break   1, 15
    ret

/* interrupt.rs */
FUNC xtensa_lx_interrupt_set_mask   /* (mask) -> previous INTENABLE */
    xsr.intenable a2
    rsync
    ret
FUNC xtensa_lx_interrupt_disable_mask   /* (mask) -> previous INTENABLE */
    movi    a3, 0
    xsr.intenable a3                /* all off while we compute */
    movi    a4, -1
    xor     a2, a2, a4              /* !mask */
    and     a4, a3, a2
    rsync
    wsr.intenable a4
    rsync
    mov     a2, a3
    ret
FUNC xtensa_lx_interrupt_enable_mask    /* (mask) -> previous INTENABLE */
    movi    a3, 0
    xsr.intenable a3
    or      a4, a3, a2
    rsync
    wsr.intenable a4
    rsync
    mov     a2, a3
    ret
FUNC xtensa_lx_interrupt_get_mask
    rsr.intenable a2
    ret
FUNC xtensa_lx_interrupt_get        /* pending interrupts */
    rsr.interrupt a2
    ret
FUNC xtensa_lx_interrupt_set        /* (mask): software interrupts */
    wsr.intset a2
    ret
FUNC xtensa_lx_interrupt_clear      /* (mask): edge and software interrupts */
    wsr.intclear a2
    ret
FUNC xtensa_lx_interrupt_get_level  /* PS.INTLEVEL */
    rsr.ps  a2
    extui   a2, a2, 0, 4
    ret

/* timer.rs */
FUNC xtensa_lx_timer_get_ccompare0
    rsr.ccompare0 a2
    ret
FUNC xtensa_lx_timer_set_ccompare0  /* (val) */
    wsr.ccompare0 a2
    isync
    ret
FUNC xtensa_lx_timer_get_cycle_count
    rsr.ccount a2
    ret
