//! Deterministic random numbers for the passes and the BRDF checks (ARCHITECTURE.md,
//! "Conventions", seeds), with no dependency beyond glam.
//!
//! - [`hash`] and [`SplitMix64`]: SplitMix64 (Steele, Lea & Flood 2014), a counter-based
//!   generator whose state is a plain `u64`, so a stream can be derived from any tuple of ids
//!   (seed, pixel, sample; seed, vertex, patch) and nothing is shared between threads. The
//!   tracer's per-pixel samplers and radiosity's visibility jitter use it.
//! - [`Pcg32`]: PCG32 for the BRDF checks (chi-square and plausibility probes), whose fixed
//!   seeds and published statistics are tied to its sequence.
//!
//! The generated benchmark scenes and ray batches of `twopass_scene::workload` draw from
//! `rand_pcg`'s `Pcg64Mcg` through `rand` instead: the scene crate may depend on more than
//! glam, and this crate may not.

use glam::Vec2;

/// The golden-ratio increment of SplitMix64, 2^64 / phi.
pub const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// The SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A counter-based hash: the first output of a SplitMix64 stream started at `x`. Random bits
/// from (seed, ids) that do not depend on thread scheduling.
#[inline]
pub fn hash(x: u64) -> u64 {
    mix64(x.wrapping_add(GOLDEN))
}

/// The top 24 bits of `bits` as a uniform float in [0, 1) (every value exactly representable,
/// never 1.0).
#[inline]
pub fn unit_f32(bits: u64) -> f32 {
    (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The top 24 bits of `bits` as a uniform float in [0, 1): `rand`'s `f32` and PCG32's.
#[inline]
pub fn unit_f32_of_u32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The top 53 bits of `bits` as a uniform double in [0, 1): `rand`'s `f64`.
#[inline]
pub fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A SplitMix64 stream: 64 random bits per step, state advanced by [`GOLDEN`].
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The stream whose state starts at `state` (its first output is [`hash`]`(state)`).
    pub fn new(state: u64) -> Self {
        Self { state }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(self.state)
    }

    /// A uniform number in [0, 1) with 24 random bits ([`unit_f32`]).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u64())
    }
}

/// A small seeded generator (PCG32, O'Neill 2014, XSH-RR output) so that the checks need no
/// dependency and give the same numbers everywhere.
#[derive(Debug, Clone)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MUL: u64 = 6364136223846793005;

    /// A generator for `seed` on stream `stream`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut g = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(seed);
        g.next_u32();
        g
    }

    /// The next 32 uniformly distributed bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in [0, 1) with 24 random bits ([`unit_f32_of_u32`]).
    pub fn next_f32(&mut self) -> f32 {
        unit_f32_of_u32(self.next_u32())
    }

    /// A uniform point in [0, 1)^2.
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64 seeded with 0: the reference implementation of Steele, Lea & Flood, as used
    /// to seed xoshiro.
    const SPLITMIX64_SEED_0: [u64; 3] = [
        0xe220_a839_7b1d_cdaf,
        0x6e78_9e6a_a1b9_65f4,
        0x06c4_5d18_8009_454f,
    ];

    /// Asserts that a generator's first outputs are the `published` ones.
    #[track_caller]
    fn assert_stream<T: PartialEq + std::fmt::Debug>(next: impl FnMut() -> T, published: &[T]) {
        let ours: Vec<T> = std::iter::repeat_with(next).take(published.len()).collect();
        assert_eq!(ours, published);
    }

    #[test]
    fn splitmix64_matches_the_published_sequence() {
        let mut s = SplitMix64::new(0);
        assert_stream(|| s.next_u64(), &SPLITMIX64_SEED_0);
        assert_eq!(hash(0), SPLITMIX64_SEED_0[0]);
    }

    #[test]
    fn pcg32_matches_the_reference_implementation() {
        // O'Neill's pcg32-demo (pcg32_srandom_r(&rng, 42, 54)), first six outputs.
        let mut g = Pcg32::new(42, 54);
        let published = [
            0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e,
        ];
        assert_stream(|| g.next_u32(), &published);
    }

    #[test]
    fn unit_floats_stay_below_one() {
        assert_eq!(unit_f32(0), 0.0);
        assert!(unit_f32(u64::MAX) < 1.0);
        assert_eq!(unit_f32(1 << 63), 0.5);
        assert!(unit_f32_of_u32(u32::MAX) < 1.0);
        assert!(unit_f64(u64::MAX) < 1.0);
        assert_eq!(unit_f64(1 << 63), 0.5);
    }
}
