//! The tests' seeded PRNG is the simulator's (xorshift64*), so random tests
//! are repeatable and there is one generator in the project.

pub use paperbot::sim::noise::Rng;
