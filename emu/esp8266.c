/*
 * esp8266: the paperbot project's ESP8266 board for QEMU (lx106 core).
 *
 * Boots an ESP8266 flash image through the board's own ROM (emu/rom/): the
 * ROM copies the boot image's segments from flash to IRAM/DRAM and calls
 * the entry, as the chip's loader does. What the board models, and where it
 * comes from (see emu/README.md for what it does not model):
 *
 *   memory map            ESP8266 Technical Reference (TRM), memory map:
 *                         DRAM 0x3FFE8000, IRAM 0x40100000, mask ROM
 *                         0x40000000, flash read through the cache at
 *                         0x40200000 (first MiB), RTC memory 0x60001000
 *   UART0 (0x60000000)    TRM, UART registers: FIFO, INT_RAW/ST/ENA/CLR,
 *                         CLKDIV, STATUS, CONF0/1; bytes leave and arrive
 *                         at the baud rate of CLKDIV and CONF0's frame
 *   GPIO  (0x60000300)    TRM, GPIO registers: OUT, ENABLE, their W1TS/W1TC,
 *                         IN, PINn (PAD_DRIVER: open drain)
 *   GPIO16                RTC_GPIO_OUT/ENABLE/IN_DATA (RTC block 0x60000700;
 *                         not in the TRM: the esp8266 PAC's SVD and
 *                         Espressif's SDK gpio16 driver give the offsets)
 *   FRC1  (0x60000600)    TRM, timer registers: 23-bit down counter at
 *                         80 MHz / 1, 16 or 256, auto-reload, edge or level
 *                         interrupt on CPU interrupt 9 (edge needs DPORT
 *                         EDGE_INT_ENABLE bit 1, 0x3FF00004)
 *   WDT   (0x60000900)    not in the TRM: register offsets from the esp8266
 *                         PAC's SVD, stage lengths from esp8266-hal's
 *                         StageTimeout (0.84 s * 2^(n - 10) at 80 MHz)
 *   DPORT, IO_MUX, RTC, RTC control: plain registers, accepted quietly
 *   everything else in 0x60000000..0x60001000: plain registers, each first
 *   access logged under `-d unimp`.
 *
 * Machine options (-M esp8266,...):
 *   rom=FILE          the ROM (ELF, built by emu/build-qemu.sh)
 *   flash=FILE        raw flash contents (boot image at offset 0)
 *   events=FILE       "<virtual ns> <event>" lines: GPIO edges, UART input
 *                     lines fed, resets
 *   uart-input=FILE   bytes fed to UART0 RX at the baud rate, a line at a
 *                     time, input-gap-ms apart, starting input-gap-ms after
 *                     UART0 TX has sent the text uart-input-after (or at
 *                     once when that is empty)
 *   stop-ms=N         quit (exit status 0) after N virtual milliseconds
 *   sim=PATH          the simulator's Unix socket (esp8266_link.h): the
 *                     I2C slaves on GPIO14/12, XSHUT on GPIO0/2, the servo
 *                     pins GPIO5/4 and UART0 wired to the simulated robot
 *   profile=FILE      at stop-ms, the CPU's PC sampled every profile-ns
 *                     virtual ns (with sim=, from when the simulator says
 *                     the firmware's loop runs): "<pc> <a0> <samples>"
 *                     lines (hex, hex, decimal)
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/units.h"
#include "qemu/log.h"
#include "qemu/timer.h"
#include "qemu/error-report.h"
#include "qapi/error.h"
#include "qapi/visitor.h"
#include "cpu.h"
#include "sysemu/reset.h"
#include "sysemu/runstate.h"
#include "sysemu/sysemu.h"
#include "hw/boards.h"
#include "hw/loader.h"
#include "hw/clock.h"
#include "hw/irq.h"
#include "elf.h"
#include "exec/memory.h"
#include "exec/address-spaces.h"
#include "chardev/char-fe.h"
#include "qom/object.h"
#include "esp8266_link.h"

#define TYPE_ESP8266_MACHINE MACHINE_TYPE_NAME("esp8266")
OBJECT_DECLARE_SIMPLE_TYPE(Esp8266State, ESP8266_MACHINE)

/* The clock the HAL sets up; CCOUNT, FRC1 and the UART run from it. */
#define CPU_HZ            80000000ULL

/* Memory map (TRM, memory map). */
#define DRAM_BASE         0x3ffe8000u
#define DRAM_SIZE         0x18000u       /* 96 KiB, up to 0x40000000 */
#define ROM_BASE          0x40000000u
#define ROM_SIZE          (64 * KiB)
#define IRAM_BASE         0x40100000u
#define IRAM_SIZE         (32 * KiB)
#define FLASH_MAP_BASE    0x40200000u
#define FLASH_MAP_SIZE    (1 * MiB)
#define FLASH_MAX_SIZE    (16 * MiB)
#define DPORT_BASE        0x3ff00000u
#define DPORT_SIZE        0x100u
#define PERIPH_BASE       0x60000000u
#define PERIPH_SIZE       0x1000u
#define RTC_MEM_BASE      0x60001000u
#define RTC_MEM_SIZE      (1 * KiB)

/* Peripheral blocks, offsets from PERIPH_BASE (TRM / PAC). */
#define UART0_OFFSET      0x000
#define GPIO_OFFSET       0x300
#define FRC1_OFFSET       0x600
#define RTC_OFFSET        0x700
#define IO_MUX_OFFSET     0x800
#define WDT_OFFSET        0x900
#define RTC_CNTL_OFFSET   0xd00

/* CPU interrupt of FRC1 (core-isa.h: interrupt 9 is external, edge). */
#define FRC1_CPU_IRQ      9
/* DPORT EDGE_INT_ENABLE: bit 1 lets FRC1's edge interrupt through. */
#define DPORT_EDGE_INT_ENABLE   0x04
#define EDGE_INT_FRC1           (1u << 1)

#define NUM_GPIO          16      /* GPIO0..15; GPIO16 is the RTC's */
#define UART_FIFO_LEN     128

/* ---- register files: the blocks we accept without modelling ------------ */

typedef struct RegFile {
    const char *name;
    hwaddr base;
    unsigned size;
    bool log_unimp;         /* log each register's first read and write */
    uint32_t *regs;
    uint8_t *logged;        /* bit 0: read logged, bit 1: write logged */
} RegFile;

typedef struct Fifo {
    uint8_t data[UART_FIFO_LEN];
    unsigned head, count;
} Fifo;

struct Esp8266State {
    MachineState parent;

    XtensaCPU *cpu;
    char *rom_path, *flash_path, *events_path;
    char *input_path, *input_after;
    uint32_t input_gap_ms, stop_ms;
    FILE *events;
    QEMUTimer *stop_timer;
    bool stopped;               /* past stop-ms: nothing more leaves the board */

    MemoryRegion flash_mr, dport_mr, periph_mr, uart_mr, gpio_mr, rtc_mr,
                 frc1_mr, wdt_mr;
    RegFile dport, periph, rtc, io_mux, rtc_cntl;

    /* UART0 */
    CharBackend chr;
    Fifo tx, rx;
    uint32_t uart_int_raw, uart_int_ena, uart_clkdiv, uart_conf0, uart_conf1;
    QEMUTimer *tx_timer;
    /* deterministic input (uart-input) */
    uint8_t *input;
    size_t input_len, input_pos;
    size_t after_matched;       /* bytes of input_after matched so far */
    bool input_started;
    QEMUTimer *input_timer;

    /* GPIO */
    uint32_t gpio_out, gpio_enable, gpio_pin[NUM_GPIO];
    uint32_t gpio_levels;       /* GPIO0..15, bit 16 = GPIO16 */
    uint32_t rtc_gpio_out, rtc_gpio_enable;

    /* the simulator (sim=PATH): see "the wire to the simulator" below */
    char *sim_path;
    Esp8266Link *link;
    uint32_t driven;            /* levels the chip drives, before the slaves */
    uint32_t ext_low;           /* pins a slave pulls low */
    bool link_dirty;            /* an edge the slaves may answer since the last sync */
    int64_t link_valid_until;
    QEMUTimer *link_wake_timer, *link_rx_timer;
    Fifo link_rx;               /* bytes for UART0 RX, one per frame time */

    /* PC sampling (profile=FILE) */
    char *profile_path;
    uint32_t profile_ns;
    uint64_t profile_samples;
    int64_t profile_start_ns;   /* with sim=: from the loop's start */
    GHashTable *profile;
    QEMUTimer *profile_timer;

    /* FRC1 */
    uint32_t frc1_load, frc1_ctrl, frc1_count_at_start;
    bool frc1_int_pending;
    int64_t frc1_start_ns;
    QEMUTimer *frc1_timer;
    qemu_irq frc1_irq;

    /* watchdog */
    uint32_t wdt_ctl, wdt_op, wdt_op_nd;
    unsigned wdt_stage;
    QEMUTimer *wdt_timer;
};

static int64_t now_ns(void)
{
    return qemu_clock_get_ns(QEMU_CLOCK_VIRTUAL);
}

static int64_t cycles_to_ns(uint64_t cycles)
{
    return muldiv64(cycles, NANOSECONDS_PER_SECOND, CPU_HZ);
}

static void log_event(Esp8266State *s, const char *fmt, ...) G_GNUC_PRINTF(2, 3);

static void log_event(Esp8266State *s, const char *fmt, ...)
{
    va_list ap;

    if (!s->events || s->stopped) {
        return;
    }
    fprintf(s->events, "%" PRId64 " ", now_ns());
    va_start(ap, fmt);
    vfprintf(s->events, fmt, ap);
    va_end(ap);
    fputc('\n', s->events);
}

static void regfile_init(RegFile *f, const char *name, hwaddr base,
                         unsigned size, bool log_unimp)
{
    f->name = name;
    f->base = base;
    f->size = size;
    f->log_unimp = log_unimp;
    f->regs = g_new0(uint32_t, size / 4);
    f->logged = g_new0(uint8_t, size / 4);
}

static uint32_t regfile_read(RegFile *f, hwaddr addr)
{
    unsigned w = addr / 4;

    if (f->log_unimp && !(f->logged[w] & 1)) {
        f->logged[w] |= 1;
        qemu_log_mask(LOG_UNIMP, "esp8266: %s: read of unmodelled register "
                      "0x%08" HWADDR_PRIx " (returns 0x%08x; further reads "
                      "not logged)\n", f->name, f->base + addr, f->regs[w]);
    }
    return f->regs[w];
}

static void regfile_write(RegFile *f, hwaddr addr, uint32_t v)
{
    unsigned w = addr / 4;

    if (f->log_unimp && !(f->logged[w] & 2)) {
        f->logged[w] |= 2;
        qemu_log_mask(LOG_UNIMP, "esp8266: %s: write of unmodelled register "
                      "0x%08" HWADDR_PRIx " <- 0x%08x (further writes not "
                      "logged)\n", f->name, f->base + addr, v);
    }
    f->regs[w] = v;
}

static uint64_t regfile_io_read(void *opaque, hwaddr addr, unsigned size)
{
    return regfile_read(opaque, addr);
}

static void regfile_io_write(void *opaque, hwaddr addr, uint64_t v,
                             unsigned size)
{
    regfile_write(opaque, addr, v);
}

/* Peripheral registers are 32-bit; narrower accesses are widened by QEMU. */
static const MemoryRegionOps regfile_ops = {
    .read = regfile_io_read,
    .write = regfile_io_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* ---- UART0 (TRM, UART) ----------------------------------------------------- */

enum {
    UART_FIFO = 0x00, UART_INT_RAW = 0x04, UART_INT_ST = 0x08,
    UART_INT_ENA = 0x0c, UART_INT_CLR = 0x10, UART_CLKDIV = 0x14,
    UART_STATUS = 0x1c, UART_CONF0 = 0x20, UART_CONF1 = 0x24,
};
#define UART_INT_RXFIFO_FULL    (1u << 0)
#define UART_INT_TXFIFO_EMPTY   (1u << 1)
#define UART_INT_RXFIFO_OVF     (1u << 4)
#define UART_STATUS_RXD         (1u << 15)      /* line levels: idle high */
#define UART_STATUS_TXD         (1u << 31)
#define UART_CONF0_RESET        0x1c            /* 8 data bits, 1 stop bit */
#define UART_CONF1_RESET        0x6060          /* rx full 96, tx empty 96 */
#define UART_CLKDIV_RESET       (CPU_HZ / 115200)

static bool fifo_push(Fifo *f, uint8_t b)
{
    if (f->count == UART_FIFO_LEN) {
        return false;
    }
    f->data[(f->head + f->count) % UART_FIFO_LEN] = b;
    f->count++;
    return true;
}

static uint8_t fifo_pop(Fifo *f)
{
    uint8_t b = 0;

    if (f->count) {
        b = f->data[f->head];
        f->head = (f->head + 1) % UART_FIFO_LEN;
        f->count--;
    }
    return b;
}

/* One frame on the line: start bit, 5..8 data bits, parity, 1..2 stop bits
 * (CONF0: bit_num [3:2], parity_en [1], stop_bit_num [5:4]). */
static int64_t uart_frame_ns(Esp8266State *s)
{
    unsigned data_bits = 5 + ((s->uart_conf0 >> 2) & 3);
    unsigned parity = (s->uart_conf0 >> 1) & 1;
    unsigned stop_half_bits = (s->uart_conf0 >> 4) & 3 ? ((s->uart_conf0 >> 4) & 3) + 1 : 2;
    uint64_t half_bits = 2 * (1 + data_bits + parity) + stop_half_bits;
    uint32_t div = s->uart_clkdiv & 0xfffff;

    return cycles_to_ns(half_bits * MAX(div, 1u) / 2);
}

/* RXFIFO_FULL and TXFIFO_EMPTY follow the fill levels against CONF1's
 * thresholds; they are levels, not latched. */
static void uart_update_levels(Esp8266State *s)
{
    unsigned rx_full = s->uart_conf1 & 0x7f;
    unsigned tx_empty = (s->uart_conf1 >> 8) & 0x7f;

    s->uart_int_raw &= ~(UART_INT_RXFIFO_FULL | UART_INT_TXFIFO_EMPTY);
    if (s->rx.count >= rx_full) {
        s->uart_int_raw |= UART_INT_RXFIFO_FULL;
    }
    if (s->tx.count < tx_empty) {
        s->uart_int_raw |= UART_INT_TXFIFO_EMPTY;
    }
}

static void uart_receive_byte(Esp8266State *s, uint8_t b)
{
    if (!fifo_push(&s->rx, b)) {
        s->uart_int_raw |= UART_INT_RXFIFO_OVF;
        qemu_log_mask(LOG_GUEST_ERROR, "esp8266: UART0 RX FIFO overflow\n");
    }
    uart_update_levels(s);
}

static void input_schedule(Esp8266State *s, int64_t delay_ns)
{
    if (s->input_pos < s->input_len) {
        timer_mod(s->input_timer, now_ns() + delay_ns);
    }
}

/* The text uart-input-after, matched on the bytes UART0 has sent. */
static void input_watch_tx(Esp8266State *s, uint8_t b)
{
    const char *after = s->input_after;

    if (s->input_started || !s->input) {
        return;
    }
    if (b == (uint8_t)after[s->after_matched]) {
        s->after_matched++;
    } else {
        s->after_matched = b == (uint8_t)after[0];
    }
    if (!after[s->after_matched]) {
        s->input_started = true;
        input_schedule(s, (int64_t)s->input_gap_ms * SCALE_MS);
    }
}

/* One byte of uart-input per frame time; a line gap after each newline. */
static void input_tick(void *opaque)
{
    Esp8266State *s = opaque;
    uint8_t b = s->input[s->input_pos];

    if (s->input_pos == 0 || s->input[s->input_pos - 1] == '\n') {
        const uint8_t *end = memchr(s->input + s->input_pos, '\n',
                                    s->input_len - s->input_pos);
        size_t len = end ? (size_t)(end - s->input - s->input_pos)
                         : s->input_len - s->input_pos;
        log_event(s, "uart0-rx %.*s", (int)len, s->input + s->input_pos);
    }
    s->input_pos++;
    uart_receive_byte(s, b);
    input_schedule(s, b == '\n' ? (int64_t)s->input_gap_ms * SCALE_MS
                                : uart_frame_ns(s));
}

/* The byte at the head of the TX FIFO has been shifted out. */
static void uart_tx_done(void *opaque)
{
    Esp8266State *s = opaque;
    uint8_t b = fifo_pop(&s->tx);

    if (!s->stopped) {
        qemu_chr_fe_write_all(&s->chr, &b, 1);
        if (s->link) {
            esp8266_link_event(s->link, now_ns(), LINK_UART_TX, b);
        }
    }
    input_watch_tx(s, b);
    if (s->tx.count) {
        timer_mod(s->tx_timer, now_ns() + uart_frame_ns(s));
    }
    uart_update_levels(s);
}

static void uart_transmit(Esp8266State *s, uint8_t b)
{
    if (!fifo_push(&s->tx, b)) {
        qemu_log_mask(LOG_GUEST_ERROR, "esp8266: UART0 TX FIFO full, byte "
                      "0x%02x lost\n", b);
        return;
    }
    if (!timer_pending(s->tx_timer)) {
        timer_mod(s->tx_timer, now_ns() + uart_frame_ns(s));
    }
    uart_update_levels(s);
}

static uint64_t uart_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;
    uint32_t v;

    switch (addr) {
    case UART_FIFO:
        v = fifo_pop(&s->rx);
        uart_update_levels(s);
        qemu_chr_fe_accept_input(&s->chr);
        return v;
    case UART_INT_RAW:
        return s->uart_int_raw;
    case UART_INT_ST:
        return s->uart_int_raw & s->uart_int_ena;
    case UART_INT_ENA:
        return s->uart_int_ena;
    case UART_CLKDIV:
        return s->uart_clkdiv;
    case UART_STATUS:
        return (s->rx.count & 0xff) | ((s->tx.count & 0xff) << 16) |
               UART_STATUS_RXD | UART_STATUS_TXD;
    case UART_CONF0:
        return s->uart_conf0;
    case UART_CONF1:
        return s->uart_conf1;
    default:
        return regfile_read(&s->periph, UART0_OFFSET + addr);
    }
}

static void uart_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case UART_FIFO:
        uart_transmit(s, v & 0xff);
        break;
    case UART_INT_ENA:
        s->uart_int_ena = v;
        break;
    case UART_INT_CLR:
        s->uart_int_raw &= ~v;
        uart_update_levels(s);
        break;
    case UART_CLKDIV:
        s->uart_clkdiv = v & 0xfffff;
        break;
    case UART_CONF0:
        s->uart_conf0 = v;
        break;
    case UART_CONF1:
        s->uart_conf1 = v;
        uart_update_levels(s);
        break;
    default:
        regfile_write(&s->periph, UART0_OFFSET + addr, v);
    }
}

static const MemoryRegionOps uart_ops = {
    .read = uart_read,
    .write = uart_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* Host input (the chardev: a pty or stdio) goes straight into the RX FIFO. */
static int uart_can_receive(void *opaque)
{
    Esp8266State *s = opaque;
    return UART_FIFO_LEN - s->rx.count;
}

static void uart_receive(void *opaque, const uint8_t *buf, int size)
{
    Esp8266State *s = opaque;

    for (int i = 0; i < size; i++) {
        uart_receive_byte(s, buf[i]);
    }
}

static void uart_reset(Esp8266State *s)
{
    memset(&s->tx, 0, sizeof(s->tx));
    memset(&s->rx, 0, sizeof(s->rx));
    s->uart_int_raw = s->uart_int_ena = 0;
    s->uart_clkdiv = UART_CLKDIV_RESET;
    s->uart_conf0 = UART_CONF0_RESET;
    s->uart_conf1 = UART_CONF1_RESET;
    timer_del(s->tx_timer);
    uart_update_levels(s);
}

/* ---- GPIO (TRM, GPIO) and GPIO16 (RTC) -------------------------------------- */

enum {
    GPIO_OUT = 0x00, GPIO_OUT_W1TS = 0x04, GPIO_OUT_W1TC = 0x08,
    GPIO_ENABLE = 0x0c, GPIO_ENABLE_W1TS = 0x10, GPIO_ENABLE_W1TC = 0x14,
    GPIO_IN = 0x18, GPIO_PIN0 = 0x28,
};
#define GPIO_PIN_PAD_DRIVER     (1u << 2)   /* 1: open drain */
#define GPIO_PIN_INT_TYPE(v)    (((v) >> 7) & 7)
#define GPIO_MASK               0xffffu

enum {
    RTC_GPIO_OUT = 0x68, RTC_GPIO_ENABLE = 0x74, RTC_GPIO_IN_DATA = 0x8c,
};

/*
 * The level on each pin. Nothing outside drives the pins (no I2C devices on
 * the bus), so a pin is high unless the chip drives it low: an enabled
 * push-pull pin shows its output bit, an enabled open-drain pin is low
 * while its output bit is 0 and released (pulled up) otherwise, and an
 * input floats high (the board's and the pads' pull-ups). GPIO16 (bit 16)
 * is push-pull when enabled.
 */
static uint32_t gpio_driven_levels(Esp8266State *s)
{
    uint32_t levels = 0;

    for (int pin = 0; pin < NUM_GPIO; pin++) {
        bool enabled = (s->gpio_enable >> pin) & 1;
        bool out = (s->gpio_out >> pin) & 1;
        bool open_drain = s->gpio_pin[pin] & GPIO_PIN_PAD_DRIVER;
        bool driven_low = enabled && !out;
        bool driven_high = enabled && out && !open_drain;

        levels |= (uint32_t)(driven_high || !driven_low) << pin;
    }
    if (s->rtc_gpio_enable & 1) {
        levels |= (s->rtc_gpio_out & 1) << NUM_GPIO;
    } else {
        levels |= 1u << NUM_GPIO;
    }
    return levels;
}

/* With a simulator, its slaves can pull the I2C lines low too. */
static uint32_t gpio_compute_levels(Esp8266State *s)
{
    return gpio_driven_levels(s) & ~s->ext_low;
}

static void link_note_pins(Esp8266State *s, uint32_t driven);

/* Recompute the pin levels and log each change as an edge. */
static void gpio_update(Esp8266State *s)
{
    uint32_t levels, changed;

    if (s->link) {
        link_note_pins(s, gpio_driven_levels(s));
    }
    levels = gpio_compute_levels(s);
    changed = levels ^ s->gpio_levels;

    s->gpio_levels = levels;
    for (int pin = 0; changed && pin <= NUM_GPIO; pin++) {
        if ((changed >> pin) & 1) {
            log_event(s, "gpio%d %u", pin, (levels >> pin) & 1);
        }
    }
}

static void link_refresh(Esp8266State *s);

static uint64_t gpio_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case GPIO_OUT:
        return s->gpio_out;
    case GPIO_ENABLE:
        return s->gpio_enable;
    case GPIO_IN:   /* bits 16..31: strapping, read as 0 */
        link_refresh(s);
        return s->gpio_levels & GPIO_MASK;
    case GPIO_OUT_W1TS:
    case GPIO_OUT_W1TC:
    case GPIO_ENABLE_W1TS:
    case GPIO_ENABLE_W1TC:
        return 0;   /* write-only strobes */
    default:
        if (addr >= GPIO_PIN0 && addr < GPIO_PIN0 + 4 * NUM_GPIO) {
            return s->gpio_pin[(addr - GPIO_PIN0) / 4];
        }
        return regfile_read(&s->periph, GPIO_OFFSET + addr);
    }
}

static void gpio_write_pin_conf(Esp8266State *s, unsigned pin, uint32_t v)
{
    if (GPIO_PIN_INT_TYPE(v)) {
        qemu_log_mask(LOG_UNIMP, "esp8266: GPIO%u pin interrupts are not "
                      "modelled\n", pin);
    }
    s->gpio_pin[pin] = v;
}

static void gpio_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case GPIO_OUT:
        s->gpio_out = v & GPIO_MASK;
        break;
    case GPIO_OUT_W1TS:
        s->gpio_out |= v & GPIO_MASK;
        break;
    case GPIO_OUT_W1TC:
        s->gpio_out &= ~v;
        break;
    case GPIO_ENABLE:
        s->gpio_enable = v & GPIO_MASK;
        break;
    case GPIO_ENABLE_W1TS:
        s->gpio_enable |= v & GPIO_MASK;
        break;
    case GPIO_ENABLE_W1TC:
        s->gpio_enable &= ~v;
        break;
    default:
        if (addr >= GPIO_PIN0 && addr < GPIO_PIN0 + 4 * NUM_GPIO) {
            gpio_write_pin_conf(s, (addr - GPIO_PIN0) / 4, v);
        } else {
            regfile_write(&s->periph, GPIO_OFFSET + addr, v);
        }
        return;
    }
    gpio_update(s);
}

static const MemoryRegionOps gpio_ops = {
    .read = gpio_read,
    .write = gpio_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* The RTC block: GPIO16's registers modelled, the rest plain storage. */
static uint64_t rtc_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case RTC_GPIO_OUT:
        return s->rtc_gpio_out;
    case RTC_GPIO_ENABLE:
        return s->rtc_gpio_enable;
    case RTC_GPIO_IN_DATA:
        return (s->gpio_levels >> NUM_GPIO) & 1;
    default:
        return regfile_read(&s->rtc, addr);
    }
}

static void rtc_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case RTC_GPIO_OUT:
        s->rtc_gpio_out = v;
        gpio_update(s);
        break;
    case RTC_GPIO_ENABLE:
        s->rtc_gpio_enable = v;
        gpio_update(s);
        break;
    default:
        regfile_write(&s->rtc, addr, v);
    }
}

static const MemoryRegionOps rtc_ops = {
    .read = rtc_read,
    .write = rtc_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

static void gpio_reset(Esp8266State *s)
{
    s->gpio_out = s->gpio_enable = 0;
    memset(s->gpio_pin, 0, sizeof(s->gpio_pin));
    s->rtc_gpio_out = s->rtc_gpio_enable = 0;
    gpio_update(s);
}

/* ---- the wire to the simulator (sim=PATH, esp8266_link.h) ------------------------ */

#define SDA_GPIO        14
#define SCL_GPIO        12
/* The pins the simulated robot sees: XSHUT front/right, servos right/left,
 * SCL, SDA (config::pins). */
#define LINK_PINS_MASK  ((1u << 0) | (1u << 2) | (1u << 4) | (1u << 5) | \
                         (1u << SCL_GPIO) | (1u << SDA_GPIO))

/*
 * A slave's SDA changes only at SCL's falling edge, at a START or a STOP
 * (SDA moving while SCL is high), or when the simulator said so
 * (valid_until: an injected fault's window); no slave stretches SCL. So
 * GPIO_IN asks the simulator only after such an edge: a bit costs one
 * round trip, and the levels in between are known here.
 */
static void link_note_pins(Esp8266State *s, uint32_t driven)
{
    uint32_t changed = (driven ^ s->driven) & LINK_PINS_MASK;
    bool scl_was_high = (s->driven >> SCL_GPIO) & 1;
    bool scl_high = (driven >> SCL_GPIO) & 1;

    s->driven = driven;
    if (!changed || s->stopped) {
        return;
    }
    esp8266_link_event(s->link, now_ns(), LINK_PINS, driven & LINK_PINS_MASK);
    if ((scl_was_high && !scl_high) ||
        (scl_high && ((changed >> SDA_GPIO) & 1))) {
        s->link_dirty = true;
    }
}

static void link_rx_tick(void *opaque)
{
    Esp8266State *s = opaque;

    uart_receive_byte(s, fifo_pop(&s->link_rx));
    if (s->link_rx.count) {
        timer_mod(s->link_rx_timer, now_ns() + uart_frame_ns(s));
    }
}

static void stop_expired(void *opaque);

static void link_sync(Esp8266State *s)
{
    LinkAnswer a;

    if (s->stopped) {
        return;
    }
    esp8266_link_sync(s->link, now_ns(), &a);
    if (a.flags & LINK_STOP) {
        stop_expired(s);
        return;
    }
    if ((a.flags & LINK_LOOP) && s->profile && !s->profile_start_ns) {
        s->profile_start_ns = now_ns();
        timer_mod(s->profile_timer, now_ns() + s->profile_ns);
    }
    s->ext_low = a.flags & LINK_SDA_LOW ? 1u << SDA_GPIO : 0;
    s->link_valid_until = a.valid_until_ns;
    s->link_dirty = false;
    if (a.wake_at_ns < INT64_MAX) {
        timer_mod(s->link_wake_timer, MAX(a.wake_at_ns, now_ns() + 1));
    }
    for (uint32_t i = 0; i < a.rx_len; i++) {
        if (!fifo_push(&s->link_rx, a.rx[i])) {
            qemu_log_mask(LOG_GUEST_ERROR, "esp8266: simulator RX bytes lost\n");
        }
    }
    if (s->link_rx.count && !timer_pending(s->link_rx_timer)) {
        timer_mod(s->link_rx_timer, now_ns() + uart_frame_ns(s));
    }
    gpio_update(s);
}

static void link_refresh(Esp8266State *s)
{
    if (s->link && (s->link_dirty || now_ns() >= s->link_valid_until)) {
        link_sync(s);
    }
}

static void link_wake(void *opaque)
{
    link_sync(opaque);
}

static void link_start(Esp8266State *s)
{
    s->link = esp8266_link_connect(s->sim_path);
    s->link_wake_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, link_wake, s);
    s->link_rx_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, link_rx_tick, s);
    s->driven = gpio_driven_levels(s);
    esp8266_link_event(s->link, 0, LINK_PINS, s->driven & LINK_PINS_MASK);
    link_sync(s);
}

/* ---- PC sampling (profile=FILE) --------------------------------------------- */

/* The vCPU stops at an instruction boundary for a virtual timer under
 * -icount, so env.pc is the next instruction to run. */
static void profile_tick(void *opaque)
{
    Esp8266State *s = opaque;
    /* the PC and a0 (call0 ABI: in a leaf function, its return address) */
    uint64_t key = (uint64_t)s->cpu->env.pc << 32 | s->cpu->env.regs[0];
    uint64_t *n = g_hash_table_lookup(s->profile, &key);

    if (!n) {
        n = g_new0(uint64_t, 2);
        n[0] = key;
        g_hash_table_insert(s->profile, n, n);
    }
    n[1]++;
    s->profile_samples++;
    timer_mod(s->profile_timer, now_ns() + s->profile_ns);
}

static void profile_write(Esp8266State *s)
{
    GHashTableIter it;
    gpointer k, v;
    FILE *f = fopen(s->profile_path, "w");

    if (!f) {
        error_report("esp8266: profile=%s: %s", s->profile_path, strerror(errno));
        return;
    }
    fprintf(f, "# samples %" PRIu64 " every %u ns from %" PRId64 " to %"
            PRId64 " ns\n", s->profile_samples, s->profile_ns,
            s->profile_start_ns, now_ns());
    g_hash_table_iter_init(&it, s->profile);
    while (g_hash_table_iter_next(&it, &k, &v)) {
        const uint64_t *n = v;
        fprintf(f, "%08x %08x %" PRIu64 "\n", (uint32_t)(n[0] >> 32),
                (uint32_t)n[0], n[1]);
    }
    fclose(f);
}

/* ---- FRC1 (TRM, timer registers) --------------------------------------------- */

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
    return cycles_to_ns(ticks * frc1_prescaler(s));
}

static uint32_t frc1_count(Esp8266State *s)
{
    uint64_t ticks;

    if (!(s->frc1_ctrl & FRC1_CTRL_ENABLE)) {
        return s->frc1_count_at_start;
    }
    ticks = muldiv64(now_ns() - s->frc1_start_ns, CPU_HZ,
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

static void frc1_expired(void *opaque)
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

static const MemoryRegionOps timer_block_ops = {
    .read = timer_block_read,
    .write = timer_block_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

static void frc1_reset(Esp8266State *s)
{
    s->frc1_load = s->frc1_ctrl = s->frc1_count_at_start = 0;
    s->frc1_int_pending = false;
    timer_del(s->frc1_timer);
    qemu_irq_lower(s->frc1_irq);
}

/* ---- watchdog (PAC's WDT block; stage lengths from esp8266-hal) ------------- */

enum {
    WDT_CTL = 0x00, WDT_OP = 0x04, WDT_OP_ND = 0x08, WDT_STAGE = 0x10,
    WDT_RST = 0x14,
};
#define WDT_CTL_ENABLE          (1u << 0)
#define WDT_CTL_NO_RESET        (1u << 1)   /* two-stage: never reset */
#define WDT_CTL_STAGE1_DISABLE  (1u << 2)
#define WDT_FEED_MAGIC          0x73

/* Stage n lasts 2^(n + 16) cycles: 0.84 s for n = 10 (esp8266-hal). */
static int64_t wdt_stage_ns(uint32_t n)
{
    n = MIN(MAX(n & 0xf, 1u), 15u);
    return cycles_to_ns(1ULL << (n + 16));
}

static void wdt_start_stage(Esp8266State *s, unsigned stage)
{
    s->wdt_stage = stage;
    timer_mod(s->wdt_timer, now_ns() +
              wdt_stage_ns(stage == 0 ? s->wdt_op : s->wdt_op_nd));
}

static void esp8266_reset(void *opaque);

/* The chip resets at the CPU's next instruction boundary: the reset runs as
 * work on the vCPU thread. (A system reset request would wait for the main
 * loop, which under -icount sleep=off runs late in virtual time.) */
static void wdt_reset_chip(CPUState *cpu, run_on_cpu_data data)
{
    esp8266_reset(data.host_ptr);
}

static void wdt_expired(void *opaque)
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

static const MemoryRegionOps wdt_ops = {
    .read = wdt_read,
    .write = wdt_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

static void wdt_reset(Esp8266State *s)
{
    s->wdt_ctl = s->wdt_op = s->wdt_op_nd = 0;
    s->wdt_stage = 0;
    timer_del(s->wdt_timer);
}

/* ---- memory and images ---------------------------------------------------------- */

static void map_ram(const char *name, hwaddr base, uint64_t size)
{
    MemoryRegion *mr = g_new(MemoryRegion, 1);

    memory_region_init_ram(mr, NULL, name, size, &error_fatal);
    memory_region_add_subregion(get_system_memory(), base, mr);
}

static void map_rom(const char *name, hwaddr base, uint64_t size)
{
    MemoryRegion *mr = g_new(MemoryRegion, 1);

    memory_region_init_rom(mr, NULL, name, size, &error_fatal);
    memory_region_add_subregion(get_system_memory(), base, mr);
}

static void map_io(Esp8266State *s, MemoryRegion *mr, const MemoryRegionOps *ops,
                   void *opaque, const char *name, hwaddr base, uint64_t size)
{
    memory_region_init_io(mr, OBJECT(s), ops, opaque, name, size);
    memory_region_add_subregion_overlap(get_system_memory(), base, mr, 1);
}

/* A plain register block of its own, mapped over the catch-all. */
static void map_regfile(Esp8266State *s, RegFile *f, const char *name,
                        hwaddr base, unsigned size, bool log_unimp)
{
    MemoryRegion *mr = g_new(MemoryRegion, 1);

    regfile_init(f, name, base, size, log_unimp);
    map_io(s, mr, &regfile_ops, f, name, base, size);
}

/* The flash chip's contents, read through the cache window at 0x40200000
 * (the first MiB; the rest of the file is accepted and not mapped). */
static void load_flash(Esp8266State *s)
{
    g_autofree gchar *data = NULL;
    gsize len;
    GError *err = NULL;
    uint8_t *window;

    memory_region_init_rom(&s->flash_mr, OBJECT(s), "esp8266.flash",
                           FLASH_MAP_SIZE, &error_fatal);
    memory_region_add_subregion(get_system_memory(), FLASH_MAP_BASE,
                                &s->flash_mr);
    window = memory_region_get_ram_ptr(&s->flash_mr);
    memset(window, 0xff, FLASH_MAP_SIZE);   /* erased flash */
    if (!s->flash_path) {
        return;
    }
    if (!g_file_get_contents(s->flash_path, &data, &len, &err)) {
        error_report("esp8266: flash=%s: %s", s->flash_path, err->message);
        exit(1);
    }
    if (len > FLASH_MAX_SIZE) {
        error_report("esp8266: flash=%s is larger than 16 MiB", s->flash_path);
        exit(1);
    }
    memcpy(window, data, MIN(len, (gsize)FLASH_MAP_SIZE));
}

static uint64_t identity(void *opaque, uint64_t addr)
{
    return addr;
}

static void load_rom(Esp8266State *s)
{
    map_rom("esp8266.rom", ROM_BASE, ROM_SIZE);
    if (!s->rom_path) {
        error_report("esp8266: no ROM: give -M esp8266,rom=FILE "
                     "(emu/build-qemu.sh builds rom.elf)");
        exit(1);
    }
    if (load_elf(s->rom_path, NULL, identity, NULL, NULL, NULL, NULL, NULL,
                 0, EM_XTENSA, 0, 0) <= 0) {
        error_report("esp8266: cannot load the ROM %s", s->rom_path);
        exit(1);
    }
}

static void load_uart_input(Esp8266State *s)
{
    g_autofree gchar *data = NULL;
    gsize len;
    GError *err = NULL;

    if (!s->input_path) {
        return;
    }
    if (!g_file_get_contents(s->input_path, &data, &len, &err)) {
        error_report("esp8266: uart-input=%s: %s", s->input_path, err->message);
        exit(1);
    }
    s->input = g_steal_pointer(&data);
    s->input_len = len;
    if (!s->input_after) {
        s->input_after = g_strdup("");
    }
    if (!s->input_after[0]) {
        s->input_started = true;
        input_schedule(s, (int64_t)s->input_gap_ms * SCALE_MS);
    }
}

static FILE *open_events(const char *path)
{
    FILE *f = fopen(path, "w");

    if (!f) {
        error_report("esp8266: events=%s: %s", path, strerror(errno));
        exit(1);
    }
    setvbuf(f, NULL, _IOLBF, 0);
    return f;
}

/* The end of a timed run (stop-ms): QEMU exits with status 0. The main loop
 * acts on the request a little later; what the guest sends meanwhile is
 * dropped, so a run's output ends at exactly stop-ms. */
static void stop_expired(void *opaque)
{
    Esp8266State *s = opaque;

    log_event(s, "stop");
    if (s->profile) {
        profile_write(s);
    }
    if (s->link) {
        esp8266_link_end(s->link, now_ns());
    }
    s->stopped = true;
    qemu_system_shutdown_request(SHUTDOWN_CAUSE_HOST_QMP_QUIT);
}

/* ---- the machine ------------------------------------------------------------------- */

/* Power-on and every watchdog reset: the chip's peripherals to their reset
 * state, the CPU to the ROM's reset vector. RAM, RTC memory, the flash and
 * the host-side input feed are left as they are, as on the chip. */
static void esp8266_reset(void *opaque)
{
    Esp8266State *s = opaque;

    xtensa_select_static_vectors(&s->cpu->env, 1);  /* 0x40000080 */
    cpu_reset(CPU(s->cpu));
    uart_reset(s);
    gpio_reset(s);
    frc1_reset(s);
    wdt_reset(s);
    memset(s->dport.regs, 0, s->dport.size);
}

static void map_peripherals(Esp8266State *s)
{
    MemoryRegion *catch_all = &s->periph_mr;

    regfile_init(&s->periph, "periph", PERIPH_BASE, PERIPH_SIZE, true);
    memory_region_init_io(catch_all, OBJECT(s), &regfile_ops, &s->periph,
                          "esp8266.periph", PERIPH_SIZE);
    memory_region_add_subregion(get_system_memory(), PERIPH_BASE, catch_all);

    map_regfile(s, &s->dport, "esp8266.dport", DPORT_BASE, DPORT_SIZE, false);
    map_regfile(s, &s->io_mux, "esp8266.io_mux", PERIPH_BASE + IO_MUX_OFFSET,
                0x100, false);
    map_regfile(s, &s->rtc_cntl, "esp8266.rtc_cntl",
                PERIPH_BASE + RTC_CNTL_OFFSET, 0x100, false);
    regfile_init(&s->rtc, "esp8266.rtc", PERIPH_BASE + RTC_OFFSET, 0x100, false);

    map_io(s, &s->uart_mr, &uart_ops, s, "esp8266.uart0",
           PERIPH_BASE + UART0_OFFSET, 0x80);
    map_io(s, &s->gpio_mr, &gpio_ops, s, "esp8266.gpio",
           PERIPH_BASE + GPIO_OFFSET, 0x100);
    map_io(s, &s->frc1_mr, &timer_block_ops, s, "esp8266.timer",
           PERIPH_BASE + FRC1_OFFSET, 0x40);
    map_io(s, &s->rtc_mr, &rtc_ops, s, "esp8266.rtc",
           PERIPH_BASE + RTC_OFFSET, 0x100);
    map_io(s, &s->wdt_mr, &wdt_ops, s, "esp8266.wdt",
           PERIPH_BASE + WDT_OFFSET, 0x20);
}

static void esp8266_init(MachineState *machine)
{
    Esp8266State *s = ESP8266_MACHINE(machine);
    Clock *clk = clock_new(OBJECT(machine), "cpu-refclk");

    clock_set_hz(clk, CPU_HZ);
    s->cpu = xtensa_cpu_create_with_clock(machine->cpu_type, clk);

    map_ram("esp8266.dram", DRAM_BASE, DRAM_SIZE);
    map_ram("esp8266.iram", IRAM_BASE, IRAM_SIZE);
    map_ram("esp8266.rtc_mem", RTC_MEM_BASE, RTC_MEM_SIZE);
    load_rom(s);
    load_flash(s);
    map_peripherals(s);

    s->tx_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, uart_tx_done, s);
    s->input_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, input_tick, s);
    s->frc1_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, frc1_expired, s);
    s->wdt_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, wdt_expired, s);
    s->frc1_irq = s->cpu->env.irq_inputs[FRC1_CPU_IRQ];

    if (serial_hd(0)) {
        qemu_chr_fe_init(&s->chr, serial_hd(0), &error_abort);
        qemu_chr_fe_set_handlers(&s->chr, uart_can_receive, uart_receive,
                                 NULL, NULL, s, NULL, true);
    }
    if (s->events_path) {
        s->events = open_events(s->events_path);
    }
    s->gpio_levels = gpio_compute_levels(s);
    if (s->profile_path) {
        s->profile = g_hash_table_new_full(g_int64_hash, g_int64_equal,
                                           NULL, g_free);
        s->profile_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, profile_tick, s);
        s->profile_ns = MAX(s->profile_ns, 1u);
        if (!s->sim_path) {
            timer_mod(s->profile_timer, s->profile_ns);
        }
    }
    if (s->sim_path) {
        link_start(s);
    }
    load_uart_input(s);
    if (s->stop_ms) {
        s->stop_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, stop_expired, s);
        timer_mod(s->stop_timer, (int64_t)s->stop_ms * SCALE_MS);
    }
    qemu_register_reset(esp8266_reset, s);
}

/* ---- options ------------------------------------------------------------------------ */

#define STRING_OPTION(field)                                          \
    static char *get_##field(Object *obj, Error **errp)                     \
    {                                                                       \
        return g_strdup(ESP8266_MACHINE(obj)->field);                       \
    }                                                                       \
    static void set_##field(Object *obj, const char *v, Error **errp)       \
    {                                                                       \
        Esp8266State *s = ESP8266_MACHINE(obj);                             \
        g_free(s->field);                                                   \
        s->field = g_strdup(v);                                             \
    }

STRING_OPTION(rom_path)
STRING_OPTION(flash_path)
STRING_OPTION(events_path)
STRING_OPTION(input_path)
STRING_OPTION(input_after)
STRING_OPTION(sim_path)
STRING_OPTION(profile_path)

/* uint32 options: `opaque` is the field's offset in Esp8266State. */
static void visit_u32_option(Object *obj, Visitor *v, const char *name,
                             void *opaque, Error **errp)
{
    uint32_t *field = (uint32_t *)((char *)obj + (uintptr_t)opaque);
    visit_type_uint32(v, name, field, errp);
}

static void add_u32_option(ObjectClass *oc, const char *name, size_t offset,
                           const char *description)
{
    object_class_property_add(oc, name, "uint32", visit_u32_option,
                              visit_u32_option, NULL, (void *)offset);
    object_class_property_set_description(oc, name, description);
}

static void esp8266_instance_init(Object *obj)
{
    ESP8266_MACHINE(obj)->input_gap_ms = 100;
    ESP8266_MACHINE(obj)->profile_ns = 10007;
    ESP8266_MACHINE(obj)->link_valid_until = INT64_MAX;
}

static void add_string_option(ObjectClass *oc, const char *name,
                              char *(*get)(Object *, Error **),
                              void (*set)(Object *, const char *, Error **),
                              const char *description)
{
    object_class_property_add_str(oc, name, get, set);
    object_class_property_set_description(oc, name, description);
}

static void esp8266_class_init(ObjectClass *oc, void *data)
{
    MachineClass *mc = MACHINE_CLASS(oc);

    mc->desc = "ESP8266 (paperbot board: ROM boot from flash, UART0, GPIO, "
               "FRC1, watchdog)";
    mc->init = esp8266_init;
    mc->max_cpus = 1;
    mc->default_cpu_type = XTENSA_CPU_TYPE_NAME("lx106");

    add_string_option(oc, "rom", get_rom_path, set_rom_path,
                      "the board's ROM (ELF)");
    add_string_option(oc, "flash", get_flash_path, set_flash_path,
                      "raw flash contents, boot image at offset 0");
    add_string_option(oc, "events", get_events_path, set_events_path,
                      "log of '<virtual ns> <event>' lines (GPIO edges, "
                      "UART input, resets)");
    add_string_option(oc, "uart-input", get_input_path, set_input_path,
                      "file fed to UART0 RX at the baud rate, line by line");
    add_string_option(oc, "uart-input-after", get_input_after,
                      set_input_after,
                      "start uart-input once UART0 has sent this text");
    add_u32_option(oc, "input-gap-ms", offsetof(Esp8266State, input_gap_ms),
        "virtual ms before the first uart-input line and between lines");
    add_string_option(oc, "sim", get_sim_path, set_sim_path,
                      "the simulator's Unix socket (cargo fw-emu --sim)");
    add_string_option(oc, "profile", get_profile_path, set_profile_path,
                      "PC samples written here at stop-ms");
    add_u32_option(oc, "profile-ns", offsetof(Esp8266State, profile_ns),
        "virtual ns between PC samples (default 10007)");
    add_u32_option(oc, "stop-ms", offsetof(Esp8266State, stop_ms),
        "quit after this many virtual ms (0: run until stopped)");
}

static const TypeInfo esp8266_info = {
    .name = TYPE_ESP8266_MACHINE,
    .parent = TYPE_MACHINE,
    .instance_size = sizeof(Esp8266State),
    .instance_init = esp8266_instance_init,
    .class_init = esp8266_class_init,
};

static void esp8266_register(void)
{
    type_register_static(&esp8266_info);
}

type_init(esp8266_register)
