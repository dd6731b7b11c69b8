/*
 * esp8266_wdt: the watchdog (0x60000900) of the paperbot ESP8266 board.
 *
 * Not in the ESP8266 Technical Reference: register offsets from the esp8266
 * PAC's SVD, stage lengths from esp8266-hal's StageTimeout (0.84 s *
 * 2^(n - 10) at 80 MHz). When the last stage runs out the chip resets
 * (esp8266_reset: peripherals to their reset state, CPU to the ROM).
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/error-report.h"
#include "esp8266.h"

enum {
    WDT_CTL = 0x00, WDT_OP = 0x04, WDT_OP_ND = 0x08, WDT_STAGE = 0x10,
    WDT_RST = 0x14,
};
#define WDT_CTL_ENABLE          (1u << 0)
#define WDT_CTL_NO_RESET        (1u << 1)   /* two-stage: never reset */
#define WDT_CTL_STAGE1_DISABLE  (1u << 2)
#define WDT_FEED_MAGIC          0x73

/* Stage n lasts 2^(n + 16) cycles: 0.84 s for n = 10 (esp8266-hal). */
static int64_t wdt_stage_ns(Esp8266State *s, uint32_t n)
{
    n = MIN(MAX(n & 0xf, 1u), 15u);
    return cycles_to_ns(s, 1ULL << (n + 16));
}

static void wdt_start_stage(Esp8266State *s, unsigned stage)
{
    s->wdt_stage = stage;
    timer_mod(s->wdt_timer, now_ns() +
              wdt_stage_ns(s, stage == 0 ? s->wdt_op : s->wdt_op_nd));
}

/* The chip resets at the CPU's next instruction boundary: the reset runs as
 * work on the vCPU thread. (A system reset request would wait for the main
 * loop, which under -icount sleep=off runs late in virtual time.) */
static void wdt_reset_chip(CPUState *cpu, run_on_cpu_data data)
{
    Esp8266State *s = data.host_ptr;

    s->reset_cause = RST_CAUSE_WATCHDOG;
    esp8266_reset(s);
}

void wdt_expired(void *opaque)
{
    Esp8266State *s = opaque;

    if (s->wdt_stage == 0 && !(s->wdt_ctl & WDT_CTL_STAGE1_DISABLE)) {
        wdt_start_stage(s, 1);
        return;
    }
    if (s->wdt_ctl & WDT_CTL_NO_RESET) {
        return;
    }
    log_event(s, "reset watchdog");
    error_report("esp8266: watchdog reset at %.6f s (virtual): the firmware "
                 "stopped feeding it", now_ns() / 1e9);
    async_run_on_cpu(CPU(s->cpu), wdt_reset_chip, RUN_ON_CPU_HOST_PTR(s));
}

static uint64_t wdt_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case WDT_CTL:
        return s->wdt_ctl;
    case WDT_OP:
        return s->wdt_op;
    case WDT_OP_ND:
        return s->wdt_op_nd;
    case WDT_STAGE:
        return s->wdt_stage;
    default:
        return regfile_read(&s->periph, WDT_OFFSET + addr);
    }
}

static void wdt_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;
    bool was_enabled = s->wdt_ctl & WDT_CTL_ENABLE;

    switch (addr) {
    case WDT_CTL:
        s->wdt_ctl = v;
        if (!(v & WDT_CTL_ENABLE)) {
            timer_del(s->wdt_timer);
        } else if (!was_enabled) {
            wdt_start_stage(s, 0);
        }
        break;
    case WDT_OP:
        s->wdt_op = v;
        break;
    case WDT_OP_ND:
        s->wdt_op_nd = v;
        break;
    case WDT_RST:   /* feeding: back to the start of stage 0 */
        if (v == WDT_FEED_MAGIC && was_enabled) {
            wdt_start_stage(s, 0);
        }
        break;
    default:
        regfile_write(&s->periph, WDT_OFFSET + addr, v);
    }
}

const MemoryRegionOps wdt_ops = {
    .read = wdt_read,
    .write = wdt_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

void wdt_reset(Esp8266State *s)
{
    s->wdt_ctl = s->wdt_op = s->wdt_op_nd = 0;
    s->wdt_stage = 0;
    timer_del(s->wdt_timer);
}
