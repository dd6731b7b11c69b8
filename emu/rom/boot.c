/*
 * The board's mask ROM, part 2: the boot from flash and the report of an
 * exception taken at the ROM's vectors. Modelled on what Espressif's ROM
 * loader does and prints (the ESP8266 boot messages: "ets Jan  8 2013,rst
 * cause:N, boot mode:(M,N)" at 74880 baud, then a "load 0x..., len ..."
 * line per segment and "csum 0x.."), written for this board; the ROM's own
 * code is not available.
 *
 *   1. UART0's divider for 115200 baud at 80 MHz; the CPU runs at 52 MHz
 *      until the firmware's PLL write, so the lines go out at 74880 baud;
 *   2. the banner: the reset cause (RTC 0x60000714, the board's) and the
 *      boot mode from the strapping pins (GPIO_IN bits 16..18, latched at
 *      reset); anything but 3 (flash) runs nothing: 1 is UART download mode;
 *   3. the flash cache on, in the slow read mode every flash answers; the
 *      esptool "version 1" boot image at flash offset 0: an 8-byte header
 *      (magic 0xE9, segment count, flash mode, size/frequency, entry), then
 *      each segment as load address, length, data; zero padding up to the
 *      last byte of a 16-byte block, which holds the checksum (0xEF XOR
 *      every data byte). After the header, the rest is read in the header's
 *      flash mode (SPI0 CTRL): a mode the board's flash does not answer
 *      reads as all ones, and the image fails its checks;
 *   4. each segment copied to its address, the checksum checked;
 *   5. the cache off again, UART0 drained, its TX-FIFO-empty interrupt left
 *      enabled (asserted from then on: the FIFO is empty); reset.S hands
 *      over to the entry with that interrupt among INTENABLE's bits. What
 *      Espressif's ROM leaves in UART0 is not documented: this is the
 *      board's worst case, so that a foreign INTENABLE bit bites.
 *
 * The flash is read in 32-bit words only: the cache window takes no
 * narrower load (see the board's narrow-load check).
 */
#include <stdint.h>

#define REG(addr)           (*(volatile uint32_t *)(addr))
#define UART0_FIFO          0x60000000u
#define UART0_CLKDIV        0x60000014u
#define UART0_STATUS        0x6000001cu
#define UART0_INT_ENA       0x6000000cu
#define UART_TXFIFO_EMPTY   (1u << 1)
#define SPI0_CTRL           0x60000208u
#define GPIO_IN             0x60000318u
#define RTC_RESET_CAUSE     0x60000714u
#define DPORT_SPI_CACHE     0x3ff0000cu
#define FLASH_MAPPED        0x40200000u

#define ROM_ASSUMED_HZ      80000000u   /* a 40 MHz crystal's PLL clock */
#define BOOT_BAUD           115200u
#define SPI_CACHE_ENABLE    (1u << 8)
#define SPI_CTRL_DOUT       (1u << 14)
#define SPI_CTRL_QOUT       (1u << 20)
#define SPI_CTRL_DIO        (1u << 23)
#define SPI_CTRL_QIO        (1u << 24)
#define SPI_CTRL_MODES      (SPI_CTRL_DOUT | SPI_CTRL_QOUT | SPI_CTRL_DIO | SPI_CTRL_QIO)
#define IMAGE_MAGIC         0xe9u
#define CHECKSUM_SEED       0xefu
#define BOOT_MODE_UART      1u
#define BOOT_MODE_FLASH     3u
#define TX_FIFO_ROOM        126u

static void put_char(char c)
{
    while (((REG(UART0_STATUS) >> 16) & 0xff) >= TX_FIFO_ROOM) {
    }
    REG(UART0_FIFO) = (uint8_t)c;
}

static void put_str(const char *s)
{
    while (*s) {
        put_char(*s++);
    }
}

static void put_hex(uint32_t v, int digits)
{
    put_str("0x");
    for (int i = digits - 1; i >= 0; i--) {
        put_char("0123456789abcdef"[(v >> (4 * i)) & 0xf]);
    }
}

/* Decimal without a division (the lx106 has none, and the ROM links no
 * library): powers of ten subtracted. */
static void put_dec(uint32_t v)
{
    static const uint32_t tens[] = {
        1000000000u, 100000000u, 10000000u, 1000000u, 100000u, 10000u,
        1000u, 100u, 10u, 1u,
    };
    int started = 0;

    for (unsigned i = 0; i < sizeof(tens) / sizeof(tens[0]); i++) {
        char d = '0';
        while (v >= tens[i]) {
            v -= tens[i];
            d++;
        }
        if (d != '0' || started || tens[i] == 1) {
            put_char(d);
            started = 1;
        }
    }
}

static void drain_uart(void)
{
    while ((REG(UART0_STATUS) >> 16) & 0xff) {
    }
}

static void __attribute__((noreturn)) stop(const char *why)
{
    put_str(why);
    drain_uart();
    for (;;) {
        __asm__ volatile("waiti 15");
    }
}

static uint32_t flash_word(uint32_t offset)
{
    return REG(FLASH_MAPPED + offset);
}

static uint32_t spi_mode_bits(uint32_t header_mode)
{
    static const uint32_t bits[] = {
        SPI_CTRL_QIO, SPI_CTRL_QOUT, SPI_CTRL_DIO, SPI_CTRL_DOUT,
    };
    return bits[header_mode];
}

/* Steps 1..5 above; returns the entry. */
uint32_t rom_boot(void)
{
    uint32_t mode, header, entry, segments, at, sum = 0;

    REG(UART0_CLKDIV) = ROM_ASSUMED_HZ / BOOT_BAUD;
    mode = (REG(GPIO_IN) >> 16) & 7;
    put_str("\r\n ets Jan  8 2013,rst cause:");
    put_dec(REG(RTC_RESET_CAUSE));
    put_str(", boot mode:(");
    put_dec(mode);
    put_str(",6)\r\n\r\n");
    if (mode == BOOT_MODE_UART) {
        stop("waiting for host\r\n");
    }
    if (mode != BOOT_MODE_FLASH) {
        stop("rom: not a flash boot mode; nothing runs\r\n");
    }

    REG(SPI0_CTRL) &= ~SPI_CTRL_MODES;
    REG(DPORT_SPI_CACHE) |= SPI_CACHE_ENABLE;
    header = flash_word(0);
    entry = flash_word(4);
    if ((header & 0xff) != IMAGE_MAGIC) {
        stop("rom: no boot image at flash offset 0 (magic is not 0xE9)\r\n");
    }
    if (((header >> 16) & 0xff) > 3) {
        stop("rom: unknown flash mode in the boot image header\r\n");
    }
    REG(SPI0_CTRL) |= spi_mode_bits((header >> 16) & 0xff);

    segments = (header >> 8) & 0xff;
    at = 8;
    while (segments--) {
        uint32_t load = flash_word(at), len = flash_word(at + 4);
        volatile uint32_t *to = (volatile uint32_t *)load;

        put_str("load ");
        put_hex(load, 8);
        put_str(", len ");
        put_dec(len);
        put_str("\r\n");
        if (len & 3) {
            stop("rom: boot image segment length is not a multiple of 4\r\n");
        }
        at += 8;
        for (uint32_t i = 0; i < len / 4; i++, at += 4) {
            uint32_t w = flash_word(at);
            to[i] = w;
            sum ^= w;
        }
    }
    sum ^= sum >> 16;
    sum ^= sum >> 8;
    sum = (sum ^ CHECKSUM_SEED) & 0xff;
    at |= 15;   /* the checksum: the last byte of the 16-byte block */
    put_str("csum ");
    put_hex(sum, 2);
    put_str("\r\n");
    if (((flash_word(at & ~3u) >> (8 * (at & 3))) & 0xff) != sum) {
        stop("csum err\r\n");
    }
    REG(DPORT_SPI_CACHE) &= ~SPI_CACHE_ENABLE;
    drain_uart();
    REG(UART0_INT_ENA) = UART_TXFIFO_EMPTY;
    return entry;
}

static const char *cause_name(uint32_t cause)
{
    switch (cause) {
    case 0: return "IllegalInstruction";
    case 2: return "InstructionFetchError";
    case 3: return "LoadStoreError";
    case 4: return "Level1Interrupt";
    case 9: return "LoadStoreAlignment";
    case 12: return "InstrPIFDataError";
    case 13: return "LoadStorePIFDataError";
    case 14: return "InstrPIFAddrError";
    case 15: return "LoadStorePIFAddrError";
    case 20: return "InstFetchProhibited";
    case 28: return "LoadProhibited";
    case 29: return "StoreProhibited";
    default: return "other";
    }
}

/* An exception or interrupt at the ROM's vectors (VECBASE 0x40000000: the
 * image has not moved it yet). `vector`: a name from reset.S; a double
 * exception (one taken with PS.EXCM set) keeps its PC in DEPC, not EPC1. */
void __attribute__((noreturn)) rom_exception(const char *vector, int is_double)
{
    uint32_t cause, pc, excvaddr;

    __asm__ volatile("rsr %0, exccause" : "=r"(cause));
    if (is_double) {
        __asm__ volatile("rsr %0, depc" : "=r"(pc));
    } else {
        __asm__ volatile("rsr %0, epc1" : "=r"(pc));
    }
    __asm__ volatile("rsr %0, excvaddr" : "=r"(excvaddr));
    put_str("\r\nrom: ");
    put_str(vector);
    put_str(" exception at the ROM's vectors: EXCCAUSE ");
    put_dec(cause);
    put_str(" (");
    put_str(cause_name(cause));
    put_str(is_double ? "), DEPC " : "), EPC1 ");
    put_hex(pc, 8);
    put_str(", EXCVADDR ");
    put_hex(excvaddr, 8);
    stop("\r\n");
}
