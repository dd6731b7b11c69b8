/*
 * esp8266_uart: UART0 (0x60000000) of the paperbot ESP8266 board.
 *
 * From the ESP8266 Technical Reference (TRM), UART registers: the 128-byte
 * TX and RX FIFOs, INT_RAW/ST/ENA/CLR (RXFIFO_FULL, TXFIFO_EMPTY, overflow;
 * CPU interrupt 5 while one enabled is raised),
 * CLKDIV, STATUS, CONF0/1; bytes leave and arrive at the baud rate of CLKDIV
 * and CONF0's frame. Also the board's deterministic input (uart-input=FILE):
 * a line at a time, input-gap-ms apart, once UART0 TX has sent the text
 * uart-input-after.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/log.h"
#include "qemu/error-report.h"
#include "hw/irq.h"
#include "esp8266.h"

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
#define UART_CLKDIV_RESET       (CPU_HZ_PLL / 115200)
/* How far off the listener's rate a byte may be and still be read, and
 * what it reads otherwise (a frame sampled at the wrong rate). */
#define UART_BAUD_TOLERANCE_PCT 3
#define UART_GARBLED            0xff

bool fifo_push(Fifo *f, uint8_t b)
{
    if (f->count == UART_FIFO_LEN) {
        return false;
    }
    f->data[(f->head + f->count) % UART_FIFO_LEN] = b;
    f->count++;
    return true;
}

uint8_t fifo_pop(Fifo *f)
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
int64_t uart_frame_ns(Esp8266State *s)
{
    unsigned data_bits = 5 + ((s->uart_conf0 >> 2) & 3);
    unsigned parity = (s->uart_conf0 >> 1) & 1;
    unsigned stop_half_bits = (s->uart_conf0 >> 4) & 3 ? ((s->uart_conf0 >> 4) & 3) + 1 : 2;
    uint64_t half_bits = 2 * (1 + data_bits + parity) + stop_half_bits;
    uint32_t div = s->uart_clkdiv & 0xfffff;

    return cycles_to_ns(s, half_bits * MAX(div, 1u) / 2);
}

/* RXFIFO_FULL and TXFIFO_EMPTY follow the fill levels against CONF1's
 * thresholds; they are levels, not latched. UART0's CPU interrupt (5, a
 * level one) is raised while INT_RAW & INT_ENA is not zero. */
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
    qemu_set_irq(s->uart_irq, (s->uart_int_raw & s->uart_int_ena) != 0);
}

void uart_receive_byte(Esp8266State *s, uint8_t b)
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
void input_tick(void *opaque)
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

/* The byte as the other end, listening at uart-baud, reads it: the rate is
 * the CPU clock over CLKDIV (52 MHz before the PLL write, so the ROM's
 * divider for 115200 at 80 MHz gives 74880 baud). A change of rate is
 * logged ("uart0-baud N"). */
static uint8_t uart_as_heard(Esp8266State *s, uint8_t b)
{
    uint32_t baud = s->cpu_hz / MAX(s->uart_clkdiv & 0xfffff, 1u);
    uint64_t off = baud > s->uart_baud ? baud - s->uart_baud
                                       : s->uart_baud - baud;

    if (baud != s->uart_tx_baud) {
        s->uart_tx_baud = baud;
        log_event(s, "uart0-baud %u", baud);
    }
    return off * 100 <= (uint64_t)s->uart_baud * UART_BAUD_TOLERANCE_PCT
           ? b : UART_GARBLED;
}

/* The byte at the head of the TX FIFO has been shifted out. */
void uart_tx_done(void *opaque)
{
    Esp8266State *s = opaque;
    uint8_t b = uart_as_heard(s, fifo_pop(&s->tx));

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
        uart_update_levels(s);
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

const MemoryRegionOps uart_ops = {
    .read = uart_read,
    .write = uart_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* Host input (the chardev: a pty or stdio) goes straight into the RX FIFO. */
int uart_can_receive(void *opaque)
{
    Esp8266State *s = opaque;
    return UART_FIFO_LEN - s->rx.count;
}

void uart_receive(void *opaque, const uint8_t *buf, int size)
{
    Esp8266State *s = opaque;

    for (int i = 0; i < size; i++) {
        uart_receive_byte(s, buf[i]);
    }
}

void uart_reset(Esp8266State *s)
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

/* uart-input=FILE, read at init; fed from input_tick. */
void load_uart_input(Esp8266State *s)
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
