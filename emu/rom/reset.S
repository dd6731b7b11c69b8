/*
 * The board's mask ROM, part 1: exception vectors, the reset path and the
 * entries of the ROM routines (their bodies are in routines.c; the boot
 * itself, in C, in boot.c).
 *
 * Reset: SP = 0x3FFFFFF0 (the stack the ROM leaves the image), rom_boot()
 * loads the boot image and returns its entry, which is called as the
 * chip's ROM hands over: interrupts masked, PS = UM | EXCM | INTLEVEL 15,
 * and INTENABLE holding bits the image does not own (SLC, UART, watchdog:
 * ESP8266 interrupts 0, 5, 8), UART0's among them live (rom_boot leaves
 * its TX-FIFO-empty interrupt enabled). An image must set PS and
 * INTENABLE itself: one that keeps PS never takes an interrupt, one that
 * keeps INTENABLE takes UART0's, which it has no handler for, for ever.
 *
 * An exception or interrupt at the ROM's vectors (before the image moves
 * VECBASE) is reported by rom_exception() with EXCCAUSE, EPC1 and EXCVADDR.
 *
 * QEMU's lx106 (target/xtensa/core-lx106/core-isa.h) has VECBASE reset
 * 0x40000000 and the second static reset vector at 0x40000080, which the
 * board selects: the ESP8266's own reset vector in its ROM.
 */
    .equ ROM_STACK,        0x3ffffff0
    .equ HANDOVER_PS,      0x3f         /* UM | EXCM | INTLEVEL 15 */
    .equ HANDOVER_INTENABLE, 0x121      /* SLC, UART, WDT: not the image's */

/* ---- vectors (offsets from VECBASE, core-isa.h) ------------------------- */
    .section .vectors, "ax"
    .global rom_vectors
rom_vectors:
    j       rom_vec_other
    .org    0x10                    /* debug (= level 2) */
    j       rom_vec_debug
    .org    0x20                    /* NMI (level 3) */
    j       rom_vec_other
    .org    0x30                    /* kernel exception */
    j       rom_vec_kernel
    .org    0x50                    /* user exception */
    j       rom_vec_user
    .org    0x70                    /* double exception */
    j       rom_vec_double
    .org    0x80                    /* reset vector 1 */
    .global rom_reset_vector
rom_reset_vector:
    j       rom_reset

/* ---- reset --------------------------------------------------------------- */
    .section .text.rom_reset, "ax"
    .literal .Lstack, ROM_STACK
    .literal .Lintenable, HANDOVER_INTENABLE
    .align  4
    .global rom_reset
rom_reset:
    l32r    a1, .Lstack
    call0   rom_boot                /* a2: the entry */
    l32r    a3, .Lintenable
    wsr     a3, intenable
    movi    a3, HANDOVER_PS
    wsr     a3, ps
    rsync
    movi    a0, 0                   /* the entry never returns */
    jx      a2

/* ---- exceptions at the ROM's vectors: reported, then wait for a reset ---- */
    .section .text.rom_vec, "ax"
    .literal .Lvec_stack, ROM_STACK
    .literal .Lname_user, name_user
    .literal .Lname_kernel, name_kernel
    .literal .Lname_double, name_double
    .literal .Lname_debug, name_debug
    .literal .Lname_other, name_other
    .align  4
rom_vec_user:
    l32r    a2, .Lname_user
    j       rom_vec_single
rom_vec_kernel:
    l32r    a2, .Lname_kernel
    j       rom_vec_single
rom_vec_double:
    l32r    a2, .Lname_double
    movi    a3, 1                   /* the PC is in DEPC */
    j       rom_vec_report
rom_vec_debug:
    l32r    a2, .Lname_debug
    j       rom_vec_single
rom_vec_other:
    l32r    a2, .Lname_other
rom_vec_single:
    movi    a3, 0
rom_vec_report:
    l32r    a1, .Lvec_stack
    call0   rom_exception           /* never returns */

    .section .rodata.rom_vector_names, "a"
name_user:      .asciz "user"
name_kernel:    .asciz "kernel"
name_double:    .asciz "double"
name_debug:     .asciz "debug"
name_other:     .asciz "NMI or other"

/* ---- ROM routine entries, at the addresses of rom-functions.x ------------ */
    .macro  rom_entry name, body
    .section .entry.\name, "ax"
    .global \name
    .type   \name, @function
\name:
    j       \body
    .endm

    rom_entry memcpy,    rom_memcpy
    rom_entry memmove,   rom_memmove
    rom_entry memset,    rom_memset
    rom_entry memcmp,    rom_memcmp
    rom_entry __muldi3,  rom_muldi3
    rom_entry __udivdi3, rom_udivdi3
    rom_entry __umoddi3, rom_umoddi3
    rom_entry __divdi3,  rom_divdi3
    rom_entry SPIEraseSector, rom_spi_erase_sector
    rom_entry SPIWrite,  rom_spi_write
    rom_entry SPIRead,   rom_spi_read
