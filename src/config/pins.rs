//! Wiring: GPIO numbers (fact sheet, `docs/paperbot.md`; NodeMCU label in
//! brackets; docs/hardware.md has the table and the boot-strapping pins).

/// Left servo signal (D1).
pub const LEFT_SERVO_GPIO: u8 = 5;
/// Right servo signal (D2).
pub const RIGHT_SERVO_GPIO: u8 = 4;
/// I2C data (D5).
pub const SDA_GPIO: u8 = 14;
/// I2C clock (D6).
pub const SCL_GPIO: u8 = 12;
/// Front lidar XSHUT (D3).
pub const FRONT_XSHUT_GPIO: u8 = 0;
/// Right lidar XSHUT (D4).
pub const RIGHT_XSHUT_GPIO: u8 = 2;
/// On-board LED (D0).
pub const LED_GPIO: u8 = 16;
