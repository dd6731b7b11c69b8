//! What a lidar reading describes in the test worlds: the body two loop
//! ticks before it is read. The chip measures over its 33 ms budget and
//! the loop polls once a tick (`config::lidar::READING_AGE_US`, 21.5 ms);
//! the realistic simulator's chip reports the distance set nearest the
//! middle of its measurement, mostly two ticks back (`sim::vl53l0x`).

/// Ticks between the body a reading describes and the tick it is read at.
pub const TICKS: usize = 2;

/// The body's last poses, oldest first: the first is what a reading taken
/// now describes.
#[derive(Clone, Copy, Debug)]
pub struct Lagged<P: Copy>([P; TICKS + 1]);

impl<P: Copy> Lagged<P> {
    /// Standing at `start` so far.
    pub fn new(start: P) -> Lagged<P> {
        Lagged([start; TICKS + 1])
    }

    /// After a tick, at `p`.
    pub fn push(&mut self, p: P) {
        self.0.rotate_left(1);
        self.0[TICKS] = p;
    }

    /// The pose a reading taken now describes.
    pub fn read(&self) -> P {
        self.0[0]
    }
}
