/*
 * esp8266_clock: the CPU clock and the PLL, and the flash cache with the
 * SPI0 read mode, of the paperbot ESP8266 board: what the chip does before
 * the firmware has set it up.
 *
 * Clock: the CPU (CCOUNT) and the peripherals the board models (UART0,
 * FRC1, the watchdog) run from 52 MHz, twice the NodeMCU's 26 MHz crystal,
 * from power-on and after every reset, until the firmware writes the PLL
 * through RTC control's internal-I2C register (0x60000D10: block 0x67,
 * address 1 then 2, the values for a 26 MHz crystal, 0x88 and 0x91, as
 * esp8266-hal's ESP8266Reset does); from then on 80 MHz. So the ROM's
 * UART divider (for 115200 baud at 80 MHz) gives 74880 baud, as on the
 * chip (Espressif: "ESP8266 outputs boot messages through UART0 with a
 * baud rate of 74880"). Values for another crystal leave the clock at
 * 52 MHz, logged.
 *
 * Flash cache: 0x40200000.. reads the flash only while DPORT SPI_CACHE
 * (0x3FF0000C) bit 8 is set (esp8266-hal's cache_enable; the SDK's
 * Cache_Read_Enable) and SPI0 CTRL (0x60000208) selects a read mode the
 * board's flash chip answers (flash-mode=, default dio: dio, dout and the
 * slow single-line read). Otherwise a read there is refused: with the
 * cache off, an error the CPU takes as an exception (instruction or
 * load/store PIF address error), logged; in a mode the flash does not
 * answer, all ones (what a flash that does not drive the extra lines
 * gives), logged.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/error-report.h"
#include "hw/clock.h"
#include "esp8266.h"

/* ---- the CPU clock and the PLL -------------------------------------------- */

#define RTC_CNTL_PLL        0x10
#define PLL_I2C_BLOCK       0x67
#define PLL_WRITE           (1u << 24)
/* esp8266-hal rtccntl.rs: CRYSTAL_26MHZ = (0x88, 0x91) at addresses 1, 2 */
#define PLL_26MHZ_ADDR1     0x88
#define PLL_26MHZ_ADDR2     0x91

/* CCOUNT keeps counting from where it is: QEMU's lx106 derives it from the
 * virtual clock through the CPU's Clock (target/xtensa/op_helper.c), so
 * the count so far is folded into its base before the rate changes. */
static void set_cpu_hz(Esp8266State *s, uint32_t hz)
{
    CPUXtensaState *env = &s->cpu->env;
    int64_t now = now_ns();

    if (hz == s->cpu_hz) {
        return;
    }
    env->ccount_base += (uint32_t)clock_ns_to_ticks(s->cpu->clock,
                                                    now - env->time_base);
    env->time_base = now;
    s->cpu_hz = hz;
    clock_update_hz(s->cpu_clk, hz);
    log_event(s, "cpu-clock %u", hz);
}

static void pll_write(Esp8266State *s, uint32_t v)
{
    unsigned block = v & 0xff, addr = (v >> 8) & 0xff, data = (v >> 16) & 0xff;

    if (!(v & PLL_WRITE) || block != PLL_I2C_BLOCK || (addr != 1 && addr != 2)) {
        return;
    }
    if (data == (addr == 1 ? PLL_26MHZ_ADDR1 : PLL_26MHZ_ADDR2)) {
        s->pll_writes |= 1u << (addr - 1);
    } else {
        s->pll_writes &= ~(1u << (addr - 1));
        error_report("esp8266: PLL address %u <- 0x%02x: not the value for "
                     "the board's 26 MHz crystal; the CPU stays at 52 MHz",
                     addr, data);
    }
    if (s->pll_writes == 3) {
        set_cpu_hz(s, CPU_HZ_PLL);
    }
}

static uint64_t rtc_cntl_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;
    /* the PLL's I2C write completes at once: busy (bit 25) reads 0 */
    return regfile_read(&s->rtc_cntl, addr);
}

static void rtc_cntl_write(void *opaque, hwaddr addr, uint64_t v,
                           unsigned size)
{
    Esp8266State *s = opaque;

    regfile_write(&s->rtc_cntl, addr, v);
    if (addr == RTC_CNTL_PLL) {
        pll_write(s, v);
    }
}

const MemoryRegionOps rtc_cntl_ops = {
    .read = rtc_cntl_read,
    .write = rtc_cntl_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* At every reset: the crystal's clock again, the PLL unset. */
void clock_reset(Esp8266State *s)
{
    s->pll_writes = 0;
    set_cpu_hz(s, CPU_HZ_RESET);
}

/* ---- the flash cache and the read mode ------------------------------------ */

#define SPI0_CTRL           0x08
#define SPI_CTRL_DOUT       (1u << 14)
#define SPI_CTRL_QOUT       (1u << 20)
#define SPI_CTRL_DIO        (1u << 23)
#define SPI_CTRL_QIO        (1u << 24)

static const char *const mode_names[] = {
    [FLASH_QIO] = "qio", [FLASH_QOUT] = "qout", [FLASH_DIO] = "dio",
    [FLASH_DOUT] = "dout", [FLASH_SLOW] = "slow",
};

bool parse_flash_mode(const char *name, FlashMode *mode)
{
    for (unsigned m = FLASH_QIO; m <= FLASH_DOUT; m++) {
        if (!strcmp(name, mode_names[m])) {
            *mode = m;
            return true;
        }
    }
    return false;
}

static FlashMode spi0_mode(Esp8266State *s)
{
    uint32_t ctrl = s->spi0.regs[SPI0_CTRL / 4];

    return ctrl & SPI_CTRL_QIO ? FLASH_QIO : ctrl & SPI_CTRL_QOUT ? FLASH_QOUT
         : ctrl & SPI_CTRL_DIO ? FLASH_DIO : ctrl & SPI_CTRL_DOUT ? FLASH_DOUT
         : FLASH_SLOW;
}

/* The modes in the enum's order, fastest first: a flash answers its best
 * mode and every slower one (a quad flash all, a dio one dio, dout and the
 * slow read, a dout one dout and the slow read). */
static bool flash_answers(Esp8266State *s, FlashMode m)
{
    return m >= s->flash_best;
}

/* After a write to DPORT or SPI0 (their register files' hook) and at reset:
 * the window mapped or not. */
void flash_update_map(void *opaque)
{
    Esp8266State *s = opaque;
    bool cache_on = s->dport.regs[DPORT_SPI_CACHE / 4] & SPI_CACHE_ENABLE;
    FlashMode mode = spi0_mode(s);
    bool readable = cache_on && flash_answers(s, mode);

    if (cache_on && !flash_answers(s, mode)) {
        log_event(s, "flash-mode-refused %s", mode_names[mode]);
        error_report("esp8266: the flash is read in %s mode, which this "
                     "board's flash (flash-mode=%s) does not answer: reads "
                     "give all ones", mode_names[mode],
                     mode_names[s->flash_best]);
    }
    if (readable != s->flash_readable) {
        s->flash_readable = readable;
        memory_region_set_enabled(&s->flash_mr, readable);
    }
}

/* Under the flash window, for when it is not readable. */
static MemTxResult flash_off_read(void *opaque, hwaddr addr, uint64_t *data,
                                  unsigned size, MemTxAttrs attrs)
{
    Esp8266State *s = opaque;

    if (s->dport.regs[DPORT_SPI_CACHE / 4] & SPI_CACHE_ENABLE) {
        *data = ~0ull;      /* a mode the flash does not answer */
        return MEMTX_OK;
    }
    if (!s->flash_off_logged) {
        s->flash_off_logged = true;
        log_event(s, "flash-cache-off 0x%08" PRIx64, FLASH_MAP_BASE + addr);
        error_report("esp8266: read of 0x%08" PRIx64 " (flash) with the "
                     "flash cache off (DPORT SPI_CACHE bit 8 clear): the "
                     "CPU takes an exception", FLASH_MAP_BASE + addr);
    }
    return MEMTX_ERROR;
}

static MemTxResult flash_off_write(void *opaque, hwaddr addr, uint64_t data,
                                   unsigned size, MemTxAttrs attrs)
{
    return MEMTX_OK;    /* the window is read-only: ignored, as before */
}

const MemoryRegionOps flash_off_ops = {
    .read_with_attrs = flash_off_read,
    .write_with_attrs = flash_off_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .valid = { .min_access_size = 1, .max_access_size = 4 },
};
