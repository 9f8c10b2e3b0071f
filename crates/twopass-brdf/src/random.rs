//! Deterministic random numbers, the one home of the workspace's generators (ARCHITECTURE.md,
//! "Conventions", seeds).
//!
//! - [`hash`] and [`SplitMix64`]: SplitMix64 (Steele, Lea & Flood 2014), a counter-based
//!   generator whose state is a plain `u64`, so a stream can be derived from any tuple of ids
//!   (seed, pixel, sample; seed, vertex, patch) and nothing is shared between threads. The
//!   tracer's per-pixel samplers and radiosity's visibility jitter use it.
//! - [`Pcg32`]: PCG32 for the BRDF checks (chi-square and plausibility probes), whose fixed
//!   seeds and published statistics are tied to its sequence.
//! - [`Pcg64Mcg`]: PCG64 "fast" (128-bit multiplicative generator, XSL-RR output) for the
//!   generated benchmark scenes and ray batches of `twopass_scene::workload`. It reproduces
//!   `rand_pcg` 0.9's `Pcg64Mcg` seeded by `rand_core` 0.9's `seed_from_u64`, and `rand` 0.9's
//!   conversions to floats, booleans and ranges, bit for bit, so the workloads (and the
//!   published ray-rate figures measured on them) did not change when `rand` was dropped.

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

/// PCG64 "fast" (O'Neill 2014's `pcg64_fast`, `rand_pcg`'s `Mcg128Xsl64`): a 128-bit
/// multiplicative congruential generator with the XSL-RR 128/64 output, and the conversions of
/// `rand` 0.9 on top, so that a stream seeded here equals `Pcg64Mcg::seed_from_u64(seed)` drawn
/// through `rand::Rng` (see the module documentation for why that matters).
#[derive(Debug, Clone)]
pub struct Pcg64Mcg {
    state: u128,
}

impl Pcg64Mcg {
    const MUL: u128 = 0x2360_ED05_1FC6_5DA4_4385_DF64_9FCC_F645;

    /// The generator of PCG's own seeding, `state` with its low bit forced to 1.
    pub fn new(state: u128) -> Self {
        Self { state: state | 1 }
    }

    /// The generator `rand_core` 0.9's `SeedableRng::seed_from_u64(seed)` builds: its 16 seed
    /// bytes are four outputs of a PCG32 stream (fixed increment, advanced before each output)
    /// started at `seed`, read as a little-endian `u128`.
    pub fn seed_from_u64(seed: u64) -> Self {
        const INC: u64 = 11_634_580_027_462_260_723;
        let mut seeder = Pcg32 {
            state: seed.wrapping_mul(Pcg32::MUL).wrapping_add(INC),
            inc: INC,
        };
        let state = (0..4).fold(0u128, |acc, i| {
            acc | u128::from(seeder.next_u32()) << (32 * i)
        });
        Self::new(state)
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_mul(Self::MUL);
        let rot = (self.state >> 122) as u32;
        (((self.state >> 64) as u64) ^ (self.state as u64)).rotate_right(rot)
    }

    /// The next 32 random bits: the low half of [`Pcg64Mcg::next_u64`] (as `rand_pcg`).
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.next_u64() as u32
    }

    /// A uniform float in [0, 1) with 24 random bits (`rand`'s `random::<f32>()`).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32_of_u32(self.next_u32())
    }

    /// A uniform double in [0, 1) with 53 random bits (`rand`'s `random::<f64>()`).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// A uniform point in [0, 1)^2, x drawn first.
    #[inline]
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }

    /// A fair coin: the top bit of [`Pcg64Mcg::next_u32`] (`rand`'s `random::<bool>()`).
    #[inline]
    pub fn next_bool(&mut self) -> bool {
        self.next_u32() >> 31 == 1
    }

    /// A nearly uniform integer in `0..n`, `n > 0` (`rand` 0.9's `random_range(0..n)` for a
    /// range that fits in 32 bits: Canon's widening multiply, with one more draw when the low
    /// half says the first could be biased; bias below 2^-32).
    pub fn below(&mut self, n: u32) -> u32 {
        debug_assert!(n > 0, "empty range");
        let wide = u64::from(self.next_u32()) * u64::from(n);
        let (mut result, low) = ((wide >> 32) as u32, wide as u32);
        if low > n.wrapping_neg() {
            let more = ((u64::from(self.next_u32()) * u64::from(n)) >> 32) as u32;
            result += u32::from(low.checked_add(more).is_none());
        }
        result
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

    /// The PCG C test suite's pcg64f (pcg64_fast) for state 42, as rand_pcg pins it.
    const PCG64_FAST_STATE_42: [u64; 6] = [
        0x63b4_a3a8_13ce_700a,
        0x3829_5420_0617_ab24,
        0xa7fd_85ae_3fe9_50ce,
        0xd715_286a_a288_7737,
        0x60c9_2fee_2e59_f32c,
        0x84c4_e96b_eff3_0017,
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
    fn pcg64_fast_matches_the_reference_implementation() {
        let mut g = Pcg64Mcg::new(42);
        assert_stream(|| g.next_u64(), &PCG64_FAST_STATE_42);
    }

    #[test]
    fn pcg64_fast_seeds_as_rand_core() {
        // rand_pcg's own test: Pcg64Mcg::seed_from_u64(0).next_u64().
        assert_eq!(
            Pcg64Mcg::seed_from_u64(0).next_u64(),
            6_198_063_878_555_692_194
        );
    }

    #[test]
    fn below_stays_in_range() {
        let mut g = Pcg64Mcg::seed_from_u64(1);
        for n in [1, 2, 3, 7, 1000, u32::MAX] {
            assert!((0..100).all(|_| g.below(n) < n));
        }
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
