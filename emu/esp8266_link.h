/*
 * esp8266_link: the emulated board's wire to the project's simulator (a
 * Rust process: `cargo fw-emu --sim`), over a Unix stream socket.
 *
 * The board sends events stamped with QEMU's virtual clock: the levels
 * the chip drives on the simulator's pins, each UART0 byte that left, and
 * sync requests. Events queue here and go out with the next sync (or when
 * the queue is full); a sync blocks until the simulator answers with what
 * the outside world does at that virtual instant: whether a slave pulls
 * SDA low, until when that answer holds without further edges, when to
 * sync again (the next script line), whether the run is over, and bytes
 * for UART0 RX.
 *
 * Wire format, little endian. An event is 16 bytes: u64 virtual ns,
 * u32 kind, u32 value. An answer is u32 flags, u32 rx_len, u64
 * valid_until_ns, u64 wake_at_ns, then rx_len bytes. Flags: bit 0 a slave
 * pulls SDA low, bit 1 the simulator has run its course (stop now), bit 2
 * the firmware's loop is running (PC sampling, if asked for, starts).
 *
 * Self-contained (no board state), so QEMU trees that build it without
 * the board using it still link.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef ESP8266_LINK_H
#define ESP8266_LINK_H

#include <stdint.h>
#include <stddef.h>

enum {
    LINK_PINS = 1,      /* value: the driven levels of GPIO0..16 (bit n) */
    LINK_UART_TX = 2,   /* value: the byte UART0 sent */
    LINK_SYNC = 3,      /* the simulator answers */
    LINK_END = 4,       /* the run is over (stop-ms); no answer */
};

#define LINK_SDA_LOW    (1u << 0)
#define LINK_STOP       (1u << 1)
#define LINK_LOOP       (1u << 2)

typedef struct LinkAnswer {
    uint32_t flags;
    int64_t valid_until_ns;
    int64_t wake_at_ns;
    uint32_t rx_len;
    uint8_t rx[256];
} LinkAnswer;

typedef struct Esp8266Link Esp8266Link;

/* Connects to the simulator's socket; exits QEMU with a message on failure. */
Esp8266Link *esp8266_link_connect(const char *path);
void esp8266_link_event(Esp8266Link *l, int64_t t_ns, uint32_t kind,
                        uint32_t value);
/* Sends the queued events and a sync at t_ns; waits for the answer. */
void esp8266_link_sync(Esp8266Link *l, int64_t t_ns, LinkAnswer *answer);
/* Sends the queued events and the end of the run. */
void esp8266_link_end(Esp8266Link *l, int64_t t_ns);

#endif
