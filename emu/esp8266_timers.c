/*
 * esp8266_timers: FRC1 (0x60000600) of the paperbot ESP8266 board.
 *
 * From the ESP8266 Technical Reference (TRM), timer registers: a 23-bit down
 * counter at 80 MHz / 1, 16 or 256, auto-reload, edge or level interrupt on
 * CPU interrupt 9 (edge needs DPORT EDGE_INT_ENABLE bit 1, 0x3FF00004).
 * FRC2 is not modelled: its registers are plain storage.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "hw/irq.h"
#include "esp8266.h"

enum { FRC1_LOAD = 0x00, FRC1_COUNT = 0x04, FRC1_CTRL = 0x08, FRC1_INT = 0x0c };
#define FRC1_CTRL_LEVEL_INT     (1u << 0)   /* 0: edge, 1: level */
#define FRC1_CTRL_DIV(v)        (((v) >> 2) & 3)
#define FRC1_CTRL_AUTOLOAD      (1u << 6)
#define FRC1_CTRL_ENABLE        (1u << 7)
#define FRC1_CTRL_INT_STATUS    (1u << 8)   /* read only */
#define FRC1_INT_CLR            (1u << 0)
#define FRC1_COUNT_MASK         0x7fffffu

static unsigned frc1_prescaler(Esp8266State *s)
{
    static const unsigned div[4] = { 1, 16, 256, 256 };
    return div[FRC1_CTRL_DIV(s->frc1_ctrl)];
}

static int64_t frc1_ticks_to_ns(Esp8266State *s, uint64_t ticks)
{
    return cycles_to_ns(s, ticks * frc1_prescaler(s));
}

static uint32_t frc1_count(Esp8266State *s)
{
    uint64_t ticks;

    if (!(s->frc1_ctrl & FRC1_CTRL_ENABLE)) {
        return s->frc1_count_at_start;
    }
    ticks = muldiv64(now_ns() - s->frc1_start_ns, s->cpu_hz,
                     NANOSECONDS_PER_SECOND) / frc1_prescaler(s);
    return (s->frc1_count_at_start - (uint32_t)ticks) & FRC1_COUNT_MASK;
}

/* (Re)start counting down from `count`; the alarm fires at zero. */
static void frc1_start(Esp8266State *s, uint32_t count)
{
    s->frc1_count_at_start = count & FRC1_COUNT_MASK;
    s->frc1_start_ns = now_ns();
    if (s->frc1_ctrl & FRC1_CTRL_ENABLE) {
        timer_mod(s->frc1_timer, s->frc1_start_ns +
                  frc1_ticks_to_ns(s, s->frc1_count_at_start));
    } else {
        timer_del(s->frc1_timer);
    }
}

/* Level interrupts follow the status bit; edge ones pulse once, and only
 * while DPORT lets FRC1's edge through. */
static void frc1_raise(Esp8266State *s)
{
    s->frc1_int_pending = true;
    if (s->frc1_ctrl & FRC1_CTRL_LEVEL_INT) {
        qemu_irq_raise(s->frc1_irq);
    } else if (s->dport.regs[DPORT_EDGE_INT_ENABLE / 4] & EDGE_INT_FRC1) {
        qemu_irq_pulse(s->frc1_irq);
    }
}

void frc1_expired(void *opaque)
{
    Esp8266State *s = opaque;

    frc1_raise(s);
    /* at zero the counter reloads (autoload) or wraps around */
    frc1_start(s, s->frc1_ctrl & FRC1_CTRL_AUTOLOAD ? s->frc1_load
                                                   : FRC1_COUNT_MASK);
}

static uint64_t frc1_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case FRC1_LOAD:
        return s->frc1_load;
    case FRC1_COUNT:
        return frc1_count(s);
    case FRC1_CTRL:
        return s->frc1_ctrl | (s->frc1_int_pending ? FRC1_CTRL_INT_STATUS : 0);
    default:
        return 0;
    }
}

static void frc1_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;
    uint32_t count;

    switch (addr) {
    case FRC1_LOAD:     /* loading restarts the count from the new value */
        s->frc1_load = v & FRC1_COUNT_MASK;
        frc1_start(s, s->frc1_load);
        break;
    case FRC1_CTRL:
        count = frc1_count(s);
        s->frc1_ctrl = v & 0xff;
        frc1_start(s, count);
        break;
    case FRC1_INT:
        if (v & FRC1_INT_CLR) {
            s->frc1_int_pending = false;
            qemu_irq_lower(s->frc1_irq);
        }
        break;
    }
}

/* The timer block is 0x40 long; FRC2 (0x20..) is not modelled. */
static uint64_t timer_block_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;
    return addr < 0x10 ? frc1_read(s, addr, size)
                       : regfile_read(&s->periph, FRC1_OFFSET + addr);
}

static void timer_block_write(void *opaque, hwaddr addr, uint64_t v,
                              unsigned size)
{
    Esp8266State *s = opaque;

    if (addr < 0x10) {
        frc1_write(s, addr, v, size);
    } else {
        regfile_write(&s->periph, FRC1_OFFSET + addr, v);
    }
}

const MemoryRegionOps timer_block_ops = {
    .read = timer_block_read,
    .write = timer_block_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

void frc1_reset(Esp8266State *s)
{
    s->frc1_load = s->frc1_ctrl = s->frc1_count_at_start = 0;
    s->frc1_int_pending = false;
    timer_del(s->frc1_timer);
    qemu_irq_lower(s->frc1_irq);
}
