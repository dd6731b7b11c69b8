/*
 * esp8266_link: the board's wire to the simulator (see esp8266_link.h).
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "qemu/osdep.h"
#include "qemu/error-report.h"
#include <sys/socket.h>
#include <sys/un.h>
#include "esp8266_link.h"

#define EVENT_BYTES     16
#define QUEUE_EVENTS    4096
#define ANSWER_HEADER   24

struct Esp8266Link {
    int fd;
    uint8_t queue[QUEUE_EVENTS * EVENT_BYTES];
    size_t queued;      /* bytes */
};

static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = v >> (8 * i);
    }
}

static void put_u64(uint8_t *p, uint64_t v)
{
    put_u32(p, (uint32_t)v);
    put_u32(p + 4, (uint32_t)(v >> 32));
}

static uint32_t get_u32(const uint8_t *p)
{
    return p[0] | p[1] << 8 | p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t get_u64(const uint8_t *p)
{
    return get_u32(p) | (uint64_t)get_u32(p + 4) << 32;
}

static G_NORETURN void link_lost(const char *what)
{
    error_report("esp8266: simulator link: %s: %s", what,
                 errno ? strerror(errno) : "closed");
    exit(1);
}

static void write_all(Esp8266Link *l, const uint8_t *p, size_t n)
{
    while (n) {
        ssize_t k = write(l->fd, p, n);
        if (k < 0 && errno == EINTR) {
            continue;
        }
        if (k <= 0) {
            link_lost("write");
        }
        p += k;
        n -= k;
    }
}

static void read_all(Esp8266Link *l, uint8_t *p, size_t n)
{
    while (n) {
        ssize_t k = read(l->fd, p, n);
        if (k < 0 && errno == EINTR) {
            continue;
        }
        if (k <= 0) {
            errno = k < 0 ? errno : 0;
            link_lost("read");
        }
        p += k;
        n -= k;
    }
}

static void flush(Esp8266Link *l)
{
    write_all(l, l->queue, l->queued);
    l->queued = 0;
}

Esp8266Link *esp8266_link_connect(const char *path)
{
    Esp8266Link *l = g_new0(Esp8266Link, 1);
    struct sockaddr_un addr = { .sun_family = AF_UNIX };

    if (strlen(path) >= sizeof(addr.sun_path)) {
        error_report("esp8266: sim=%s: path too long", path);
        exit(1);
    }
    strcpy(addr.sun_path, path);
    l->fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (l->fd < 0 || connect(l->fd, (struct sockaddr *)&addr, sizeof(addr))) {
        error_report("esp8266: sim=%s: %s", path, strerror(errno));
        exit(1);
    }
    return l;
}

void esp8266_link_event(Esp8266Link *l, int64_t t_ns, uint32_t kind,
                        uint32_t value)
{
    uint8_t *p;

    if (l->queued == sizeof(l->queue)) {
        flush(l);
    }
    p = l->queue + l->queued;
    put_u64(p, t_ns);
    put_u32(p + 8, kind);
    put_u32(p + 12, value);
    l->queued += EVENT_BYTES;
}

void esp8266_link_sync(Esp8266Link *l, int64_t t_ns, LinkAnswer *answer)
{
    uint8_t head[ANSWER_HEADER];

    esp8266_link_event(l, t_ns, LINK_SYNC, 0);
    flush(l);
    read_all(l, head, sizeof(head));
    answer->flags = get_u32(head);
    answer->rx_len = get_u32(head + 4);
    answer->valid_until_ns = (int64_t)MIN(get_u64(head + 8), (uint64_t)INT64_MAX);
    answer->wake_at_ns = (int64_t)MIN(get_u64(head + 16), (uint64_t)INT64_MAX);
    if (answer->rx_len > sizeof(answer->rx)) {
        errno = 0;
        link_lost("answer with too many RX bytes");
    }
    read_all(l, answer->rx, answer->rx_len);
}

void esp8266_link_end(Esp8266Link *l, int64_t t_ns)
{
    esp8266_link_event(l, t_ns, LINK_END, 0);
    flush(l);
}
