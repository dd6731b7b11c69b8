/*
 * The ROM's SPI flash routines (Espressif's eagle.rom.addr.v6.ld: SPIRead
 * 0x40004b1c, SPIWrite 0x40004a4c, SPIEraseSector 0x40004a00), written for
 * this board: they drive SPI0's command registers (emu/esp8266_flash.c) as
 * the NONOS SDK's spi_flash_read / spi_flash_write / spi_flash_erase_sector
 * document them ("ESP8266 Flash RW Operation"):
 *   - the result is SpiFlashOpResult: 0 OK, 1 ERR, 2 TIMEOUT;
 *   - addresses, buffers and sizes are 4-byte aligned, else ERR;
 *   - nothing past the chip's 4 MiB, else ERR;
 *   - a write does not erase: it can only clear bits (erase first);
 *   - SPIEraseSector takes a sector number (4 KiB sectors).
 * They read and write the flash with the cache's window unusable: the
 * caller disables the cache around them and runs from IRAM. A read moves
 * 32 bytes a command, a write up to 32 within a 256-byte page, each after
 * a write enable, and waits for the chip's WIP bit.
 */
#include <stdint.h>

#define SPI0                0x60000200u
#define SPI_CMD             (*(volatile uint32_t *)(SPI0 + 0x00))
#define SPI_ADDR            (*(volatile uint32_t *)(SPI0 + 0x04))
#define SPI_RD_STATUS       (*(volatile uint32_t *)(SPI0 + 0x10))
#define SPI_W(i)            (*(volatile uint32_t *)(SPI0 + 0x40 + 4 * (i)))

#define CMD_READ            (1u << 31)
#define CMD_WREN            (1u << 30)
#define CMD_RDSR            (1u << 27)
#define CMD_PP              (1u << 25)
#define CMD_SE              (1u << 24)

#define CHIP_BYTES          0x400000u
#define CHUNK               32u
#define PAGE                256u
/* polls before TIMEOUT: far beyond a sector erase's 400 ms maximum */
#define WAIT_LIMIT          20000000u

enum { OK = 0, ERR = 1, TIMEOUT = 2 };

/* Runs one command and waits for SPI_CMD to read 0. */
static int command(uint32_t cmd)
{
    uint32_t n;

    SPI_CMD = cmd;
    for (n = 0; SPI_CMD != 0; n++) {
        if (n == WAIT_LIMIT) {
            return TIMEOUT;
        }
    }
    return OK;
}

/* Waits for the chip's write in progress (status bit 0) to clear. */
static int wait_ready(void)
{
    uint32_t n;

    for (n = 0; n < WAIT_LIMIT; n++) {
        SPI_ADDR = 0;
        if (command(CMD_RDSR) != OK) {
            return TIMEOUT;
        }
        if ((SPI_RD_STATUS & 1) == 0) {
            return OK;
        }
    }
    return TIMEOUT;
}

static int write_enable(void)
{
    SPI_ADDR = 0;
    return command(CMD_WREN);
}

static int bad(uint32_t addr, uint32_t ptr, uint32_t size)
{
    return (addr | ptr | size) & 3 || addr >= CHIP_BYTES || size > CHIP_BYTES - addr;
}

int rom_spi_read(uint32_t addr, uint32_t *dst, uint32_t size)
{
    if (bad(addr, (uint32_t)dst, size)) {
        return ERR;
    }
    while (size) {
        uint32_t n = size < CHUNK ? size : CHUNK, i;
        int r;

        if ((r = wait_ready()) != OK) {
            return r;
        }
        SPI_ADDR = addr | n << 24;
        if ((r = command(CMD_READ)) != OK) {
            return r;
        }
        for (i = 0; i < n / 4; i++) {
            *dst++ = SPI_W(i);
        }
        addr += n;
        size -= n;
    }
    return OK;
}

int rom_spi_write(uint32_t addr, const uint32_t *src, uint32_t size)
{
    if (bad(addr, (uint32_t)src, size)) {
        return ERR;
    }
    while (size) {
        uint32_t page_left = PAGE - (addr & (PAGE - 1));
        uint32_t n = size < CHUNK ? size : CHUNK, i;
        int r;

        n = n < page_left ? n : page_left;
        if ((r = wait_ready()) != OK || (r = write_enable()) != OK) {
            return r;
        }
        for (i = 0; i < n / 4; i++) {
            SPI_W(i) = *src++;
        }
        SPI_ADDR = addr | n << 24;
        if ((r = command(CMD_PP)) != OK) {
            return r;
        }
        addr += n;
        size -= n;
    }
    return wait_ready();
}

int rom_spi_erase_sector(uint32_t sector)
{
    int r;

    if (sector >= CHIP_BYTES / 4096) {
        return ERR;
    }
    if ((r = wait_ready()) != OK || (r = write_enable()) != OK) {
        return r;
    }
    SPI_ADDR = sector * 4096;
    if ((r = command(CMD_SE)) != OK) {
        return r;
    }
    return wait_ready();
}
