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
 *   UART0 (0x60000000)    esp8266_uart.c: TRM, UART registers: FIFO,
 *                         INT_RAW/ST/ENA/CLR, CLKDIV, STATUS, CONF0/1; bytes
 *                         leave and arrive at the baud rate of CLKDIV and
 *                         CONF0's frame
 *   GPIO  (0x60000300)    esp8266_gpio.c: TRM, GPIO registers: OUT, ENABLE,
 *                         their W1TS/W1TC, IN, PINn (PAD_DRIVER: open drain)
 *   GPIO16                esp8266_gpio.c: RTC_GPIO_OUT/ENABLE/IN_DATA (RTC
 *                         block 0x60000700; not in the TRM: the esp8266
 *                         PAC's SVD and Espressif's SDK gpio16 driver give
 *                         the offsets)
 *   FRC1  (0x60000600)    esp8266_timers.c: TRM, timer registers: 23-bit
 *                         down counter at 80 MHz / 1, 16 or 256,
 *                         auto-reload, edge or level interrupt on CPU
 *                         interrupt 9 (edge needs DPORT EDGE_INT_ENABLE
 *                         bit 1, 0x3FF00004)
 *   WDT   (0x60000900)    esp8266_wdt.c: not in the TRM: register offsets
 *                         from the esp8266 PAC's SVD, stage lengths from
 *                         esp8266-hal's StageTimeout (0.84 s * 2^(n - 10)
 *                         at 80 MHz)
 *   DPORT, IO_MUX, RTC, RTC control: plain registers, accepted quietly
 *   everything else in 0x60000000..0x60001000: plain registers, each first
 *   access logged under `-d unimp`.
 *
 * This file: the memory map, the ROM and flash, the register files, the
 * event log, reset, init and the options. The wire to the simulator:
 * esp8266_sim.c (the board's side) and esp8266_link.c (the socket); PC
 * sampling: esp8266_profile.c. The state and what the files share:
 * esp8266.h.
 *
 * Machine options (-M esp8266,...):
 *   rom=FILE          the ROM (ELF, built by emu/build-qemu.sh)
 *   flash=FILE        raw flash contents (boot image at offset 0); flash
 *                     programs and erases are written back to it
 *   flash-power-ops=N the power fails before the N+1th program or erase
 *   events=FILE       "<virtual ns> <event>" lines: GPIO edges, UART input
 *                     lines fed, resets; at a timed run's end the stack's
 *                     low-water mark (stack-low ADDR)
 *   uart-input=FILE   bytes fed to UART0 RX at the baud rate, a line at a
 *                     time, input-gap-ms apart, starting input-gap-ms after
 *                     UART0 TX has sent the text uart-input-after (or at
 *                     once when that is empty)
 *   stop-ms=N         quit (exit status 0) after N virtual milliseconds
 *   sim=PATH          the simulator's Unix socket (esp8266_link.h): the
 *                     I2C slaves on GPIO14/12, XSHUT on GPIO0/2, the servo
 *                     pins GPIO5/4 and UART0 wired to the simulated robot
 *   flash-mode=M      the fastest read mode the flash chip answers (qio,
 *                     qout, dio, dout; default dio, the NodeMCU's ESP-12E):
 *                     a slower mode is answered too, a faster one is not
 *   uart-baud=N       the rate the other end of UART0 listens at (default
 *                     115200): bytes sent more than 3 % off it arrive as
 *                     0xFF, as framing garbage does on a terminal
 *   profile=FILE      at stop-ms, the CPU's PC sampled every profile-ns
 *                     virtual ns (with sim=, from when the simulator says
 *                     the firmware's loop runs): "<pc> <a0> <samples>"
 *                     lines (hex, hex, decimal)
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/log.h"
#include "qemu/error-report.h"
#include "qapi/error.h"
#include "qapi/visitor.h"
#include "sysemu/reset.h"
#include "sysemu/runstate.h"
#include "sysemu/sysemu.h"
#include "hw/loader.h"
#include "hw/clock.h"
#include "elf.h"
#include "exec/address-spaces.h"
#include "esp8266.h"

/* ---- the event log (events=FILE) --------------------------------------------- */

void log_event(Esp8266State *s, const char *fmt, ...)
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

/* ---- register files: the blocks we accept without modelling ------------ */

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

uint32_t regfile_read(RegFile *f, hwaddr addr)
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

void regfile_write(RegFile *f, hwaddr addr, uint32_t v)
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
    RegFile *f = opaque;

    regfile_write(f, addr, v);
    if (f->written) {
        f->written(f->written_opaque);
    }
}

/* Peripheral registers are 32-bit; narrower accesses are widened by QEMU. */
static const MemoryRegionOps regfile_ops = {
    .read = regfile_io_read,
    .write = regfile_io_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* ---- memory and images ---------------------------------------------------------- */

/* RAM as at power-on: not zero (POWER_ON_PATTERN), so an image that
 * counts on memory it did not zero sees the difference. */
static void map_ram(const char *name, hwaddr base, uint64_t size)
{
    MemoryRegion *mr = g_new(MemoryRegion, 1);

    memory_region_init_ram(mr, NULL, name, size, &error_fatal);
    memory_region_add_subregion(get_system_memory(), base, mr);
    memset(memory_region_get_ram_ptr(mr), POWER_ON_PATTERN, size);
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
 * (the first MiB; the rest of the file is accepted and not mapped). The
 * window is there only while the cache is on in a mode the flash answers
 * (esp8266_clock.c); under it, flash_off_mr refuses the read. The whole
 * chip, written through SPI0's commands: esp8266_flash.c. */
static void load_flash(Esp8266State *s)
{
    g_autofree gchar *data = NULL;
    gsize len;
    GError *err = NULL;
    uint8_t *window;

    memory_region_init_rom(&s->flash_mr, OBJECT(s), "esp8266.flash",
                           FLASH_MAP_SIZE, &error_fatal);
    memory_region_add_subregion_overlap(get_system_memory(), FLASH_MAP_BASE,
                                        &s->flash_mr, 1);
    memory_region_set_enabled(&s->flash_mr, false);
    memory_region_init_io(&s->flash_off_mr, OBJECT(s), &flash_off_ops, s,
                          "esp8266.flash-off", FLASH_MAP_SIZE);
    memory_region_add_subregion_overlap(get_system_memory(), FLASH_MAP_BASE,
                                        &s->flash_off_mr, 0);
    window = memory_region_get_ram_ptr(&s->flash_mr);
    memset(window, 0xff, FLASH_MAP_SIZE);   /* erased flash */
    if (!s->flash_path) {
        flash_chip_load(s, NULL, 0);
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
    flash_chip_load(s, (const uint8_t *)data, len);
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

/* The top of DRAM, above the image's (memory.x's dram_seg ends at
 * 0x3FFFC000): the stack the ROM hands the image grows down from 0x3FFFFFF0
 * there, and nothing else on this board writes it (its ROM keeps no data). */
#define STACK_REGION_BASE 0x3fffc000u

/* The stack's low-water mark over the run: the lowest byte of the region
 * that no longer holds the power-on pattern, logged as `stack-low ADDR`
 * (`cargo fw-emu --sim-test` holds it against xtask's static bound). A
 * deepest byte that happened to be written with the pattern itself would
 * read a few bytes shallower. */
static void log_stack_low(Esp8266State *s)
{
    static uint8_t region[DRAM_BASE + DRAM_SIZE - STACK_REGION_BASE];
    uint32_t at = 0;

    address_space_read(&address_space_memory, STACK_REGION_BASE, MEMTXATTRS_UNSPECIFIED, region,
                       sizeof(region));
    while (at < sizeof(region) && region[at] == POWER_ON_PATTERN) {
        at++;
    }
    log_event(s, "stack-low 0x%08x", STACK_REGION_BASE + at);
}

/* The end of a timed run (stop-ms): QEMU exits with status 0. The main loop
 * acts on the request a little later; what the guest sends meanwhile is
 * dropped, so a run's output ends at exactly stop-ms. */
void stop_expired(void *opaque)
{
    Esp8266State *s = opaque;

    log_stack_low(s);
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

/* The boot mode from the strapping pins at the instant of the reset, before
 * the pins are released: GPIO15 (pulled low on the NodeMCU), GPIO0, GPIO2
 * as bits 2, 1, 0 (Espressif's boot messages: 3 boots from flash, 1 is UART
 * download mode). A pin the firmware drives low when the reset comes
 * counts as low. */
static uint32_t latch_boot_mode(Esp8266State *s)
{
    uint32_t gpio0 = s->gpio_levels & 1, gpio2 = (s->gpio_levels >> 2) & 1;

    return (gpio0 << 1) | gpio2;
}

/* Power-on and every watchdog reset: the boot mode latched, the clock back
 * to the crystal's, the chip's peripherals to their reset state (the flash
 * cache off), the CPU to the ROM's reset vector. RAM, RTC memory, the flash
 * and the host-side input feed are left as they are, as on the chip. */
void esp8266_reset(void *opaque)
{
    Esp8266State *s = opaque;

    s->boot_mode = latch_boot_mode(s);
    s->rtc.regs[RTC_RESET_CAUSE / 4] = s->reset_cause;
    log_event(s, "reset cause %u boot-mode %u", s->reset_cause, s->boot_mode);
    if (s->boot_mode == BOOT_MODE_UART) {
        log_event(s, "download-mode");
        error_report("esp8266: reset with GPIO0 low: the ROM enters UART "
                     "download mode (boot mode 1) and runs nothing");
    } else if (s->boot_mode != BOOT_MODE_FLASH) {
        error_report("esp8266: reset with boot mode %u (GPIO0, GPIO2 = %u, "
                     "%u): not a flash boot, nothing runs", s->boot_mode,
                     (s->boot_mode >> 1) & 1, s->boot_mode & 1);
    }
    clock_reset(s);
    xtensa_select_static_vectors(&s->cpu->env, 1);  /* 0x40000080 */
    cpu_reset(CPU(s->cpu));
    uart_reset(s);
    gpio_reset(s);
    frc1_reset(s);
    wdt_reset(s);
    memset(s->dport.regs, 0, s->dport.size);
    memset(s->spi0.regs, 0, s->spi0.size);
    s->flash_off_logged = false;
    flash_update_map(s);
}

static void map_peripherals(Esp8266State *s)
{
    MemoryRegion *catch_all = &s->periph_mr;

    regfile_init(&s->periph, "periph", PERIPH_BASE, PERIPH_SIZE, true);
    memory_region_init_io(catch_all, OBJECT(s), &regfile_ops, &s->periph,
                          "esp8266.periph", PERIPH_SIZE);
    memory_region_add_subregion(get_system_memory(), PERIPH_BASE, catch_all);

    /* DPORT SPI_CACHE and SPI0 CTRL decide whether the flash is readable */
    map_regfile(s, &s->dport, "esp8266.dport", DPORT_BASE, DPORT_SIZE, false);
    s->dport.written = flash_update_map;
    s->dport.written_opaque = s;
    map_regfile(s, &s->io_mux, "esp8266.io_mux", PERIPH_BASE + IO_MUX_OFFSET,
                0x100, false);
    regfile_init(&s->rtc_cntl, "esp8266.rtc_cntl",
                 PERIPH_BASE + RTC_CNTL_OFFSET, 0x100, false);
    map_io(s, &s->rtc_cntl_mr, &rtc_cntl_ops, s, "esp8266.rtc_cntl",
           PERIPH_BASE + RTC_CNTL_OFFSET, 0x100);
    map_regfile(s, &s->spi0, "esp8266.spi0", PERIPH_BASE + SPI0_OFFSET, 0x100,
                false);
    s->spi0.written = spi0_written;
    s->spi0.written_opaque = s;
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

    if (!parse_flash_mode(s->flash_mode_name, &s->flash_best)) {
        error_report("esp8266: flash-mode=%s: one of qio, qout, dio, dout",
                     s->flash_mode_name);
        exit(1);
    }
    s->cpu_clk = clk;
    s->cpu_hz = CPU_HZ_RESET;
    s->reset_cause = RST_CAUSE_POWER_ON;
    clock_set_hz(clk, CPU_HZ_RESET);
    s->cpu = xtensa_cpu_create_with_clock(machine->cpu_type, clk);

    /* IRAM, the cache's RAM after it and the flash window: the instruction
     * bus, which takes 32-bit loads only (LoadStoreError otherwise) */
    xtensa_narrow_load_error_base = IRAM_BASE;
    xtensa_narrow_load_error_size = FLASH_MAP_BASE + FLASH_MAP_SIZE - IRAM_BASE;
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
    s->uart_irq = s->cpu->env.irq_inputs[UART_CPU_IRQ];

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
STRING_OPTION(flash_mode_name)

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
    ESP8266_MACHINE(obj)->flash_mode_name = g_strdup("dio");
    ESP8266_MACHINE(obj)->uart_baud = 115200;
    ESP8266_MACHINE(obj)->profile_ns = 10007;
    ESP8266_MACHINE(obj)->link_valid_until = INT64_MAX;
    ESP8266_MACHINE(obj)->flash_power_ops = UINT32_MAX;
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
    add_string_option(oc, "flash-mode", get_flash_mode_name,
                      set_flash_mode_name,
                      "the fastest read mode the flash chip answers: qio, "
                      "qout, dio (default), dout");
    add_u32_option(oc, "flash-power-ops", offsetof(Esp8266State, flash_power_ops),
        "the power fails before the flash program or erase after these "
        "many (a power cut mid-save; default: never)");
    add_u32_option(oc, "uart-baud", offsetof(Esp8266State, uart_baud),
        "the baud rate the other end of UART0 listens at (default 115200)");
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
