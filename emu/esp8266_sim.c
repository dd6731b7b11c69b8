/*
 * esp8266_sim: the paperbot ESP8266 board's pins and UART0 RX wired to the
 * project's simulator (sim=PATH), through the socket of esp8266_link.h: the
 * I2C slaves on GPIO14/12, XSHUT on GPIO0/2, the servo pins GPIO5/4. Which
 * pin edges are reported, when a read of GPIO_IN waits for the simulator,
 * and what its answers do to the board (our own design; see emu/README.md).
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/log.h"
#include "esp8266.h"

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
void link_note_pins(Esp8266State *s, uint32_t driven)
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

void link_refresh(Esp8266State *s)
{
    if (s->link && (s->link_dirty || now_ns() >= s->link_valid_until)) {
        link_sync(s);
    }
}

static void link_wake(void *opaque)
{
    link_sync(opaque);
}

void link_start(Esp8266State *s)
{
    s->link = esp8266_link_connect(s->sim_path);
    s->link_wake_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, link_wake, s);
    s->link_rx_timer = timer_new_ns(QEMU_CLOCK_VIRTUAL, link_rx_tick, s);
    s->driven = gpio_driven_levels(s);
    esp8266_link_event(s->link, 0, LINK_PINS, s->driven & LINK_PINS_MASK);
    link_sync(s);
}
