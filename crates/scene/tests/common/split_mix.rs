//! The seeded generator of the fuzz tests (`crates/scene/tests/fuzz_loaders.rs` and,
//! through `#[path]`, `crates/caustics/tests/fuzz_parsers.rs`): SplitMix64, the seeding
//! generator of xoshiro, written out so that the mutations need no dev-dependency. One
//! copy, so both tests draw the same kind of stream.

#![allow(dead_code, unreachable_pub)]

/// SplitMix64 (Steele, Lea & Flood 2014) with the helpers the mutators use.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (0 for `n` = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// One of `xs`.
    pub fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
}

/// The number in the environment variable `name`, else `default` (`FUZZ_SEED`,
/// `FUZZ_N`).
pub fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
