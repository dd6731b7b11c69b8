/*
 * A test image for the board's watchdog (cargo fw-emu --self-test): counts
 * its boots in RTC memory (kept across a watchdog reset, as on the chip),
 * prints "wdt-test: boot N", starts the watchdog as esp8266-hal does (two
 * stages of 0.84 s), feeds it for 0.5 s, prints "wdt-test: starving" and
 * stops feeding. The board must reset it 1.68 s later and boot it again.
 */
    .equ UART0_FIFO,    0x60000000
    .equ WDT_BASE,      0x60000900      /* CTL +0, OP +4, OP_ND +8, RST +0x14 */
    .equ BOOT_COUNT,    0x60001100      /* RTC memory, user part */
    .equ FEED_CYCLES,   40000000        /* 0.5 s at 80 MHz */
    .equ WDT_STAGE_084, 10
    .equ WDT_CTL_MODE,  0x38            /* bits 3..5, as esp8266-hal writes */
    .equ WDT_ENABLE,    1
    .equ WDT_FEED,      0x73

    .section .rodata
msg_boot:     .asciz "wdt-test: boot "
msg_starving: .asciz "wdt-test: starving\r\n"
msg_eol:      .asciz "\r\n"

    .text
    .literal .Lboot_count, BOOT_COUNT
    .literal .Lwdt, WDT_BASE
    .literal .Lfeed_cycles, FEED_CYCLES
    .literal .Lmsg_boot, msg_boot
    .literal .Lmsg_starving, msg_starving
    .literal .Lmsg_eol, msg_eol
    .literal .Luart, UART0_FIFO
    .align  4
    .global _start
_start:
    l32r    a12, .Lboot_count
    l32i    a13, a12, 0
    addi    a13, a13, 1
    s32i    a13, a12, 0
    l32r    a2, .Lmsg_boot
    call0   puts
    addi    a2, a13, '0'            /* boot count, one digit */
    call0   putc
    l32r    a2, .Lmsg_eol
    call0   puts

    l32r    a4, .Lwdt
    movi    a5, WDT_CTL_MODE
    s32i    a5, a4, 0
    movi    a5, WDT_STAGE_084
    s32i    a5, a4, 4
    s32i    a5, a4, 8
    movi    a5, WDT_FEED
    s32i    a5, a4, 0x14
    movi    a5, WDT_CTL_MODE | WDT_ENABLE
    s32i    a5, a4, 0

    rsr     a6, ccount
    l32r    a8, .Lfeed_cycles
1:  movi    a5, WDT_FEED
    s32i    a5, a4, 0x14
    rsr     a7, ccount
    sub     a7, a7, a6
    bltu    a7, a8, 1b

    l32r    a2, .Lmsg_starving
    call0   puts
2:  j       2b

/* putc(a2), puts(a2 = NUL-terminated string); clobber a2..a5 */
    .align  4
putc:
    l32r    a3, .Luart
    s32i    a2, a3, 0
    ret
    .align  4
puts:
    mov     a4, a0
    mov     a5, a2
3:  l8ui    a2, a5, 0
    beqz    a2, 4f
    call0   putc
    addi    a5, a5, 1
    j       3b
4:  mov     a0, a4
    ret
