/*
 * The board's mask ROM, part 1: exception vectors, the reset path and the
 * entries of the ROM routines (their bodies are in routines.c).
 *
 * Reset (ESP8266 boot from SPI flash, as Espressif's ROM loader does it):
 * the boot image at flash offset 0, mapped at 0x40200000, is read as the
 * esptool "version 1" image: an 8-byte header (magic 0xE9, segment count,
 * flash mode, flash size/frequency, entry address), then each segment as
 * load address, length, data; then zero padding up to the last byte of a
 * 16-byte block, which holds the checksum (0xEF XOR every data byte). Each
 * segment is copied to its address, the checksum is checked, and the entry
 * is called with the stack the ROM leaves (SP = 0x3FFFFFF0) and PS.UM set,
 * interrupts at level 0 and all of them disabled (INTENABLE = 0).
 *
 * QEMU's lx106 (target/xtensa/core-lx106/core-isa.h) has VECBASE reset
 * 0x40000000 and the second static reset vector at 0x40000080, which the
 * board selects: the ESP8266's own reset vector in its ROM.
 */
    .equ FLASH_MAPPED,   0x40200000   /* flash offset 0 through the cache */
    .equ UART0_FIFO,     0x60000000
    .equ ROM_STACK,      0x3ffffff0
    .equ IMAGE_MAGIC,    0xe9
    .equ CHECKSUM_SEED,  0xef
    .equ PS_UM,          0x20

/* ---- vectors (offsets from VECBASE, core-isa.h) ------------------------- */
    .section .vectors, "ax"
    .global rom_vectors
rom_vectors:
    j       rom_unexpected
    .org    0x10                    /* debug (= level 2) */
    j       rom_unexpected
    .org    0x20                    /* NMI (level 3) */
    j       rom_unexpected
    .org    0x30                    /* kernel exception */
    j       rom_unexpected
    .org    0x50                    /* user exception */
    j       rom_unexpected
    .org    0x70                    /* double exception */
    j       rom_unexpected
    .org    0x80                    /* reset vector 1 */
    .global rom_reset_vector
rom_reset_vector:
    j       rom_reset

/* ---- reset --------------------------------------------------------------- */
    .section .text.rom_reset, "ax"
    .literal .Lflash, FLASH_MAPPED
    .literal .Lstack, ROM_STACK
    .literal .Lmsg_magic, msg_magic
    .literal .Lmsg_length, msg_length
    .literal .Lmsg_checksum, msg_checksum
    .align  4
    .global rom_reset
rom_reset:
    movi    a0, 0
    wsr     a0, intenable
    l32r    a2, .Lflash             /* a2: read pointer in the image */
    l8ui    a3, a2, 0
    movi    a4, IMAGE_MAGIC
    bne     a3, a4, .Lbad_magic
    l8ui    a5, a2, 1               /* a5: segments left */
    l32i    a6, a2, 4               /* a6: entry */
    addi    a2, a2, 8
    movi    a7, 0                   /* a7: XOR of every data word */
.Lsegment:
    beqz    a5, .Lsegments_done
    l32i    a8, a2, 0               /* a8: load address */
    l32i    a9, a2, 4               /* a9: bytes left */
    addi    a2, a2, 8
    extui   a10, a9, 0, 2           /* esptool pads segments to words */
    bnez    a10, .Lbad_length
.Lword:
    beqz    a9, .Lsegment_done
    l32i    a10, a2, 0
    s32i    a10, a8, 0
    xor     a7, a7, a10
    addi    a2, a2, 4
    addi    a8, a8, 4
    addi    a9, a9, -4
    j       .Lword
.Lsegment_done:
    addi    a5, a5, -1
    j       .Lsegment
.Lsegments_done:
    srli    a10, a7, 16             /* fold the word XOR into a byte */
    xor     a7, a7, a10
    srli    a10, a7, 8
    xor     a7, a7, a10
    extui   a7, a7, 0, 8
    movi    a10, CHECKSUM_SEED
    xor     a7, a7, a10
    movi    a10, 15                 /* checksum: last byte of the 16-byte block */
    or      a2, a2, a10
    l8ui    a10, a2, 0
    bne     a7, a10, .Lbad_checksum
    l32r    a1, .Lstack
    movi    a0, PS_UM
    wsr     a0, ps
    rsync
    movi    a0, 0                   /* the entry never returns */
    jx      a6

.Lbad_magic:
    l32r    a2, .Lmsg_magic
    j       rom_fail
.Lbad_length:
    l32r    a2, .Lmsg_length
    j       rom_fail
.Lbad_checksum:
    l32r    a2, .Lmsg_checksum
    j       rom_fail

/* ---- failure: a line on UART0, then wait for a reset --------------------- */
    .section .text.rom_fail, "ax"
    .literal .Luart, UART0_FIFO
    .literal .Lmsg_unexpected, msg_unexpected
    .align  4
    .global rom_unexpected
rom_unexpected:
    l32r    a2, .Lmsg_unexpected
    .global rom_fail
rom_fail:                           /* a2: NUL-terminated message */
    l32r    a3, .Luart
1:  l8ui    a4, a2, 0
    beqz    a4, 2f
    s32i    a4, a3, 0
    addi    a2, a2, 1
    j       1b
2:  waiti   15
    j       2b

    .section .rodata.rom_messages, "a"
msg_magic:      .asciz "\r\nrom: no boot image at flash offset 0 (magic is not 0xE9)\r\n"
msg_length:     .asciz "\r\nrom: boot image segment length is not a multiple of 4\r\n"
msg_checksum:   .asciz "\r\nrom: boot image checksum mismatch\r\n"
msg_unexpected: .asciz "\r\nrom: exception or interrupt at the ROM's vectors\r\n"

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
