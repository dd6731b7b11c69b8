/* The firmware's own interrupt state at start (issue 28), whatever ran
   before it: the ESP8266's ROM hands over with PS.INTLEVEL high, PS.EXCM
   set and INTENABLE bits the firmware does not own. Upstream rustc has no
   inline assembly for Xtensa, hence a leaf here (call0 ABI).

   INTENABLE first (every interrupt off), then PS = UM alone: interrupt
   level 0, EXCM clear, level-1 interrupts and exceptions to the user
   vector (Xtensa ISA, PS register; the lx106 has no register windows, so
   WOE stays 0). Each interrupt the firmware owns is then enabled by its
   owner (src/board/esp8266.rs). */

#include "function.inc"

    .set PS_UM, 0x20

FUNC paperbot_interrupt_handover
    movi    a2, 0
    wsr.intenable a2
    rsync
    movi    a2, PS_UM
    wsr.ps  a2
    rsync
    ret
