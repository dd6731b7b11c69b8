/*
 * esp8266_flash: the SPI flash chip behind SPI0's command registers, as the
 * ROM's SPIRead / SPIWrite / SPIEraseSector (emu/rom/flash.c) drive it.
 *
 * SPI0 (0x60000200; Espressif's spi_register.h, the esp8266 PAC): SPI_CMD
 * (+0x00) starts a command by setting its bit and clears the bit when the
 * command is done; SPI_ADDR (+0x04) holds the address in bits 0..23 and
 * the byte count of a read or page program in bits 24..31 (at most 64, the
 * W0..W15 buffer at +0x40); SPI_RD_STATUS (+0x10) takes the status register
 * of RDSR (bit 0 WIP, bit 1 WEL). The chip (a 25-series SPI NOR flash, e.g.
 * the GD25Q32 / W25Q32 of ESP-12 modules, 4 MiB): READ any bytes; WREN sets
 * the write-enable latch; PAGE PROGRAM and SECTOR ERASE are ignored without
 * it and clear it; a program only clears bits (a 1 written leaves the bit,
 * a 0 clears it) and wraps within its 256-byte page; an erase sets a whole
 * 4 KiB sector to 0xff. SPI0 finishes each command at once (SPI_CMD reads
 * 0), but the chip stays busy after a program or an erase for its typical
 * time (Winbond W25Q32JV datasheet, AC characteristics: tPP 0.4 ms, tSE
 * 45 ms) in virtual time: RDSR's WIP bit reads 1 meanwhile, and any other
 * command is ignored, as a busy chip does.
 *
 * The contents are the flash file (flash=FILE), kept: every program and
 * erase is written back to the file, so a new run on the same file finds
 * it (a power-cycle). flash-power-ops=N: the power fails before the N+1th
 * program or erase, which does not happen, and the board stops as at a
 * power cut (QEMU exits; `stopped: power cut` in the events).
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/error-report.h"
#include "sysemu/runstate.h"
#include "esp8266.h"

#define SPI_CMD             0x00
#define SPI_ADDR            0x04
#define SPI_RD_STATUS       0x10
#define SPI_W0              0x40
#define SPI_BUF_BYTES       64

#define CMD_READ            (1u << 31)
#define CMD_WREN            (1u << 30)
#define CMD_RDSR            (1u << 27)
#define CMD_PP              (1u << 25)
#define CMD_SE              (1u << 24)

#define STATUS_WIP          (1u << 0)
#define STATUS_WEL          (1u << 1)
#define PAGE_PROGRAM_NS     (400 * SCALE_US)
#define SECTOR_ERASE_NS     (45 * SCALE_MS)
#define PAGE_BYTES          256u
#define SECTOR_BYTES        4096u

/* The contents from the file (the rest erased) and the window's first MiB. */
void flash_chip_load(Esp8266State *s, const uint8_t *data, size_t len)
{
    s->flash_data = g_malloc(FLASH_CHIP_SIZE);
    memset(s->flash_data, 0xff, FLASH_CHIP_SIZE);
    memcpy(s->flash_data, data, MIN(len, (size_t)FLASH_CHIP_SIZE));
    s->flash_file_len = len;
}

/* Writes [off, off + len) back to the file (extending it, erased, first). */
static void flash_persist(Esp8266State *s, uint32_t off, uint32_t len)
{
    int fd;
    size_t end = (size_t)off + len;

    if (!s->flash_path) {
        return;
    }
    fd = open(s->flash_path, O_WRONLY);
    if (fd < 0) {
        error_report("esp8266: flash=%s: cannot write back: %s", s->flash_path, strerror(errno));
        return;
    }
    if (end > s->flash_file_len) {
        /* the bytes between the file's end and `off` are erased flash */
        off = MIN(off, (uint32_t)s->flash_file_len);
        len = end - off;
        s->flash_file_len = end;
    }
    if (pwrite(fd, s->flash_data + off, len, off) != (ssize_t)len) {
        error_report("esp8266: flash=%s: short write back", s->flash_path);
    }
    close(fd);
}

/* The window the cache reads shows the chip's first MiB. */
static void flash_refresh_window(Esp8266State *s, uint32_t off, uint32_t len)
{
    uint8_t *window = memory_region_get_ram_ptr(&s->flash_mr);

    if (off < FLASH_MAP_SIZE) {
        memcpy(window + off, s->flash_data + off, MIN(len, FLASH_MAP_SIZE - off));
    }
}

/* One more program or erase on the power left; false: the power is gone. */
static bool flash_power(Esp8266State *s)
{
    if (s->flash_power_ops == UINT32_MAX) {
        return true;
    }
    if (s->flash_power_ops == 0) {
        log_event(s, "stopped: power cut");
        error_report("esp8266: power cut before a flash program or erase (flash-power-ops)");
        qemu_system_shutdown_request(SHUTDOWN_CAUSE_GUEST_SHUTDOWN);
        return false;
    }
    s->flash_power_ops--;
    return true;
}

static void flash_command(Esp8266State *s, uint32_t cmd)
{
    uint32_t a = s->spi0.regs[SPI_ADDR / 4];
    uint32_t addr = (a & 0xffffff) % FLASH_CHIP_SIZE;
    uint32_t n = MIN(a >> 24, (uint32_t)SPI_BUF_BYTES);
    uint8_t *buf = (uint8_t *)&s->spi0.regs[SPI_W0 / 4];
    uint32_t i;

    bool busy = now_ns() < s->flash_busy_until_ns;

    if (cmd & CMD_RDSR) {
        s->spi0.regs[SPI_RD_STATUS / 4] = (s->flash_wel ? STATUS_WEL : 0) | (busy ? STATUS_WIP : 0);
        return;
    }
    if (busy) {
        log_event(s, "flash-command-while-busy 0x%08x", cmd);
        return;
    }
    if (cmd & CMD_READ) {
        for (i = 0; i < n; i++) {
            buf[i] = s->flash_data[(addr + i) % FLASH_CHIP_SIZE];
        }
    } else if (cmd & CMD_WREN) {
        s->flash_wel = true;
    } else if (cmd & (CMD_PP | CMD_SE)) {
        if (!s->flash_wel) {
            log_event(s, "flash-%s-without-wren 0x%06x", cmd & CMD_PP ? "program" : "erase", addr);
        } else if (flash_power(s)) {
            if (cmd & CMD_PP) {
                uint32_t page = addr & ~(PAGE_BYTES - 1);
                for (i = 0; i < n; i++) {
                    s->flash_data[page + ((addr + i) & (PAGE_BYTES - 1))] &= buf[i];
                }
                flash_refresh_window(s, page, PAGE_BYTES);
                flash_persist(s, page, PAGE_BYTES);
                s->flash_busy_until_ns = now_ns() + PAGE_PROGRAM_NS;
                log_event(s, "flash-program 0x%06x %u", addr, n);
            } else {
                uint32_t sector = addr & ~(SECTOR_BYTES - 1);
                memset(s->flash_data + sector, 0xff, SECTOR_BYTES);
                flash_refresh_window(s, sector, SECTOR_BYTES);
                flash_persist(s, sector, SECTOR_BYTES);
                s->flash_busy_until_ns = now_ns() + SECTOR_ERASE_NS;
                log_event(s, "flash-erase 0x%06x", sector);
            }
        }
        s->flash_wel = false;
    }
}

/* SPI0's register file hook: a command bit starts it; done, SPI_CMD reads 0. */
void spi0_written(void *opaque)
{
    Esp8266State *s = opaque;
    uint32_t cmd = s->spi0.regs[SPI_CMD / 4];

    if (cmd & (CMD_READ | CMD_WREN | CMD_RDSR | CMD_PP | CMD_SE)) {
        flash_command(s, cmd);
        s->spi0.regs[SPI_CMD / 4] = 0;
    }
    flash_update_map(s);
}
