/*
 * esp8266_profile: PC sampling of the paperbot ESP8266 board (profile=FILE):
 * the CPU's PC and a0 every profile-ns virtual ns (with sim=, from when the
 * simulator says the firmware's loop runs), written at stop-ms as
 * "<pc> <a0> <samples>" lines (hex, hex, decimal). Not a chip feature.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/error-report.h"
#include "esp8266.h"

/* The vCPU stops at an instruction boundary for a virtual timer under
 * -icount, so env.pc is the next instruction to run. */
void profile_tick(void *opaque)
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

void profile_write(Esp8266State *s)
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
