/* What upstream LLVM's Xtensa backend calls for the esp8266 cpu and no
   library of ours provides (Espressif's LLVM emits these inline):
   - `abort`, for llvm.trap (a panic with panic=abort ends here after the
     panic handler, and core::intrinsics::abort): an illegal instruction,
     so the exception handler reports it; never returns;
   - the 1-, 2- and 4-byte atomic loads and stores: the lx106 has no
     S32C1I (no compare-and-swap), and on this single core an aligned load
     or store is atomic; memw on both sides orders it like SeqCst, whatever
     the ordering argument says.
   In IRAM: the servo interrupt uses the atomics. */

#include "function.inc"

FUNC abort
    ill
1:  j       1b

FUNC __atomic_load_1        /* (ptr, ordering) -> value */
    memw
    l8ui    a2, a2, 0
    memw
    ret
FUNC __atomic_load_2
    memw
    l16ui   a2, a2, 0
    memw
    ret
FUNC __atomic_load_4
    memw
    l32i    a2, a2, 0
    memw
    ret
FUNC __atomic_store_1       /* (ptr, value, ordering) */
    memw
    s8i     a3, a2, 0
    memw
    ret
FUNC __atomic_store_2
    memw
    s16i    a3, a2, 0
    memw
    ret
FUNC __atomic_store_4
    memw
    s32i    a3, a2, 0
    memw
    ret
