//! Deterministic random numbers: one independent stream per (seed, pixel, sample), so an image
//! does not depend on which thread rendered which pixel, or in which order.
//!
//! The generator is SplitMix64 (Steele, Lea & Flood 2014, [`twopass_brdf::random`], the
//! workspace's one home of random streams) over a state derived by hashing the three
//! indices: statistically independent streams for neighbouring pixels and samples, and nothing that
//! a rayon job could share (ARCHITECTURE.md, "Conventions": never keep RNG state in `map_init`).

use twopass_brdf::random::{SplitMix64, hash, mix64};

/// A stream of uniform numbers in [0, 1) for one camera sample of one pixel.
#[derive(Debug, Clone)]
pub struct Sampler {
    stream: SplitMix64,
}

impl Sampler {
    /// The stream of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let h = hash(seed);
        let h = mix64(h ^ pixel.wrapping_mul(0xd6e8_feb8_6659_fd93));
        let h = mix64(h ^ sample.wrapping_mul(0xa076_1d64_78bd_642f));
        Self {
            stream: SplitMix64::new(h),
        }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.stream.next_u64()
    }

    /// A uniform number in [0, 1) with 24 random bits (every value exactly representable, never
    /// 1.0).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        self.stream.next_f32()
    }

    /// Two uniform numbers in [0, 1).
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        let x = self.next_f32();
        glam::Vec2::new(x, self.next_f32())
    }

    /// A uniform integer in `0..n` (n > 0), by Lemire's multiply-shift (bias below 2^-32 n).
    #[inline]
    pub fn next_below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * u64::from(n)) >> 32) as u32
    }
}

/// The point of stratum `index` of a `k` x `k` grid over [0, 1)^2, jittered by `u` in [0, 1)^2
/// (`u` = (0.5, 0.5) gives the stratum centre). Strata are numbered row by row.
#[inline]
pub fn stratum(index: u32, k: u32, u: glam::Vec2) -> glam::Vec2 {
    let k = k.max(1);
    let (i, j) = (index % k, (index / k) % k);
    let inv = 1.0 / k as f32;
    let p = glam::Vec2::new((i as f32 + u.x) * inv, (j as f32 + u.y) * inv);
    // (k - 1 + u) / k can round to 1.0 for u just under 1: stay inside [0, 1).
    p.min(glam::Vec2::splat(1.0 - f32::EPSILON / 2.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<u64> = (0..4).map(|_| Sampler::new(7, 3, 1).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        let mut x = Sampler::new(7, 3, 1);
        let mut y = Sampler::new(7, 3, 2);
        let mut z = Sampler::new(7, 4, 1);
        let (x, y, z) = (x.next_u64(), y.next_u64(), z.next_u64());
        assert!(x != y && x != z && y != z);
    }

    #[test]
    fn uniform_numbers_have_the_right_mean_and_range() {
        let mut s = Sampler::new(1, 2, 3);
        let n = 200_000;
        let mut sum = 0.0_f64;
        for _ in 0..n {
            let u = s.next_f32();
            assert!((0.0..1.0).contains(&u));
            sum += f64::from(u);
        }
        // Mean of U(0,1): 1/2 with standard deviation sqrt(1/12 / n) = 6.5e-4.
        assert!((sum / n as f64 - 0.5).abs() < 4.0 * (1.0 / 12.0 / n as f64).sqrt());
        assert!((0..1000).all(|_| s.next_below(3) < 3));
    }

    #[test]
    fn strata_tile_the_square() {
        let k = 4;
        for i in 0..k * k {
            let c = stratum(i, k, glam::Vec2::splat(0.5));
            let lo = stratum(i, k, glam::Vec2::ZERO);
            assert!((c - lo).abs_diff_eq(glam::Vec2::splat(0.125), 1e-6));
            assert!(stratum(i, k, glam::Vec2::splat(0.999_999_94)).max_element() < 1.0);
        }
    }
}
