//! Deterministic sample values: one independent sequence per (seed, pixel, sample), so an
//! image does not depend on which thread rendered which pixel, or in which order.
//!
//! A camera sample's numbers are, in the order they are asked for, the dimensions of one point
//! of an Owen-scrambled Sobol sequence (Burley 2020, "Practical Hash-based Owen Scrambling",
//! through the `sobol_burley` crate): sample `s` of a pixel is point `s` of that pixel's
//! sequence, and each pixel's sequence has its own scramble, hashed from (seed, pixel). The
//! samples of one pixel then fill every dimension evenly (the first 2^k points of each
//! dimension pair form a net) instead of clumping as independent numbers do, while every
//! single point stays uniform over the unit cube, so each estimate stays unbiased; neighbouring
//! pixels stay independent, and the error at a given sample count falls (measured in
//! docs/benchmarks.md, "The path tracer against Mitsuba 3").
//!
//! **Joint sets, then padded ones.** The numbers come in sets of four dimensions. The first
//! [`JOINT_SETS`] sets (the camera and a path's first vertices) are Sobol dimensions 0 to 15 of
//! the one point, stratified jointly. Every later set is *padded* (Burley's section 4): the
//! first four Sobol dimensions again, under a seed of its own (an index shuffle and a
//! scramble), stratified within itself and paired at random with the other sets. The
//! sequence's higher dimensions, which those sets would otherwise be, have 2D projections of
//! poor quality at some sample counts (dimensions 16 and 17 put a pixel's first 16 points two
//! by two into half the cells of a 4 x 4 grid): drawn from them, four generated rooms' error
//! fell by only 1.6-1.8x from 64 to 256 samples instead of 2x. Where the joint sets end is
//! measured, not derived: padding every set after the first cost the Cornell box 10-13 % more
//! squared error at 64 and 256 samples, padding from dimension 16 on 4-5 %
//! (docs/benchmarks.md, "The path tracer against Mitsuba 3").
//!
//! Past the sequence's 256 dimensions (paths of more than about 36 bounces) or 2^16 samples
//! of a pixel, and for [`Sampler::next_u64`], the numbers come from SplitMix64 (Steele, Lea &
//! Flood 2014, [`twopass_brdf::random`], the workspace's one home of random streams) over a
//! state hashed from the three indices. Nothing here is shared between rayon jobs
//! (ARCHITECTURE.md, "Conventions": never keep RNG state in `map_init`).

use twopass_brdf::random::{SplitMix64, hash, mix64};

/// What the sample values are, for records that must say how an image was sampled (the
/// tradeoff bench's reference cache).
pub const SAMPLE_SEQUENCE: &str = "Owen-scrambled Sobol per pixel (Burley 2020, sobol_burley 0.5), \
     dimensions 0-15 joint, padded sets of four after, then SplitMix64";

/// Sets of four dimensions drawn jointly from one Sobol point (Sobol dimensions 0 to
/// `4 * JOINT_SETS - 1`); every later set is padded (see the module documentation).
pub const JOINT_SETS: u32 = 4;

/// Samples per pixel the Sobol sequence covers; further samples of a pixel are independent.
const SOBOL_SAMPLES: u64 = 1 << 16;

/// The sample values of one camera sample of one pixel: successive dimensions of a scrambled
/// Sobol point, then an independent stream.
#[derive(Debug, Clone)]
pub struct Sampler {
    stream: SplitMix64,
    /// The hash of (seed, pixel, sample) the stream starts from; forks derive theirs from it.
    key: u64,
    /// The point's index in the pixel's sequence (the sample number), or `u32::MAX` past it.
    index: u32,
    /// The next dimension [`Sampler::next_f32`] hands out.
    dimension: u32,
    /// The pixel's scramble seed.
    scramble: u32,
    /// The point's index as the joint sets take it: bit-reversed and shuffled by the pixel's
    /// scramble (`sobol_burley::sample_4d`'s first step, the same for each of them), made once.
    shuffled: u32,
    /// Dimensions `4 * (dimension / 4)` to `+ 3` of the point, computed together.
    set: [f32; 4],
}

impl Sampler {
    /// The values of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let h = hash(seed);
        let p = mix64(h ^ pixel.wrapping_mul(0xd6e8_feb8_6659_fd93));
        let h = mix64(p ^ sample.wrapping_mul(0xa076_1d64_78bd_642f));
        let index = if sample < SOBOL_SAMPLES {
            sample as u32
        } else {
            u32::MAX
        };
        let scramble = (p >> 32) as u32;
        Self {
            stream: SplitMix64::new(h),
            key: h,
            index,
            dimension: 0,
            scramble,
            shuffled: shuffled_index(index, scramble),
            set: [0.0; 4],
        }
    }

    /// The numbers of sub-sample `j` of `per` drawn at site `site` of this camera sample: point
    /// `sample * per + j` of a Sobol sequence scrambled per (pixel, site), so that the sub-samples
    /// of all of a pixel's camera samples together are the first points of one sequence (a
    /// per-pixel gather's rays stratified over the pixel, not only within one camera sample).
    /// `site` tells apart the places one camera sample draws sub-samples at (the camera hit,
    /// each landing of the delta recursion), numbered alike in every camera sample. The
    /// independent stream is hashed from the same indices.
    pub fn fork(&self, site: u64, j: u32, per: u32) -> Self {
        let scramble = (mix64(u64::from(self.scramble) ^ site.wrapping_mul(0x9e37_79b9_7f4a_7c15))
            >> 32) as u32;
        let per = u64::from(per.max(1));
        let index = (self.index != u32::MAX)
            .then(|| u64::from(self.index) * per + u64::from(j))
            .filter(|&i| i < SOBOL_SAMPLES);
        let key = mix64(
            self.key
                ^ site.wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ u64::from(j).wrapping_mul(0xd6e8_feb8_6659_fd93),
        );
        let index = index.map_or(u32::MAX, |i| i as u32);
        Self {
            stream: SplitMix64::new(key),
            key,
            index,
            dimension: 0,
            scramble,
            shuffled: shuffled_index(index, scramble),
            set: [0.0; 4],
        }
    }

    /// The next 64 random bits, from the independent stream (not the Sobol point).
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.stream.next_u64()
    }

    /// The next dimension of the sample: a uniform number in [0, 1) with 24 bits (every value
    /// exactly representable, never 1.0).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        if self.index != u32::MAX && self.dimension < sobol_burley::NUM_DIMENSIONS {
            let d = self.dimension;
            self.dimension += 1;
            if d.is_multiple_of(4) {
                self.set = point_set(self.index, self.shuffled, d / 4, self.scramble);
            }
            self.set[(d % 4) as usize]
        } else {
            self.stream.next_f32()
        }
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

/// Per joint set of four dimensions, for the index's high byte (`[0]`) and the next (`[1]`),
/// the XOR of the direction vectors of each byte value's set bits (bit-reversed, as
/// `sobol_burley::parts::sobol_int4_rev` forms them): 32 KiB, made on first use.
type SobolBytes = [[[[u32; 4]; 256]; 2]; JOINT_SETS as usize];

fn sobol_bytes() -> &'static SobolBytes {
    static TABLE: std::sync::OnceLock<SobolBytes> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|set| {
            std::array::from_fn(|byte| {
                std::array::from_fn(|v| {
                    let index = (v as u32) << (24 - 8 * byte);
                    sobol_burley::parts::sobol_int4_rev(index, set as u32).into()
                })
            })
        })
    })
}

/// `sobol_burley::sample_4d`'s shuffled index of point `index` under `seed` (the pixel's, or a
/// padded set's; 0 past the sequence, where it is not used).
fn shuffled_index(index: u32, seed: u32) -> u32 {
    use sobol_burley::parts::{hash, owen_scramble_rev};
    if index == u32::MAX {
        return 0;
    }
    owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c6_8e4a))
}

/// `sobol_burley::sample_4d(index, set, seed)` (`set` below [`JOINT_SETS`]) from the point's
/// index shuffled under `seed` ([`shuffled_index`]): the same four numbers.
#[inline]
fn sobol_set(shuffled: u32, set: u32, seed: u32) -> [f32; 4] {
    use sobol_burley::parts::{Int4, hash_int4, owen_scramble_int4_rev};
    // The point is the XOR of the direction vectors of the index's set bits: one table entry
    // per byte of the 16 bits the sequence uses, instead of a loop over the bits whose trip
    // count (and branch) changes with every sample.
    let bytes = &sobol_bytes()[set as usize];
    let [a, b] = [
        bytes[0][(shuffled >> 24) as usize],
        bytes[1][((shuffled >> 16) & 0xff) as usize],
    ];
    let sobol = Int4::from(a) ^ Int4::from(b);
    // The crate's per-set scramble: the seed times an odd constant, the set, and one constant
    // per lane.
    let seed: Int4 = [seed.wrapping_mul(0x9c8f_2d3b); 4].into();
    let sets: Int4 = [set; 4].into();
    let lanes: Int4 = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8].into();
    owen_scramble_int4_rev(sobol, hash_int4(seed ^ sets ^ lanes))
        .reverse_bits()
        .to_f32_norm()
}

/// Set `set` of point `index` (`shuffled` its index shuffled under the pixel's `scramble`):
/// a joint set below [`JOINT_SETS`], a padded one from there on.
#[inline]
fn point_set(index: u32, shuffled: u32, set: u32, scramble: u32) -> [f32; 4] {
    if set < JOINT_SETS {
        sobol_set(shuffled, set, scramble)
    } else {
        padded_set(index, set, scramble)
    }
}

/// The seed of padded set `set` ([`JOINT_SETS`] or more) of a pixel of scramble `scramble`.
#[inline]
fn padded_seed(scramble: u32, set: u32) -> u32 {
    (mix64((u64::from(scramble) << 32) | u64::from(set)) >> 32) as u32
}

/// Set `set` ([`JOINT_SETS`] or more) of point `index`, padded:
/// `sobol_burley::sample_4d(index, 0, seed)` under the set's own seed ([`padded_seed`]), its
/// index shuffle and scramble its own.
#[inline]
fn padded_set(index: u32, set: u32, scramble: u32) -> [f32; 4] {
    let seed = padded_seed(scramble, set);
    sobol_set(shuffled_index(index, seed), 0, seed)
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

    /// The first `dims` numbers of each of the first 16 samples of `pixel` under `seed`.
    fn first_16(seed: u64, pixel: u64, dims: u32) -> Vec<Vec<f32>> {
        (0..16)
            .map(|s| {
                let mut x = Sampler::new(seed, pixel, s);
                (0..dims).map(|_| x.next_f32()).collect()
            })
            .collect()
    }

    /// How many of `points` fall in each cell of the 4 x 4 grid over dimensions `d` and `d + 1`.
    fn grid_4x4(points: &[Vec<f32>], d: usize) -> [u32; 16] {
        let mut cells = [0u32; 16];
        for p in points {
            cells[(p[d] * 4.0) as usize * 4 + (p[d + 1] * 4.0) as usize] += 1;
        }
        cells
    }

    /// The first 16 samples of a pixel put exactly one value in each sixteenth of every
    /// dimension, and, in the first two dimensions, one point in each cell of the 4 x 4 grid
    /// (the Sobol points' net properties, which Owen scrambling keeps; later pairs of
    /// dimensions are nets of a lower quality). Independent numbers would leave some of the
    /// sixteen cells empty with probability 1 - 16!/16^16, about 0.99999.
    #[test]
    fn a_pixel_s_samples_fill_every_dimension_and_the_first_pair_evenly() {
        for (seed, pixel) in [(0, 0), (7, 12_345), (u64::MAX, 3)] {
            let points = first_16(seed, pixel, 64);
            for d in 0..64 {
                let mut cells = [0u32; 16];
                for p in &points {
                    cells[(p[d] * 16.0) as usize] += 1;
                }
                assert_eq!(cells, [1; 16], "dimension {d} of pixel {pixel}");
            }
            assert_eq!(
                grid_4x4(&points, 0),
                [1; 16],
                "dimensions 0, 1 of pixel {pixel}"
            );
        }
    }

    /// Every padded set's first two dimensions are Sobol dimensions 0 and 1 under the set's own
    /// scramble: a pixel's first 16 samples put one point in each cell of their 4 x 4 grid, in
    /// every set up to the sequence's last, and each set draws other numbers than the next.
    /// (The sequence's own dimensions 16 and 17, which the first padded set would otherwise be,
    /// put their first 16 points two by two into half of the cells.)
    #[test]
    fn padded_sets_are_stratified_each_under_its_own_scramble() {
        for (seed, pixel) in [(0, 0), (7, 12_345), (u64::MAX, 3)] {
            let points = first_16(seed, pixel, sobol_burley::NUM_DIMENSIONS);
            for set in JOINT_SETS..sobol_burley::NUM_DIMENSION_SETS_4D {
                let d = (4 * set) as usize;
                assert_eq!(grid_4x4(&points, d), [1; 16], "set {set} of pixel {pixel}");
                if let Some(next) = points[0].get(d + 4) {
                    assert_ne!(points[0][d], *next, "sets {set} and next alike");
                }
            }
        }
    }

    /// Neighbouring pixels are scrambled independently: over many pixel pairs, the first
    /// dimension of their sample 0 is uncorrelated (correlation within 4 standard errors).
    #[test]
    fn pixels_are_scrambled_independently() {
        let n = 20_000u64;
        let (mut sxy, mut sx, mut sy, mut sxx, mut syy) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for p in 0..n {
            let x = f64::from(Sampler::new(5, 2 * p, 0).next_f32());
            let y = f64::from(Sampler::new(5, 2 * p + 1, 0).next_f32());
            (sxy, sx, sy, sxx, syy) = (sxy + x * y, sx + x, sy + y, sxx + x * x, syy + y * y);
        }
        let n = n as f64;
        let cov = sxy / n - sx / n * (sy / n);
        let r = cov / ((sxx / n - (sx / n).powi(2)) * (syy / n - (sy / n).powi(2))).sqrt();
        assert!(r.abs() < 4.0 / n.sqrt(), "correlation {r}");
    }

    /// Past the sequence (dimension 256, sample 2^16) the numbers still come, uniform and
    /// reproducible, from the independent stream.
    #[test]
    fn past_the_sequence_the_stream_takes_over() {
        let mut long = Sampler::new(3, 4, 5);
        let past: Vec<f32> = (0..300).map(|_| long.next_f32()).skip(256).collect();
        assert!(past.iter().all(|u| (0.0..1.0).contains(u)));
        let mut again = Sampler::new(3, 4, 5);
        let repeat: Vec<f32> = (0..300).map(|_| again.next_f32()).skip(256).collect();
        assert_eq!(past, repeat);
        let mut far = Sampler::new(3, 4, SOBOL_SAMPLES + 1);
        let mut other = Sampler::new(3, 4, SOBOL_SAMPLES + 2);
        assert_ne!(far.next_f32(), other.next_f32());
    }

    /// A sample's sets are the crate's own `sample_4d`'s, bit for bit: the joint sets
    /// `sample_4d(index, set, scramble)` (from the index shuffled once), every later set
    /// `sample_4d(index, 0, seed)` under its padded seed.
    #[test]
    fn sets_are_the_crate_s() {
        let mut r = SplitMix64::new(17);
        let cases = [(0u32, 0u32), (1, 7), (255, 0xdead_beef), (65_535, u32::MAX)]
            .into_iter()
            .chain((0..500).map(|_| {
                let bits = r.next_u64();
                ((bits & 0xffff) as u32, (bits >> 32) as u32)
            }));
        let crate_s = |index, set, scramble| {
            if set < JOINT_SETS {
                sobol_burley::sample_4d(index, set, scramble)
            } else {
                sobol_burley::sample_4d(index, 0, padded_seed(scramble, set))
            }
        };
        for (index, scramble) in cases {
            for set in 0..sobol_burley::NUM_DIMENSION_SETS_4D {
                let ours = point_set(index, shuffled_index(index, scramble), set, scramble);
                let theirs = crate_s(index, set, scramble);
                assert_eq!(ours.map(f32::to_bits), theirs.map(f32::to_bits));
            }
        }
        // And a sampler hands them out in order.
        let mut x = Sampler::new(3, 9, 5);
        let numbers: Vec<u32> = (0..24).map(|_| x.next_f32().to_bits()).collect();
        let sets: Vec<u32> = (0..6)
            .flat_map(|set| crate_s(5, set, x.scramble).map(f32::to_bits))
            .collect();
        assert_eq!(numbers, sets);
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

    /// A pixel's forks at one site, `per` per camera sample, are the points `sample * per + j`
    /// of one sequence: over 4 samples of 4 forks the first dimension puts one value in each
    /// sixteenth of [0, 1); other sites and pixels scramble it differently.
    #[test]
    fn forks_of_a_pixels_samples_are_one_stratified_sequence() {
        let first = |pixel, sample, site, j, per| {
            Sampler::new(9, pixel, sample).fork(site, j, per).next_f32()
        };
        // Sample 1's fork 0 of 2 and sample 2's fork 0 of 1 are both point 2.
        assert_eq!(first(5, 1, 3, 0, 2), first(5, 2, 3, 0, 1));
        let mut strata: Vec<u32> = (0..4u64)
            .flat_map(|s| (0..4).map(move |j| (first(5, s, 3, j, 4) * 16.0) as u32))
            .collect();
        strata.sort_unstable();
        assert_eq!(strata, (0..16).collect::<Vec<_>>());
        assert_ne!(
            first(5, 0, 3, 0, 4),
            first(5, 0, 4, 0, 4),
            "sites share a scramble"
        );
        assert_ne!(
            first(5, 0, 3, 0, 4),
            first(6, 0, 3, 0, 4),
            "pixels share a scramble"
        );
        // Reproducible, and the independent stream differs per fork.
        let mut a = Sampler::new(9, 5, 1).fork(3, 2, 4);
        let mut b = Sampler::new(9, 5, 1).fork(3, 2, 4);
        assert_eq!(a.next_u64(), b.next_u64());
        let mut c = Sampler::new(9, 5, 1).fork(3, 1, 4);
        assert_ne!(a.next_u64(), c.next_u64());
    }
}
