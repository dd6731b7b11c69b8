//! Seeded noise for the simulator: a small PRNG (xorshift64*) and Gaussian
//! samples from it, so every simulated run is repeatable from its seed.
//!
//! Why not `rand`/`rand_distr`: their streams are not stable across
//! versions, and the simulator's tests and recorded runs must give the same
//! numbers for the same seed forever; twenty lines do it.

/// xorshift64* (Vigna 2016): 64-bit state, period 2^64 - 1.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        // splitmix-style scramble so seeds 0, 1, 2... give unrelated streams
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(f64::MIN_POSITIVE);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
    }
    /// Uniform in [lo, hi).
    pub fn range_f64(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// Uniform in lo..=hi (lo <= hi).
    pub fn range_u32(&mut self, lo: u32, hi: u32) -> u32 {
        let span = u64::from(hi.saturating_sub(lo)) + 1;
        lo.saturating_add((self.next_u64() % span) as u32)
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }
    /// Normal with standard deviation `sigma` (0 gives exactly 0 and draws nothing).
    pub fn gauss(&mut self, sigma: f64) -> f64 {
        if sigma == 0.0 {
            0.0
        } else {
            sigma * self.normal()
        }
    }
}
