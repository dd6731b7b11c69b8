/*
 * esp8266: the board's private header. The machine's state (one struct for
 * every part), the memory map and peripheral offsets (ESP8266 Technical
 * Reference (TRM), memory map; the WDT and GPIO16 blocks from the esp8266
 * PAC's SVD), and what each of the board's files gives the others. What the
 * board models, and its options: esp8266.c.
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#ifndef HW_XTENSA_ESP8266_H
#define HW_XTENSA_ESP8266_H

#include "qemu/units.h"
#include "qemu/timer.h"
#include "cpu.h"
#include "hw/boards.h"
#include "exec/memory.h"
#include "chardev/char-fe.h"
#include "qom/object.h"
#include "esp8266_link.h"

#define TYPE_ESP8266_MACHINE MACHINE_TYPE_NAME("esp8266")
OBJECT_DECLARE_SIMPLE_TYPE(Esp8266State, ESP8266_MACHINE)

/* The CPU clock: 52 MHz from the 26 MHz crystal at power-on and after
 * every reset, until the firmware's PLL write (esp8266-hal's, for a 26 MHz
 * crystal) makes it 80 MHz. CCOUNT, FRC1, the UART and the watchdog run
 * from it (esp8266_clock.c). */
#define CPU_HZ_RESET      52000000u
#define CPU_HZ_PLL        80000000u

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
/* The module's flash chip (ESP-12: 4 MiB; the image header says 4MB). */
#define FLASH_CHIP_SIZE   (4 * MiB)
#define DPORT_BASE        0x3ff00000u
#define DPORT_SIZE        0x100u
#define PERIPH_BASE       0x60000000u
#define PERIPH_SIZE       0x1000u
#define RTC_MEM_BASE      0x60001000u
#define RTC_MEM_SIZE      (1 * KiB)
/* What RAM and RTC memory hold at power-on: not zero (esp8266_init). */
#define POWER_ON_PATTERN  0xa5

/* Peripheral blocks, offsets from PERIPH_BASE (TRM / PAC). */
#define UART0_OFFSET      0x000
#define SPI0_OFFSET       0x200
#define GPIO_OFFSET       0x300
#define FRC1_OFFSET       0x600
#define RTC_OFFSET        0x700
#define IO_MUX_OFFSET     0x800
#define WDT_OFFSET        0x900
#define RTC_CNTL_OFFSET   0xd00

/* CPU interrupt of FRC1 (core-isa.h: interrupt 9 is external, edge). */
#define FRC1_CPU_IRQ      9
/* CPU interrupt of UART0 (core-isa.h: interrupt 5 is external, level;
 * esp8266-hal InterruptType::UART). */
#define UART_CPU_IRQ      5
/* DPORT EDGE_INT_ENABLE: bit 1 lets FRC1's edge interrupt through. */
#define DPORT_EDGE_INT_ENABLE   0x04
#define EDGE_INT_FRC1           (1u << 1)
/* DPORT SPI_CACHE (PAC: "Controls SPI memory-mapped caching"): bit 8
 * enables the flash cache, through which 0x40200000.. is read. */
#define DPORT_SPI_CACHE         0x0c
#define SPI_CACHE_ENABLE        (1u << 8)

/* The boot modes the ROM prints, from the strapping pins latched at reset
 * (GPIO15, GPIO0, GPIO2 as bits 2, 1, 0; GPIO_IN bits 16..18 here). */
#define BOOT_MODE_UART          1
#define BOOT_MODE_FLASH         3
/* Reset causes the ROM prints ("rst cause:N"): Espressif's ESP8266 boot
 * messages: 1 power on, 2 external reset, 4 hardware watchdog. */
#define RST_CAUSE_POWER_ON      1
#define RST_CAUSE_WATCHDOG      4
/* Where the ROM reads them: RTC block 0x60000714 (the board's choice). */
#define RTC_RESET_CAUSE         0x14

/* SPI flash read modes (SPI0 CTRL's read-mode bits; esptool's header
 * byte 2: 0 QIO, 1 QOUT, 2 DIO, 3 DOUT). SLOW: none of the bits set, the
 * single-line read every flash answers. */
typedef enum FlashMode {
    FLASH_QIO, FLASH_QOUT, FLASH_DIO, FLASH_DOUT, FLASH_SLOW,
} FlashMode;

#define NUM_GPIO          16      /* GPIO0..15; GPIO16 is the RTC's */
#define UART_FIFO_LEN     128

/* ---- the machine's state ------------------------------------------------ */

/* A block we accept without modelling: plain registers (esp8266.c). */
typedef struct RegFile {
    const char *name;
    hwaddr base;
    unsigned size;
    bool log_unimp;         /* log each register's first read and write */
    uint32_t *regs;
    uint8_t *logged;        /* bit 0: read logged, bit 1: write logged */
    void (*written)(void *opaque);  /* after each write, when set */
    void *written_opaque;
} RegFile;

typedef struct Fifo {
    uint8_t data[UART_FIFO_LEN];
    unsigned head, count;
} Fifo;

struct Esp8266State {
    MachineState parent;

    XtensaCPU *cpu;
    Clock *cpu_clk;
    uint32_t cpu_hz;            /* CPU_HZ_RESET until the PLL write */
    uint32_t pll_writes;        /* bit 0: address 1, bit 1: address 2 written for 26 MHz */
    uint32_t reset_cause;       /* the cause of the next (or last) reset */
    uint32_t boot_mode;         /* latched from the strapping pins at reset */
    char *rom_path, *flash_path, *events_path;
    char *flash_mode_name;      /* flash-mode=: the best mode the flash chip answers */
    FlashMode flash_best;
    uint32_t uart_baud;         /* uart-baud=: the rate the other end listens at */
    uint32_t uart_tx_baud;      /* the rate of the last byte sent, for the log */
    char *input_path, *input_after;
    uint32_t input_gap_ms, stop_ms;
    FILE *events;
    QEMUTimer *stop_timer;
    bool stopped;               /* past stop-ms: nothing more leaves the board */

    MemoryRegion flash_mr, flash_off_mr, dport_mr, periph_mr, uart_mr, gpio_mr,
                 rtc_mr, frc1_mr, wdt_mr, rtc_cntl_mr;
    RegFile dport, periph, rtc, io_mux, rtc_cntl, spi0;
    bool flash_readable;        /* the cache on, in a mode the flash answers */
    uint8_t *flash_data;        /* the chip's contents (esp8266_flash.c) */
    size_t flash_file_len;      /* bytes of the flash file */
    bool flash_wel;             /* the write-enable latch */
    int64_t flash_busy_until_ns;    /* a program or erase in progress */
    uint32_t flash_power_ops;   /* programs and erases the power lasts for
                                   (UINT32_MAX: for ever) */
    bool flash_off_logged;

    /* UART0 */
    CharBackend chr;
    Fifo tx, rx;
    uint32_t uart_int_raw, uart_int_ena, uart_clkdiv, uart_conf0, uart_conf1;
    QEMUTimer *tx_timer;
    qemu_irq uart_irq;
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

    /* the simulator (sim=PATH): see esp8266_sim.c */
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

static inline int64_t now_ns(void)
{
    return qemu_clock_get_ns(QEMU_CLOCK_VIRTUAL);
}

/* Cycles of the CPU clock (which also clocks the peripherals) in ns. */
static inline int64_t cycles_to_ns(Esp8266State *s, uint64_t cycles)
{
    return muldiv64(cycles, NANOSECONDS_PER_SECOND, s->cpu_hz);
}

/* target/xtensa/translate.c, as emu/qemu-narrow-load.patch changes it: an
 * 8- or 16-bit load from [base, base + size) raises LoadStoreError. */
extern uint32_t xtensa_narrow_load_error_base, xtensa_narrow_load_error_size;

/* esp8266.c: the machine */
void log_event(Esp8266State *s, const char *fmt, ...) G_GNUC_PRINTF(2, 3);
uint32_t regfile_read(RegFile *f, hwaddr addr);
void regfile_write(RegFile *f, hwaddr addr, uint32_t v);
void esp8266_reset(void *opaque);
void stop_expired(void *opaque);

/* esp8266_clock.c: the CPU clock, the PLL, the flash cache and SPI0 */
extern const MemoryRegionOps rtc_cntl_ops, flash_off_ops;
void clock_reset(Esp8266State *s);
void flash_update_map(void *opaque);
bool parse_flash_mode(const char *name, FlashMode *mode);

/* esp8266_flash.c: the flash chip behind SPI0's commands */
void flash_chip_load(Esp8266State *s, const uint8_t *data, size_t len);
void spi0_written(void *opaque);

/* esp8266_uart.c: UART0 */
extern const MemoryRegionOps uart_ops;
bool fifo_push(Fifo *f, uint8_t b);
uint8_t fifo_pop(Fifo *f);
int64_t uart_frame_ns(Esp8266State *s);
void uart_receive_byte(Esp8266State *s, uint8_t b);
void uart_tx_done(void *opaque);
void input_tick(void *opaque);
int uart_can_receive(void *opaque);
void uart_receive(void *opaque, const uint8_t *buf, int size);
void uart_reset(Esp8266State *s);
void load_uart_input(Esp8266State *s);

/* esp8266_gpio.c: GPIO0..15 and GPIO16 (the RTC block) */
extern const MemoryRegionOps gpio_ops, rtc_ops;
uint32_t gpio_driven_levels(Esp8266State *s);
uint32_t gpio_compute_levels(Esp8266State *s);
void gpio_update(Esp8266State *s);
void gpio_reset(Esp8266State *s);

/* esp8266_sim.c: the wire to the simulator (sim=PATH) */
void link_note_pins(Esp8266State *s, uint32_t driven);
void link_refresh(Esp8266State *s);
void link_start(Esp8266State *s);

/* esp8266_profile.c: PC sampling (profile=FILE) */
void profile_tick(void *opaque);
void profile_write(Esp8266State *s);

/* esp8266_timers.c: FRC1 */
extern const MemoryRegionOps timer_block_ops;
void frc1_expired(void *opaque);
void frc1_reset(Esp8266State *s);

/* esp8266_wdt.c: the watchdog */
extern const MemoryRegionOps wdt_ops;
void wdt_expired(void *opaque);
void wdt_reset(Esp8266State *s);

#endif
