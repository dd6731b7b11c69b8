/* The assembly of xtensa-lx-rt 0.12 (esp8266 feature), for `cargo fw-image`
   (upstream rustc rejects inline asm on Xtensa): the exception vectors and
   the handlers that save the interrupted context, call the Rust handlers
   and return. The rewrite (xtask/src/rewrite.rs) removes the crate's
   #[naked] functions and global_asm!, whose symbols these are; the crate's
   `set_vecbase` and `reset_internal_timers` call the xtensa_lx_rt_* leaves.

   Where the exception vectors are is the link script's business
   (exception.x at the repository root); each one saves a0 in EXCSAVE1 and
   jumps to its handler with call0 (which clobbers a0, hence the save).

   call0 ABI throughout (the lx106 has no register windows). */

/* The saved frame: xtensa_lx_rt::exception::Context, #[repr(C)]:
   PC, PS, A0..A15, SAR, EXCCAUSE, EXCVADDR (4 bytes each). */
    .set FRAME_PC,        0
    .set FRAME_PS,        4
    .set FRAME_A0,        8
    .set FRAME_A1,       12
    .set FRAME_SAR,      72
    .set FRAME_EXCCAUSE, 76
    .set FRAME_EXCVADDR, 80
/* addmi takes multiples of 256; the frame needs 84 bytes */
    .set FRAME_SIZE,    256

/* EXCCAUSE of a level-1 interrupt */
    .set CAUSE_LEVEL1_INTERRUPT, 4

#include "function.inc"

/* ---- the vectors -------------------------------------------------------- */


    .section .DebugException.text, "ax"
    .global _DebugExceptionVector
    .type _DebugExceptionVector, @function
    .align 4
_DebugExceptionVector:
    wsr     a0, excsave1
    call0   __naked_debug_exception

    .section .NMIException.text, "ax"
    .global _NMIExceptionVector
    .type _NMIExceptionVector, @function
    .align 4
_NMIExceptionVector:
    wsr     a0, excsave1
    call0   __naked_nmi_exception

    .section .KernelException.text, "ax"
    .global _KernelExceptionVector
    .type _KernelExceptionVector, @function
    .align 4
_KernelExceptionVector:
    wsr     a0, excsave1
    call0   __naked_kernel_exception

    .section .UserException.text, "ax"
    .global _UserExceptionVector
    .type _UserExceptionVector, @function
    .align 4
_UserExceptionVector:
    wsr     a0, excsave1
    call0   __naked_user_exception

    .section .DoubleException.text, "ax"
    .global _DoubleExceptionVector
    .type _DoubleExceptionVector, @function
    .align 4
_DoubleExceptionVector:
    wsr     a0, excsave1
    call0   __naked_double_exception

/* ---- saving and restoring the interrupted context ----------------------- */

/* a2..a15 and SAR into the frame at sp. Called with call0; uses a3. */
FUNC save_context
    s32i    a2,  sp, 16
    s32i    a3,  sp, 20
    s32i    a4,  sp, 24
    s32i    a5,  sp, 28
    s32i    a6,  sp, 32
    s32i    a7,  sp, 36
    s32i    a8,  sp, 40
    s32i    a9,  sp, 44
    s32i    a10, sp, 48
    s32i    a11, sp, 52
    s32i    a12, sp, 56
    s32i    a13, sp, 60
    s32i    a14, sp, 64
    s32i    a15, sp, 68
    rsr     a3,  sar
    s32i    a3,  sp, FRAME_SAR
    ret

/* SAR and a2..a15 from the frame at sp. Called with call0. */
FUNC restore_context
    l32i    a3,  sp, FRAME_SAR
    wsr     a3,  sar
    l32i    a2,  sp, 16
    l32i    a3,  sp, 20
    l32i    a4,  sp, 24
    l32i    a5,  sp, 28
    l32i    a6,  sp, 32
    l32i    a7,  sp, 36
    l32i    a8,  sp, 40
    l32i    a9,  sp, 44
    l32i    a10, sp, 48
    l32i    a11, sp, 52
    l32i    a12, sp, 56
    l32i    a13, sp, 60
    l32i    a14, sp, 64
    l32i    a15, sp, 68
    ret

/* Entry from a vector (a0 in EXCSAVE1, the exception's PC in EPC1 or DEPC):
   a frame below the interrupted sp with PC, a0, a1, PS, EXCCAUSE, EXCVADDR
   and the rest; on return sp points at it. */
    .macro ENTER epc
    mov     a0, a1
    addmi   sp, sp, -FRAME_SIZE
    s32i    a0, sp, FRAME_A1
    rsr     a0, \epc
    s32i    a0, sp, FRAME_PC
    rsr     a0, excsave1
    s32i    a0, sp, FRAME_A0
    rsr     a0, ps
    s32i    a0, sp, FRAME_PS
    rsr     a0, exccause
    s32i    a0, sp, FRAME_EXCCAUSE
    rsr     a0, excvaddr
    s32i    a0, sp, FRAME_EXCVADDR
    call0   save_context
    .endm

/* Back to the interrupted code's registers (its PS and EPC1 too, for rfe). */
    .macro LEAVE
    call0   restore_context
    l32i    a0, sp, FRAME_PS
    wsr     a0, ps
    l32i    a0, sp, FRAME_PC
    wsr     a0, epc1
    l32i    a0, sp, FRAME_A0
    l32i    sp, sp, FRAME_A1
    rsync
    .endm

/* ---- the handlers -------------------------------------------------------- */

/* The user vector: level-1 interrupts go to __level_1_interrupt(1, frame),
   every other cause to __exception(cause, frame). */
FUNC __default_naked_exception
    ENTER   epc1
    rsr     a2, exccause
    mov     a3, sp
    beqi    a2, CAUSE_LEVEL1_INTERRUPT, 1f
    call0   __exception
    j       2f
1:  movi    a2, 1
    call0   __level_1_interrupt
2:  LEAVE
    rfe

/* Kernel, NMI, debug and alloca exceptions: handler(cause, frame). */
    .macro HANDLER name, handler
FUNC \name
    ENTER   epc1
    l32i    a2, sp, FRAME_EXCCAUSE
    mov     a3, sp
    call0   \handler
    LEAVE
    rfe
    .endm

    HANDLER __default_naked_kernel_exception, __kernel_exception
    HANDLER __default_naked_nmi_exception, __nmi_exception
    HANDLER __default_naked_debug_exception, __debug_exception
    HANDLER __default_naked_alloc_exception, __alloc_exception

/* A double exception: __double_exception(cause, frame), which does not
   return (its default panics). */
FUNC __default_naked_double_exception
    ENTER   depc
    l32i    a2, sp, FRAME_EXCCAUSE
    mov     a3, sp
    call0   __double_exception
1:  j       1b

/* ---- the crate's two leaves --------------------------------------------- */

FUNC xtensa_lx_rt_set_vecbase   /* (base) */
    wsr.vecbase a2
    ret

/* The crate zeroes CCOMPAREn only where its build script finds timers in
   the core's configuration, which it does for the ESP32s, not for the
   ESP8266: here too, nothing. */
FUNC xtensa_lx_rt_reset_internal_timers
    ret
