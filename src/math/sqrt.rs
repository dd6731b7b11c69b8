//! Integer square roots, without a division.

/// Defines an integer square root (floor) over one unsigned type, without
/// division: bit by bit, one round per result bit.
macro_rules! isqrt_of {
    ($(#[$doc:meta])* $name:ident, $t:ty) => {
        $(#[$doc])*
        pub fn $name(v: $t) -> u32 {
            let (mut rem, mut root): ($t, $t) = (v, 0);
            let mut bit: $t = 1 << (<$t>::BITS - 2);
            while bit > rem {
                bit >>= 2;
            }
            while bit != 0 {
                if rem >= root + bit {
                    rem -= root + bit;
                    root = (root >> 1) + bit;
                } else {
                    root >>= 1;
                }
                bit >>= 2;
            }
            root as u32 // the root of a u64 is below 2^32
        }
    };
}

isqrt_of!(
    /// Integer square root (floor) of a `u32`, no division: 16 rounds.
    isqrt,
    u32
);
isqrt_of!(
    /// Integer square root (floor) of a `u64`, no division: 32 rounds.
    isqrt64,
    u64
);
