//! Error metrics of an image against a reference, over the whole image or a region.
//!
//! With `x` the image, `r` the reference, and the mean taken over the pixels of the region and
//! the three channels (linear RGB, in the images' own radiance units):
//! - `mae = mean(|x - r|)`
//! - `rmse = sqrt(mean((x - r)^2))`
//! - `rel_mse = mean((x - r)^2 / (r^2 + 0.01))` and `rel_rmse = sqrt(rel_mse)` (issue 7's
//!   relative RMS error; the 0.01 keeps black reference pixels from dominating)
//! - `ssim`: structural similarity (Wang, Bovik, Sheikh & Simoncelli 2004) of the *displayed*
//!   luminance: each pixel goes through the sheet's [`ToneMap`] (exposure and curve), its
//!   luminance is sRGB-encoded (so in [0, 1], dynamic range L = 1), and SSIM is computed with an
//!   11 x 11 Gaussian window of sigma 1.5 and the standard constants C1 = (0.01 L)^2,
//!   C2 = (0.03 L)^2. The SSIM map has a value at every pixel: near the border the window is
//!   truncated to the image and renormalised (Wang's reference code instead drops the 5-pixel
//!   border), and the image's or region's SSIM is the mean of the map over its pixels.
//!
//! Non-finite pixels in either image are an error, never a NaN metric. Sums are in `f64`.

use crate::error::{CompositeError, Result};
use crate::image::{Image, Rect};
use crate::tonemap::{ToneMap, display_luma};

/// The constant in the relative error's denominator, `(x - r)^2 / (r^2 + REL_EPSILON)`.
pub const REL_EPSILON: f64 = 0.01;
/// SSIM window radius: the window is `2 * SSIM_RADIUS + 1` = 11 pixels wide.
pub const SSIM_RADIUS: usize = 5;
/// SSIM Gaussian standard deviation, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// SSIM constant C1 = (K1 L)^2 with K1 = 0.01 and L = 1.
pub const SSIM_C1: f64 = 1e-4;
/// SSIM constant C2 = (K2 L)^2 with K2 = 0.03 and L = 1.
pub const SSIM_C2: f64 = 9e-4;

/// The metrics of one image (or region) against the reference. See the module docs for the
/// formulas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Number of pixels compared.
    pub pixels: u64,
    /// Mean absolute error, radiance units.
    pub mae: f64,
    /// Root mean squared error, radiance units.
    pub rmse: f64,
    /// Relative mean squared error, `mean((x - r)^2 / (r^2 + 0.01))`, unitless.
    pub rel_mse: f64,
    /// `sqrt(rel_mse)`, unitless (0.026 is "2.6 %").
    pub rel_rmse: f64,
    /// Mean SSIM of the displayed luminance, in [-1, 1], 1 for identical images.
    pub ssim: f64,
}

/// Metrics of `image` against `reference` over the whole image. `display` is the tone map of
/// the sheet (used by SSIM only).
pub fn compare(image: &Image, reference: &Image, display: &ToneMap) -> Result<Metrics> {
    let full = Rect::full(reference.width(), reference.height());
    Ok(compare_regions(image, reference, display, &[full])?[0])
}

/// Metrics of `image` against `reference` in each of `regions` (the SSIM map is computed once).
pub fn compare_regions(
    image: &Image,
    reference: &Image,
    display: &ToneMap,
    regions: &[Rect],
) -> Result<Vec<Metrics>> {
    check_pair(image, reference)?;
    for r in regions {
        reference.check_region(*r)?;
        if r.area() == 0 {
            return Err(CompositeError::Empty {
                what: format!("region {r:?}"),
            });
        }
    }
    let (w, h) = (reference.width() as usize, reference.height() as usize);
    let la: Vec<f32> = image
        .pixels()
        .iter()
        .map(|&p| display_luma(display, p))
        .collect();
    let lb: Vec<f32> = reference
        .pixels()
        .iter()
        .map(|&p| display_luma(display, p))
        .collect();
    let map = ssim_map(&la, &lb, w, h);
    Ok(regions
        .iter()
        .map(|r| {
            let (mut abs, mut sq, mut rel, mut ss) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for y in r.y..r.y + r.height {
                for x in r.x..r.x + r.width {
                    let a = image.get(x, y);
                    let b = reference.get(x, y);
                    for c in 0..3 {
                        let (xv, rv) = (f64::from(a[c]), f64::from(b[c]));
                        let d = xv - rv;
                        abs += d.abs();
                        sq += d * d;
                        rel += d * d / (rv * rv + REL_EPSILON);
                    }
                    ss += map[y as usize * w + x as usize];
                }
            }
            let n = r.area() as f64;
            let rel_mse = rel / (3.0 * n);
            Metrics {
                pixels: r.area(),
                mae: abs / (3.0 * n),
                rmse: (sq / (3.0 * n)).sqrt(),
                rel_mse,
                rel_rmse: rel_mse.sqrt(),
                ssim: ss / n,
            }
        })
        .collect())
}

/// Same size, non-empty, all finite.
pub(crate) fn check_pair(image: &Image, reference: &Image) -> Result<()> {
    crate::image::check_same_size(reference, image, "image against reference")?;
    if reference.pixels().is_empty() {
        return Err(CompositeError::Empty {
            what: "reference".into(),
        });
    }
    reference.check_finite("reference")?;
    Ok(image.check_finite("image")?)
}

/// The normalised 1-D Gaussian taps `g(k) = exp(-k^2 / (2 sigma^2))`, k = -5..=5 (unnormalised;
/// normalisation happens over the in-image part of the window).
fn taps() -> [f64; 2 * SSIM_RADIUS + 1] {
    let mut t = [0.0; 2 * SSIM_RADIUS + 1];
    for (i, v) in t.iter_mut().enumerate() {
        let k = i as f64 - SSIM_RADIUS as f64;
        *v = (-k * k / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    t
}

/// Weighted mean of `src` (row-major `w` x `h`) along one axis with the Gaussian truncated to
/// the image and renormalised. `horizontal` picks the axis.
fn blur(src: &[f64], w: usize, h: usize, horizontal: bool) -> Vec<f64> {
    let t = taps();
    let r = SSIM_RADIUS as isize;
    let mut out = vec![0.0; src.len()];
    for y in 0..h {
        for x in 0..w {
            let (pos, len) = if horizontal { (x, w) } else { (y, h) };
            let (mut s, mut ws) = (0.0, 0.0);
            for k in -r..=r {
                let p = pos as isize + k;
                if p < 0 || p >= len as isize {
                    continue;
                }
                let i = if horizontal {
                    y * w + p as usize
                } else {
                    p as usize * w + x
                };
                let wt = t[(k + r) as usize];
                s += wt * src[i];
                ws += wt;
            }
            out[y * w + x] = s / ws;
        }
    }
    out
}

/// The SSIM map of two single-channel `w` x `h` images (row-major, values on a dynamic range
/// of 1), one value per pixel; see the module docs for the window and constants.
/// Panics if the slices are not `w * h` long.
pub fn ssim_map(a: &[f32], b: &[f32], w: usize, h: usize) -> Vec<f64> {
    assert!(
        a.len() == w * h && b.len() == w * h,
        "ssim_map: slices must be w * h long"
    );
    let a: Vec<f64> = a.iter().map(|&v| f64::from(v)).collect();
    let b: Vec<f64> = b.iter().map(|&v| f64::from(v)).collect();
    let prod = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..w * h).map(f).collect() };
    let g = |v: Vec<f64>| blur(&blur(&v, w, h, true), w, h, false);
    let ma = g(a.clone());
    let mb = g(b.clone());
    let maa = g(prod(&|i| a[i] * a[i]));
    let mbb = g(prod(&|i| b[i] * b[i]));
    let mab = g(prod(&|i| a[i] * b[i]));
    (0..w * h)
        .map(|i| {
            let (mx, my) = (ma[i], mb[i]);
            let vx = maa[i] - mx * mx;
            let vy = mbb[i] - my * my;
            let cxy = mab[i] - mx * my;
            ((2.0 * mx * my + SSIM_C1) * (2.0 * cxy + SSIM_C2))
                / ((mx * mx + my * my + SSIM_C1) * (vx + vy + SSIM_C2))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol, "{a} vs {b}");
    }

    #[test]
    fn two_by_two_by_hand() {
        // Reference: grey 1, 1, 1, 1 in every channel except pixel (1, 1), whose red is 0.
        // Image: the reference plus 0.1 in every channel of pixel (0, 0) and -0.5 in green of
        // pixel (1, 0). Differences over 12 samples: three 0.1s, one -0.5, eight 0.
        let reference = Image::from_fn(2, 2, |x, y| {
            if (x, y) == (1, 1) {
                [0.0, 1.0, 1.0]
            } else {
                [1.0, 1.0, 1.0]
            }
        });
        let mut image = reference.clone();
        image.set(0, 0, Vec3::splat(1.1));
        image.set(1, 0, Vec3::new(1.0, 0.5, 1.0));
        let m = compare(&image, &reference, &ToneMap::default()).unwrap();
        assert_eq!(m.pixels, 4);
        // mae = (3 * 0.1 + 0.5) / 12 = 0.8 / 12 = 0.0666...
        close(m.mae, 0.8 / 12.0, 1e-7);
        // rmse = sqrt((3 * 0.01 + 0.25) / 12) = sqrt(0.28 / 12) = 0.152753
        close(m.rmse, (0.28f64 / 12.0).sqrt(), 1e-7);
        // rel_mse: all differing samples have r = 1, so each term is d^2 / 1.01:
        // (3 * 0.01 + 0.25) / 1.01 / 12 = 0.0231023
        close(m.rel_mse, 0.28 / 1.01 / 12.0, 1e-7);
        close(m.rel_rmse, (0.28f64 / 1.01 / 12.0).sqrt(), 1e-7);
    }

    #[test]
    fn relative_error_weights_dark_reference_pixels() {
        // 3x3, reference 0 everywhere but the centre (2.0); image 0.1 everywhere (one channel
        // differs per pixel: red only, green and blue equal the reference).
        let reference = Image::from_fn(3, 3, |x, y| {
            let v = if (x, y) == (1, 1) { 2.0 } else { 0.0 };
            [v, 0.0, 0.0]
        });
        let image = Image::from_fn(3, 3, |x, y| {
            let v = if (x, y) == (1, 1) { 2.1 } else { 0.1 };
            [v, 0.0, 0.0]
        });
        let m = compare(&image, &reference, &ToneMap::default()).unwrap();
        // 9 red differences of 0.1, 18 zero samples: mae = 0.9 / 27, rmse = sqrt(0.09 / 27).
        close(m.mae, 0.9 / 27.0, 1e-7);
        close(m.rmse, (0.09f64 / 27.0).sqrt(), 1e-7);
        // Relative: eight 0.01 / (0 + 0.01) = 1 and one 0.01 / (4 + 0.01), over 27 samples:
        // (8 + 0.01 / 4.01) / 27 = 0.296388.
        close(m.rel_mse, (8.0 + 0.01 / 4.01) / 27.0, 1e-7);
        // Region: the centre pixel alone, over 3 samples: (0.01 / 4.01) / 3.
        let r = compare_regions(
            &image,
            &reference,
            &ToneMap::default(),
            &[Rect::new(1, 1, 1, 1)],
        )
        .unwrap()[0];
        // (2.1f32 - 2.0 is 0.0999999 in f32, hence the tolerance.)
        close(r.rel_mse, 0.01 / 4.01 / 3.0, 1e-8);
        close(r.mae, 0.1 / 3.0, 1e-7);
        assert_eq!(r.pixels, 1);
    }

    #[test]
    fn errors_not_nan() {
        let r = Image::new(2, 2);
        let mut x = Image::new(2, 2);
        x.set(0, 1, Vec3::new(0.0, f32::INFINITY, 0.0));
        match compare(&x, &r, &ToneMap::default()) {
            Err(CompositeError::NonFinite {
                x: 0,
                y: 1,
                layer: Some(l),
                ..
            }) => {
                assert_eq!(l, "image")
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            compare(&Image::new(3, 2), &r, &ToneMap::default()),
            Err(CompositeError::SizeMismatch { .. })
        ));
        assert!(matches!(
            compare_regions(&r, &r, &ToneMap::default(), &[Rect::new(1, 1, 2, 1)]),
            Err(CompositeError::Region { .. })
        ));
    }

    #[test]
    fn ssim_of_itself_is_one() {
        let img = Image::from_fn(17, 13, |x, y| {
            let v = ((x * 7 + y * 3) % 11) as f32 / 10.0;
            [v, 0.5 * v, 1.0 - v]
        });
        let m = compare(&img, &img, &ToneMap::default()).unwrap();
        close(m.ssim, 1.0, 1e-12);
        assert_eq!((m.mae, m.rmse, m.rel_mse), (0.0, 0.0, 0.0));
    }

    #[test]
    fn ssim_of_constant_images_by_hand() {
        // Constant displayed luma a and b: every window has mu = a, b and zero variance, so
        // SSIM = (2ab + C1) / (a^2 + b^2 + C1) * (C2 / C2). Grey 1.0 (luminance 1) and grey
        // 0.214041 (luminance encoded to sRGB 0.5 exactly: ((0.5 + 0.055) / 1.055)^2.4).
        let grey = |v: f32| Image::filled(12, 12, Vec3::splat(v));
        let dark = crate::tonemap::srgb_decode(0.5);
        let m = compare(&grey(dark), &grey(1.0), &ToneMap::default()).unwrap();
        let (a, b) = (0.5f64, 1.0f64);
        // (2 * 0.5 + 1e-4) / (0.25 + 1 + 1e-4) = 1.0001 / 1.2501 = 0.800016
        close(
            m.ssim,
            (2.0 * a * b + SSIM_C1) / (a * a + b * b + SSIM_C1),
            2e-6,
        );
    }

    /// An independent, direct evaluation: for each pixel, loop over the 11 x 11 window, keep the
    /// in-image pixels, weight by exp(-(dx^2 + dy^2) / (2 sigma^2)) and normalise.
    fn ssim_direct(a: &[f32], b: &[f32], w: usize, h: usize) -> f64 {
        let mut total = 0.0;
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let (mut sw, mut sx, mut sy, mut sxx, mut syy, mut sxy) =
                    (0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0);
                for dy in -5i64..=5 {
                    for dx in -5i64..=5 {
                        let (px, py) = (x + dx, y + dy);
                        if px < 0 || py < 0 || px >= w as i64 || py >= h as i64 {
                            continue;
                        }
                        let wt = (-((dx * dx + dy * dy) as f64) / (2.0 * 1.5 * 1.5)).exp();
                        let i = py as usize * w + px as usize;
                        let (u, v) = (f64::from(a[i]), f64::from(b[i]));
                        sw += wt;
                        sx += wt * u;
                        sy += wt * v;
                        sxx += wt * u * u;
                        syy += wt * v * v;
                        sxy += wt * u * v;
                    }
                }
                let (mx, my) = (sx / sw, sy / sw);
                let (vx, vy, cxy) = (sxx / sw - mx * mx, syy / sw - my * my, sxy / sw - mx * my);
                total += ((2.0 * mx * my + 1e-4) * (2.0 * cxy + 9e-4))
                    / ((mx * mx + my * my + 1e-4) * (vx + vy + 9e-4));
            }
        }
        total / (w * h) as f64
    }

    #[test]
    fn ssim_of_a_perturbation_matches_a_direct_evaluation() {
        // A smooth ramp with a bright square; the perturbation adds a fixed +-0.05 pattern.
        let (w, h) = (23usize, 19usize);
        let a: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let sq = (8..14).contains(&x) && (6..12).contains(&y);
                0.2 + 0.02 * x as f32 + if sq { 0.3 } else { 0.0 }
            })
            .collect();
        let b: Vec<f32> = a
            .iter()
            .enumerate()
            .map(|(i, &v)| v + if (i * 7919) % 5 < 2 { 0.05 } else { -0.05 })
            .collect();
        let map = ssim_map(&a, &b, w, h);
        let mean = map.iter().sum::<f64>() / map.len() as f64;
        let direct = ssim_direct(&a, &b, w, h);
        close(mean, direct, 1e-9);
        assert!(mean < 0.99 && mean > 0.3, "{mean}");
        close(
            ssim_map(&a, &a, w, h).iter().sum::<f64>() / (w * h) as f64,
            1.0,
            1e-12,
        );
    }
}
