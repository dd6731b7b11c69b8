/*
 * esp8266_gpio: GPIO0..15 (0x60000300) and GPIO16 of the paperbot ESP8266
 * board.
 *
 *   GPIO    ESP8266 Technical Reference (TRM), GPIO registers: OUT, ENABLE,
 *           their W1TS/W1TC, IN, PINn (PAD_DRIVER: open drain)
 *   GPIO16  RTC_GPIO_OUT/ENABLE/IN_DATA (RTC block 0x60000700; not in the
 *           TRM: the esp8266 PAC's SVD and Espressif's SDK gpio16 driver
 *           give the offsets); the rest of the RTC block: plain registers
 *
 * SPDX-License-Identifier: GPL-2.0-or-later
 */

#include "qemu/osdep.h"
#include "qemu/log.h"
#include "esp8266.h"

enum {
    GPIO_OUT = 0x00, GPIO_OUT_W1TS = 0x04, GPIO_OUT_W1TC = 0x08,
    GPIO_ENABLE = 0x0c, GPIO_ENABLE_W1TS = 0x10, GPIO_ENABLE_W1TC = 0x14,
    GPIO_IN = 0x18, GPIO_PIN0 = 0x28,
};
#define GPIO_PIN_PAD_DRIVER     (1u << 2)   /* 1: open drain */
#define GPIO_PIN_INT_TYPE(v)    (((v) >> 7) & 7)
#define GPIO_MASK               0xffffu

enum {
    RTC_GPIO_OUT = 0x68, RTC_GPIO_ENABLE = 0x74, RTC_GPIO_IN_DATA = 0x8c,
};

/*
 * The level on each pin. Nothing outside drives the pins (no I2C devices on
 * the bus), so a pin is high unless the chip drives it low: an enabled
 * push-pull pin shows its output bit, an enabled open-drain pin is low
 * while its output bit is 0 and released (pulled up) otherwise, and an
 * input floats high (the board's and the pads' pull-ups). GPIO16 (bit 16)
 * is push-pull when enabled.
 */
uint32_t gpio_driven_levels(Esp8266State *s)
{
    uint32_t levels = 0;

    for (int pin = 0; pin < NUM_GPIO; pin++) {
        bool enabled = (s->gpio_enable >> pin) & 1;
        bool out = (s->gpio_out >> pin) & 1;
        bool open_drain = s->gpio_pin[pin] & GPIO_PIN_PAD_DRIVER;
        bool driven_low = enabled && !out;
        bool driven_high = enabled && out && !open_drain;

        levels |= (uint32_t)(driven_high || !driven_low) << pin;
    }
    if (s->rtc_gpio_enable & 1) {
        levels |= (s->rtc_gpio_out & 1) << NUM_GPIO;
    } else {
        levels |= 1u << NUM_GPIO;
    }
    return levels;
}

/* With a simulator, its slaves can pull the I2C lines low too. */
uint32_t gpio_compute_levels(Esp8266State *s)
{
    return gpio_driven_levels(s) & ~s->ext_low;
}

/* Recompute the pin levels and log each change as an edge. */
void gpio_update(Esp8266State *s)
{
    uint32_t levels, changed;

    if (s->link) {
        link_note_pins(s, gpio_driven_levels(s));
    }
    levels = gpio_compute_levels(s);
    changed = levels ^ s->gpio_levels;

    s->gpio_levels = levels;
    for (int pin = 0; changed && pin <= NUM_GPIO; pin++) {
        if ((changed >> pin) & 1) {
            log_event(s, "gpio%d %u", pin, (levels >> pin) & 1);
        }
    }
}

static uint64_t gpio_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case GPIO_OUT:
        return s->gpio_out;
    case GPIO_ENABLE:
        return s->gpio_enable;
    case GPIO_IN:   /* bits 16..18: the boot mode latched at reset */
        link_refresh(s);
        return (s->gpio_levels & GPIO_MASK) | (s->boot_mode << 16);
    case GPIO_OUT_W1TS:
    case GPIO_OUT_W1TC:
    case GPIO_ENABLE_W1TS:
    case GPIO_ENABLE_W1TC:
        return 0;   /* write-only strobes */
    default:
        if (addr >= GPIO_PIN0 && addr < GPIO_PIN0 + 4 * NUM_GPIO) {
            return s->gpio_pin[(addr - GPIO_PIN0) / 4];
        }
        return regfile_read(&s->periph, GPIO_OFFSET + addr);
    }
}

static void gpio_write_pin_conf(Esp8266State *s, unsigned pin, uint32_t v)
{
    if (GPIO_PIN_INT_TYPE(v)) {
        qemu_log_mask(LOG_UNIMP, "esp8266: GPIO%u pin interrupts are not "
                      "modelled\n", pin);
    }
    s->gpio_pin[pin] = v;
}

static void gpio_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case GPIO_OUT:
        s->gpio_out = v & GPIO_MASK;
        break;
    case GPIO_OUT_W1TS:
        s->gpio_out |= v & GPIO_MASK;
        break;
    case GPIO_OUT_W1TC:
        s->gpio_out &= ~v;
        break;
    case GPIO_ENABLE:
        s->gpio_enable = v & GPIO_MASK;
        break;
    case GPIO_ENABLE_W1TS:
        s->gpio_enable |= v & GPIO_MASK;
        break;
    case GPIO_ENABLE_W1TC:
        s->gpio_enable &= ~v;
        break;
    default:
        if (addr >= GPIO_PIN0 && addr < GPIO_PIN0 + 4 * NUM_GPIO) {
            gpio_write_pin_conf(s, (addr - GPIO_PIN0) / 4, v);
        } else {
            regfile_write(&s->periph, GPIO_OFFSET + addr, v);
        }
        return;
    }
    gpio_update(s);
}

const MemoryRegionOps gpio_ops = {
    .read = gpio_read,
    .write = gpio_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

/* The RTC block: GPIO16's registers modelled, the rest plain storage. */
static uint64_t rtc_read(void *opaque, hwaddr addr, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case RTC_GPIO_OUT:
        return s->rtc_gpio_out;
    case RTC_GPIO_ENABLE:
        return s->rtc_gpio_enable;
    case RTC_GPIO_IN_DATA:
        return (s->gpio_levels >> NUM_GPIO) & 1;
    default:
        return regfile_read(&s->rtc, addr);
    }
}

static void rtc_write(void *opaque, hwaddr addr, uint64_t v, unsigned size)
{
    Esp8266State *s = opaque;

    switch (addr) {
    case RTC_GPIO_OUT:
        s->rtc_gpio_out = v;
        gpio_update(s);
        break;
    case RTC_GPIO_ENABLE:
        s->rtc_gpio_enable = v;
        gpio_update(s);
        break;
    default:
        regfile_write(&s->rtc, addr, v);
    }
}

const MemoryRegionOps rtc_ops = {
    .read = rtc_read,
    .write = rtc_write,
    .endianness = DEVICE_LITTLE_ENDIAN,
    .impl = { .min_access_size = 4, .max_access_size = 4 },
};

void gpio_reset(Esp8266State *s)
{
    s->gpio_out = s->gpio_enable = 0;
    memset(s->gpio_pin, 0, sizeof(s->gpio_pin));
    s->rtc_gpio_out = s->rtc_gpio_enable = 0;
    gpio_update(s);
}
