/*
 * The ESP8266 mask-ROM routines the firmware links to (rom-functions.x at the
 * repository root lists them and their addresses), written for this board.
 * The ROM's own code is not available; these follow the C library / libgcc
 * contracts the firmware expects: memcpy, memmove, memset, memcmp (ISO C
 * 7.24) and libgcc's 64-bit helpers __muldi3, __udivdi3, __umoddi3, __divdi3.
 *
 * The lx106 has MULL (32 x 32 -> low 32) but no MULUH and no divide
 * (core-isa.h: XCHAL_HAVE_MUL32_HIGH 0, XCHAL_HAVE_DIV32 0), so products
 * are built from 16-bit halves and quotients by shift and subtract. Nothing
 * here may call back into a libgcc or libc routine: build-qemu.sh rejects an
 * image with undefined symbols.
 *
 * The entries at the ROM addresses (reset.S) jump to these; the ABI is call0
 * (the only one the lx106 has), the caller's stack is used.
 */
#include <stddef.h>
#include <stdint.h>

void *rom_memcpy(void *dst, const void *src, size_t n)
{
    uint8_t *d = dst;
    const uint8_t *s = src;

    while (n--) {
        *d++ = *s++;
    }
    return dst;
}

void *rom_memmove(void *dst, const void *src, size_t n)
{
    uint8_t *d = dst;
    const uint8_t *s = src;

    if (d <= s || d >= s + n) {
        return rom_memcpy(dst, src, n);
    }
    while (n--) { /* overlapping, destination above: copy from the end */
        d[n] = s[n];
    }
    return dst;
}

void *rom_memset(void *dst, int c, size_t n)
{
    uint8_t *d = dst;

    while (n--) {
        *d++ = (uint8_t)c;
    }
    return dst;
}

int rom_memcmp(const void *a, const void *b, size_t n)
{
    const uint8_t *x = a, *y = b;

    for (; n; n--, x++, y++) {
        if (*x != *y) {
            return *x < *y ? -1 : 1;
        }
    }
    return 0;
}

/* The full 64-bit product of two 32-bit numbers, from four 16 x 16 products. */
static uint64_t mul_32x32(uint32_t a, uint32_t b)
{
    uint32_t al = a & 0xffff, ah = a >> 16, bl = b & 0xffff, bh = b >> 16;
    uint32_t ll = al * bl, lh = al * bh, hl = ah * bl, hh = ah * bh;
    uint32_t mid = (ll >> 16) + (lh & 0xffff) + (hl & 0xffff);
    uint32_t lo = (ll & 0xffff) | (mid << 16);
    uint32_t hi = hh + (lh >> 16) + (hl >> 16) + (mid >> 16);

    return ((uint64_t)hi << 32) | lo;
}

/* a * b mod 2^64 (signed and unsigned alike in two's complement). */
uint64_t rom_muldi3(uint64_t a, uint64_t b)
{
    uint32_t al = (uint32_t)a, ah = (uint32_t)(a >> 32);
    uint32_t bl = (uint32_t)b, bh = (uint32_t)(b >> 32);
    uint64_t low = mul_32x32(al, bl);

    return low + ((uint64_t)(al * bh + ah * bl) << 32);
}

/* Restoring division, one quotient bit per step. Division by zero gives an
 * all-ones quotient and the dividend as remainder (the loop's natural result;
 * the firmware never divides by zero). */
static uint64_t udivmod64(uint64_t num, uint64_t den, uint64_t *rem)
{
    uint64_t q = 0, r = 0;

    for (int i = 0; i < 64; i++) {
        r = (r << 1) | (num >> 63);
        num <<= 1;
        q <<= 1;
        if (r >= den) {
            r -= den;
            q |= 1;
        }
    }
    *rem = r;
    return q;
}

uint64_t rom_udivdi3(uint64_t a, uint64_t b)
{
    uint64_t r;
    return udivmod64(a, b, &r);
}

uint64_t rom_umoddi3(uint64_t a, uint64_t b)
{
    uint64_t r;
    udivmod64(a, b, &r);
    return r;
}

/* Truncating signed division (C semantics): quotient of the magnitudes,
 * negated when the signs differ. */
int64_t rom_divdi3(int64_t a, int64_t b)
{
    uint64_t ua = a < 0 ? -(uint64_t)a : (uint64_t)a;
    uint64_t ub = b < 0 ? -(uint64_t)b : (uint64_t)b;
    uint64_t r, q = udivmod64(ua, ub, &r);

    return (int64_t)((a < 0) != (b < 0) ? 0 - q : q);
}
