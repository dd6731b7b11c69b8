//! I2C bus and addresses (7-bit).

/// Both VL53L0X boot at 0x29 (VL53L0X datasheet; fact sheet).
pub const LIDAR_DEFAULT_ADDR: u8 = 0x29;
/// Front lidar after bring-up (the course sketch's 22, decimal; fact sheet).
pub const FRONT_LIDAR_ADDR: u8 = 0x16;
/// Right lidar after bring-up (the course sketch's 25, decimal; fact sheet).
pub const RIGHT_LIDAR_ADDR: u8 = 0x19;
/// MPU9250 (AD0 low; MPU-9250 datasheet, fact sheet).
pub const MPU9250_ADDR: u8 = 0x68;
/// AK8963 once the MPU9250 is in bypass mode (fact sheet).
pub const AK8963_ADDR: u8 = 0x0C;
/// Bus clock, Hz: fast mode (UM10204), which the VL53L0X and the MPU9250
/// support (their datasheets).
pub const FREQUENCY_HZ: u32 = 400_000;
/// Longest a slave may stretch the clock before the transfer fails, us: a
/// choice (UM10204 sets no limit) that bounds how long one transfer may
/// block the loop, 400 bit periods at 400 kHz.
pub const CLOCK_STRETCH_TIMEOUT_US: u32 = 1_000;
/// Shortest SCL low phase, ns: fast mode tLOW >= 1.3 us (I2C spec
/// UM10204 table 10). The bit-banged master makes the low phase at least
/// this long and gives the rest of the bit period to the high phase.
pub const T_LOW_MIN_NS: u32 = 1_300;
/// Shortest SCL high phase, ns: fast mode tHIGH >= 0.6 us (UM10204 table 10).
pub const T_HIGH_MIN_NS: u32 = 600;
/// Bus-free time between a STOP and the next START, ns: fast mode
/// tBUF >= 1.3 us (UM10204 table 10).
pub const T_BUF_MIN_NS: u32 = 1_300;
/// Clock pulses sent to free a slave that holds SDA low (UM10204 3.1.16:
/// nine clocks, then STOP).
pub const RECOVERY_CLOCKS: u8 = 9;
/// Times a failed transaction is run again before the driver sees the
/// error (`driver::bus::Retry`), count. Source: the fault runs
/// (tests/control/faults_long.rs): a lidar bring-up is ~110 transactions, so
/// without retries it got through a bus with 1 % faulty transactions
/// about one try in three; with 2 retries a transaction fails only when
/// three attempts in a row do (1e-6 at 1 %, 4e-4 at 10 % of which 3/4
/// fail loudly), so a bring-up gets through a 10 % bus ~19 times in 20.
/// Each retry costs one transaction (~0.1 ms at 400 kHz).
pub const TRANSACTION_RETRIES: u8 = 2;
