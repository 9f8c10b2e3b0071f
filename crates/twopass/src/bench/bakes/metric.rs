//! How far an image rendered from a bake is from the converged reference: over the whole
//! image and per object (the objects the camera sees through each pixel centre).
//!
//! - `rel_rmse`: [`twopass_composite::metric`]'s relative RMSE, `sqrt(mean((x - r)^2 /
//!   (r^2 + 0.01)))` over pixels and RGB channels.
//! - `mean_error`: mean luminance of the image over the reference's, minus 1 (signed: -0.023
//!   is "2.3 % dark").
//! - per-pixel deviation: `|Y(x) - Y(r)| / max(Y(r), floor)` on luminance Y, with the floor
//!   [`DEVIATION_FLOOR`] times the reference's mean luminance, so pixels darker than a
//!   twentieth of the image's mean are judged against that instead of their own (noisy,
//!   near-zero) value; `share_off` is the share of pixels deviating by more than
//!   [`OFF_THRESHOLD`], `p95_deviation` the 95th percentile (nearest rank).
//! - per object: the mean luminance of the image over the object's pixels over the
//!   reference's there, minus 1, for objects covering at least the bench's minimum of pixels.

use serde::Serialize;
use twopass_brdf::colour::luminance;
use twopass_composite::Image;
use twopass_composite::metric::compare;
use twopass_composite::tonemap::ToneMap;

use crate::error::CliError;

/// The floor of a per-pixel deviation's denominator, as a fraction of the reference's mean
/// luminance.
pub const DEVIATION_FLOOR: f64 = 0.05;
/// A pixel deviating by more than this (10 %) counts as off.
pub const OFF_THRESHOLD: f64 = 0.10;

/// The error of one object's pixels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionError {
    /// The object's name in the scene.
    pub object: String,
    /// Pixels whose centre sees the object.
    pub pixels: u64,
    /// Mean luminance of the reference over those pixels, W/(m^2 sr).
    pub reference_mean: f64,
    /// Mean of the image there over the reference's, minus 1 (signed).
    pub error: f64,
}

/// The error of one image against the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageError {
    /// Relative RMSE (twopass_composite's definition), unitless.
    pub rel_rmse: f64,
    /// Mean luminance over the reference's, minus 1 (signed).
    pub mean_error: f64,
    /// Share of pixels whose deviation exceeds [`OFF_THRESHOLD`], in [0, 1].
    pub share_off: f64,
    /// 95th percentile of the per-pixel deviation, unitless.
    pub p95_deviation: f64,
    /// Per object of at least the minimum pixel count, worst (largest |error|) first.
    pub regions: Vec<RegionError>,
}

impl ImageError {
    /// The region with the largest |error|, if any region qualified.
    pub fn worst(&self) -> Option<&RegionError> {
        self.regions.first()
    }
}

/// Luminance of each pixel, f64.
fn lumas(image: &Image) -> Vec<f64> {
    image
        .pixels()
        .iter()
        .map(|&p| f64::from(luminance(p)))
        .collect()
}

/// The 95th percentile of `values` by nearest rank (the smallest value with at least 95 % of
/// the values at or below it); 0 for none.
pub fn p95(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let rank = (0.95 * values.len() as f64).ceil() as usize;
    values[rank.clamp(1, values.len()) - 1]
}

/// Measures `image` against `reference` (same size, finite). `objects` gives each pixel's
/// object (row-major, `None` where the camera sees nothing), `names` the objects' names;
/// regions are the objects covering at least `min_pixels` pixels.
pub fn measure(
    image: &Image,
    reference: &Image,
    objects: &[Option<u32>],
    names: &[String],
    min_pixels: u64,
) -> Result<ImageError, CliError> {
    let rel_rmse = compare(image, reference, &ToneMap::auto_default(reference)?)?.rel_rmse;
    let (x, r) = (lumas(image), lumas(reference));
    let n = r.len() as f64;
    let ref_mean = r.iter().sum::<f64>() / n;
    let mean_error = x.iter().sum::<f64>() / n / ref_mean - 1.0;
    let floor = (DEVIATION_FLOOR * ref_mean).max(f64::MIN_POSITIVE);
    let mut deviation: Vec<f64> = x
        .iter()
        .zip(&r)
        .map(|(a, b)| (a - b).abs() / b.max(floor))
        .collect();
    let share_off = deviation.iter().filter(|&&d| d > OFF_THRESHOLD).count() as f64 / n;
    let p95_deviation = p95(&mut deviation);
    // Per object: (pixels, image sum, reference sum).
    let mut sums = vec![(0u64, 0.0f64, 0.0f64); names.len()];
    for ((o, a), b) in objects.iter().zip(&x).zip(&r) {
        if let Some(s) = o.and_then(|o| sums.get_mut(o as usize)) {
            *s = (s.0 + 1, s.1 + a, s.2 + b);
        }
    }
    let mut regions: Vec<RegionError> = sums
        .iter()
        .zip(names)
        .filter(|((count, _, b), _)| *count >= min_pixels && *b > 0.0)
        .map(|(&(count, a, b), name)| RegionError {
            object: name.clone(),
            pixels: count,
            reference_mean: b / count as f64,
            error: a / b - 1.0,
        })
        .collect();
    regions.sort_by(|p, q| q.error.abs().total_cmp(&p.error.abs()));
    Ok(ImageError {
        rel_rmse,
        mean_error,
        share_off,
        p95_deviation,
        regions,
    })
}

/// The object each pixel centre of the scene's camera sees, row-major from the top left
/// (`None` where the ray leaves the scene).
pub fn object_map(scene: &twopass_scene::Scene) -> Vec<Option<u32>> {
    let rays = twopass_scene::workload::camera_rays(scene);
    scene
        .intersect_batch(&rays)
        .into_iter()
        .map(|h| h.map(|h| h.object))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A 20 x 20 reference: left half object 0 (radiance 1), right half object 1 (radiance
    /// 0.5 in every channel), the top row seeing nothing.
    fn scene_like() -> (Image, Vec<Option<u32>>, Vec<String>) {
        let image = Image::from_fn(20, 20, |x, _| {
            if x < 10 {
                Vec3::splat(1.0)
            } else {
                Vec3::splat(0.5)
            }
        });
        let objects = (0..20u32)
            .flat_map(|y| (0..20u32).map(move |x| (y > 0).then_some(u32::from(x >= 10))))
            .collect();
        (image, objects, vec!["left".into(), "right".into()])
    }

    #[test]
    fn an_image_ten_percent_brighter_everywhere_is_ten_percent_off_everywhere() {
        let (reference, objects, names) = scene_like();
        let image = Image::from_fn(20, 20, |x, y| reference.get(x, y) * 1.1);
        let m = measure(&image, &reference, &objects, &names, 100).unwrap();
        assert!((m.mean_error - 0.1).abs() < 1e-6, "{}", m.mean_error);
        assert!((m.p95_deviation - 0.1).abs() < 1e-6);
        assert_eq!(m.regions.len(), 2);
        for r in &m.regions {
            assert!((r.error - 0.1).abs() < 1e-6, "{r:?}");
            assert_eq!(r.pixels, 190);
        }
        // The left half at luminance 1 and the right at 0.5: reference means 1 and 0.5.
        let left = m.regions.iter().find(|r| r.object == "left").unwrap();
        assert!((left.reference_mean - 1.0).abs() < 1e-6);
        // rel_rmse: d = 0.1 r per channel, mean over pixels of d^2 / (r^2 + 0.01).
        let expected = (0.5 * (0.01 / 1.01) + 0.5 * (0.0025 / 0.26_f64)).sqrt();
        assert!(
            (m.rel_rmse - expected).abs() < 1e-6,
            "{} {expected}",
            m.rel_rmse
        );
        // Deviation exactly 0.1 is not "more than 10 %"; f32 rounding may tip either way, so
        // the share is judged with an image 11 % brighter.
        let brighter = Image::from_fn(20, 20, |x, y| reference.get(x, y) * 1.11);
        let m = measure(&brighter, &reference, &objects, &names, 100).unwrap();
        assert_eq!(m.share_off, 1.0);
    }

    #[test]
    fn one_dark_object_is_the_worst_region_and_sets_the_shares() {
        let (reference, objects, names) = scene_like();
        // The right half 30 % dark: half the pixels off, the mean down by 0.3 * 0.5 / 1.5.
        let image = Image::from_fn(20, 20, |x, y| {
            let p = reference.get(x, y);
            if x >= 10 { p * 0.7 } else { p }
        });
        let m = measure(&image, &reference, &objects, &names, 100).unwrap();
        assert!((m.mean_error + 0.1).abs() < 1e-6, "{}", m.mean_error);
        assert!((m.share_off - 0.5).abs() < 1e-12);
        assert!((m.p95_deviation - 0.3).abs() < 1e-6);
        let worst = m.worst().unwrap();
        assert_eq!(worst.object, "right");
        assert!((worst.error + 0.3).abs() < 1e-6);
        assert!(m.regions[1].error.abs() < 1e-12);
        // Regions below the minimum pixel count are left out.
        let m = measure(&image, &reference, &objects, &names, 191).unwrap();
        assert!(m.regions.is_empty());
    }

    #[test]
    fn the_deviation_of_dark_pixels_is_taken_against_the_floor() {
        // Reference: 399 pixels at 1, one black; the image has 0.01 where the reference is
        // black. Mean ~1, floor 0.05: that pixel deviates 0.01 / 0.05 = 0.2.
        let reference = Image::from_fn(20, 20, |x, y| {
            Vec3::splat(if (x, y) == (0, 0) { 0.0 } else { 1.0 })
        });
        let image = Image::from_fn(20, 20, |x, y| {
            Vec3::splat(if (x, y) == (0, 0) { 0.01 } else { 1.0 })
        });
        let m = measure(&image, &reference, &[None; 400], &[], 1).unwrap();
        assert!((m.share_off - 1.0 / 400.0).abs() < 1e-12);
        assert_eq!(m.p95_deviation, 0.0);
    }

    #[test]
    fn p95_is_the_nearest_rank() {
        let mut v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(p95(&mut v), 95.0);
        assert_eq!(p95(&mut [3.0]), 3.0);
        let mut v: Vec<f64> = (1..=20).rev().map(f64::from).collect();
        assert_eq!(p95(&mut v), 19.0);
    }
}
