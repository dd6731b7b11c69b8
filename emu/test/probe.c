/*
 * The board's test images, one per PROBE_* mode (emu/build-qemu.sh builds
 * probe-<mode>.elf; `cargo fw-emu --self-test` wraps each in a DIO boot
 * image). Each does one thing the chip refuses or punishes and says what
 * it does on UART0, so that the self-test can show the board refuses it
 * too. All but PROBE_NO_PLL first write the PLL as esp8266-hal does (the
 * CPU and UART0 at 80 MHz, 115200 baud). The ROM's vectors stay in place
 * (VECBASE 0x40000000), so an exception is reported by the ROM.
 *
 *   wdt          counts its boots in RTC user memory (a magic word first:
 *                RTC memory is not zero at power-on), starts the watchdog
 *                as esp8266-hal does (two stages of 0.84 s), feeds it for
 *                0.5 s, stops feeding: the board must reset it 1.68 s
 *                later and the ROM boot it again
 *   gpio0-low    the same, but it drives GPIO0 low (a lidar's XSHUT held
 *                in reset) when it stops feeding: the reset must enter
 *                UART download mode, and nothing boots again
 *   no-pll       prints a line without the PLL write: it goes out at
 *                74880 baud, garbage to a 115200 listener
 *   ram          prints a DRAM word that no segment loads and the image
 *                never wrote: not zero
 *   narrow-iram  an 8-bit load from IRAM: LoadStoreError (EXCCAUSE 3)
 *   narrow-flash a 16-bit load from flash (the cache on, DIO): the same
 */
#include <stdint.h>

#define REG(addr)           (*(volatile uint32_t *)(addr))
#define UART0_FIFO          0x60000000u
#define UART0_CLKDIV        0x60000014u
#define UART0_STATUS        0x6000001cu
#define SPI0_CTRL           0x60000208u
#define GPIO_OUT_W1TC       0x60000308u
#define GPIO_ENABLE_W1TS    0x60000310u
#define WDT_CTL             0x60000900u
#define WDT_OP              0x60000904u
#define WDT_OP_ND           0x60000908u
#define WDT_RST             0x60000914u
#define RTC_CNTL_PLL        0x60000d10u
#define RTC_USER_MEMORY     0x60001200u
#define DPORT_SPI_CACHE     0x3ff0000cu
#define FLASH_MAPPED        0x40200000u

#define CPU_HZ              80000000u
#define FEED_CYCLES         (CPU_HZ / 2)    /* 0.5 s */
#define WDT_STAGE_084       10
#define WDT_CTL_MODE        0x38            /* bits 3..5, as esp8266-hal writes */
#define WDT_ENABLE          1u
#define WDT_FEED            0x73
#define BOOTS_MAGIC         0x50524f42u     /* "PROB" */

static uint32_t unloaded __attribute__((section(".unloaded"), used));

static __attribute__((unused)) uint32_t ccount(void)
{
    uint32_t c;
    __asm__ volatile("rsr %0, ccount" : "=r"(c));
    return c;
}

static void put_char(char c)
{
    while (((REG(UART0_STATUS) >> 16) & 0xff) >= 126) {
    }
    REG(UART0_FIFO) = (uint8_t)c;
}

static void put_str(const char *s)
{
    while (*s) {
        put_char(*s++);
    }
}

static __attribute__((unused)) void put_hex(uint32_t v)
{
    put_str("0x");
    for (int i = 7; i >= 0; i--) {
        put_char("0123456789abcdef"[(v >> (4 * i)) & 0xf]);
    }
}

static void __attribute__((noreturn)) spin(void)
{
    for (;;) {
    }
}

#if !defined(PROBE_NO_PLL)
/* esp8266-hal's PLL write for a 26 MHz crystal: internal I2C block 0x67,
 * address 1 <- 0x88, address 2 <- 0x91 (write bit 24); then UART0's
 * divider for 115200 baud at 80 MHz. */
static void pll_80mhz(void)
{
    REG(RTC_CNTL_PLL) = 0x67 | (1u << 8) | (0x88u << 16) | (1u << 24);
    REG(RTC_CNTL_PLL) = 0x67 | (2u << 8) | (0x91u << 16) | (1u << 24);
    REG(UART0_CLKDIV) = CPU_HZ / 115200;
}
#endif

#if defined(PROBE_WDT) || defined(PROBE_GPIO0_LOW)
static void __attribute__((noreturn)) starve_watchdog(int gpio0_low)
{
    uint32_t start;

    if (REG(RTC_USER_MEMORY) != BOOTS_MAGIC) {
        REG(RTC_USER_MEMORY) = BOOTS_MAGIC;
        REG(RTC_USER_MEMORY + 4) = 0;
    }
    REG(RTC_USER_MEMORY + 4) += 1;
    put_str("probe: boot ");
    put_char(REG(RTC_USER_MEMORY + 4) < 10 ? (char)('0' + REG(RTC_USER_MEMORY + 4)) : '+');
    put_str("\r\n");

    REG(WDT_CTL) = WDT_CTL_MODE;
    REG(WDT_OP) = WDT_STAGE_084;
    REG(WDT_OP_ND) = WDT_STAGE_084;
    REG(WDT_RST) = WDT_FEED;
    REG(WDT_CTL) = WDT_CTL_MODE | WDT_ENABLE;
    start = ccount();
    while (ccount() - start < FEED_CYCLES) {
        REG(WDT_RST) = WDT_FEED;
    }
    if (gpio0_low) {
        REG(GPIO_OUT_W1TC) = 1;
        REG(GPIO_ENABLE_W1TS) = 1;
        put_str("probe: starving, GPIO0 driven low\r\n");
    } else {
        put_str("probe: starving\r\n");
    }
    spin();
}
#endif

void __attribute__((noreturn)) _start(void)
{
#if !defined(PROBE_NO_PLL)
    pll_80mhz();
#endif
#if defined(PROBE_WDT)
    starve_watchdog(0);
#elif defined(PROBE_GPIO0_LOW)
    starve_watchdog(1);
#elif defined(PROBE_NO_PLL)
    put_str("probe: no PLL write\r\n");
#elif defined(PROBE_RAM)
    put_str("probe: unloaded DRAM word ");
    put_hex((uint32_t)&unloaded);
    put_str(" reads ");
    put_hex(*(volatile uint32_t *)&unloaded);
    put_str("\r\n");
#elif defined(PROBE_NARROW_IRAM)
    put_str("probe: 8-bit load from IRAM\r\n");
    put_hex(*(volatile uint8_t *)_start);
    put_str(" read: no exception\r\n");
#elif defined(PROBE_NARROW_FLASH)
    REG(SPI0_CTRL) |= 1u << 23;                 /* DIO */
    REG(DPORT_SPI_CACHE) |= 1u << 8;            /* the cache on */
    put_str("probe: 32-bit load from flash reads ");
    put_hex(REG(FLASH_MAPPED));
    put_str("\r\nprobe: 16-bit load from flash\r\n");
    put_hex(*(volatile uint16_t *)FLASH_MAPPED);
    put_str(" read: no exception\r\n");
#else
#error "one PROBE_* mode"
#endif
    spin();
}
