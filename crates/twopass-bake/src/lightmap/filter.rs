//! The denoiser of a gathered lightmap: an edge-aware à-trous wavelet filter in atlas space
//! (Dammertz et al. 2010, with the variance-guided luminance weight of Schied et al. 2017,
//! SVGF), applied to the indirect part only. The direct part, which carries every shadow
//! boundary, is left as the gather computed it (its stratified shadow rays keep its noise low),
//! so the filter never blurs a shadow edge; the indirect light it smooths varies slowly except
//! where the geometry changes, and the weights stop at those changes:
//! - **chart and object**: a texel never takes light from another chart or object (texels side
//!   by side in the atlas may lie far apart on the surface);
//! - **position**: nor from a texel farther from it on the surface than the atlas distance
//!   allows, or off its tangent plane (a crease or a step inside one chart);
//! - **normal**: the weight falls as (n_i . n_j)^[`NORMAL_POWER`];
//! - **luminance**: the weight falls with the difference of the two indirect luminances in
//!   units of their estimated standard errors, so a real change in the light (a contact
//!   shadow) survives while noise is averaged out.

use glam::Vec3;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance;

/// The filter in words, as the manifest records it.
pub const FILTER: &str = "edge-aware a-trous wavelet (3 passes, steps 1, 2, 4 texels) on the \
    indirect part only, stopped by chart, object, position, normal and variance-scaled luminance";

/// What the filter knows of one covered texel.
#[derive(Debug, Clone, Copy)]
pub(super) struct Guide {
    /// Index in the region (row-major).
    pub(super) texel: u32,
    /// The texel centre on the surface, scene units.
    pub(super) position: Vec3,
    /// Unit shading normal there.
    pub(super) normal: Vec3,
    /// Chart id (texels of different charts never mix).
    pub(super) chart: u32,
    /// Object index (texels of different objects never mix).
    pub(super) object: u32,
    /// Standard error of the texel's indirect luminance, W/(m^2 sr).
    pub(super) error: f32,
}

/// Passes of the à-trous filter: steps 1, 2, 4 texels (a 17 x 17 footprint).
const PASSES: u32 = 3;

/// The B3-spline taps of the à-trous kernel.
const TAPS: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// Exponent of the normal weight.
const NORMAL_POWER: i32 = 32;

/// Luminance differences, in standard errors of the difference, at which the weight falls
/// to 1/e.
const LUMINANCE_SIGMA: f32 = 4.0;

/// Distance off the texel's tangent plane, in texel edges, at which the weight falls to 1/e.
const PLANE_SIGMA: f32 = 0.5;

/// The indirect light `indirect` (one value per guide, in guide order) of a region `size`
/// texels wide and high, denoised; `texel_size` is a texel's edge on the surface, scene units.
pub(super) fn denoise(
    guides: &[Guide],
    indirect: &[Rgb],
    size: [u32; 2],
    texel_size: f32,
) -> Vec<Rgb> {
    let [w, h] = size;
    // Which guide covers each texel of the region.
    let mut at = vec![u32::MAX; (w * h) as usize];
    for (k, g) in guides.iter().enumerate() {
        at[g.texel as usize] = k as u32;
    }
    let variance: Vec<f32> = guides.iter().map(|g| g.error * g.error).collect();
    let mut current = indirect.to_vec();
    for pass in 0..PASSES {
        let step = 1i32 << pass;
        // Farther than this from the centre on the surface, a texel is not the centre's
        // neighbour however close in the atlas (another part of the chart, folded).
        let reach = texel_size * (step as f32) * 2.0 * 1.5 + texel_size;
        let max_distance2 = reach * reach * 2.0;
        current = guides
            .par_iter()
            .enumerate()
            .map(|(k, g)| {
                let (x, y) = ((g.texel % w) as i32, (g.texel / w) as i32);
                let centre = current[k];
                let yc = luminance(centre);
                let (mut sum, mut total) = (Rgb::ZERO, 0.0f32);
                for (dy, ty) in (-2i32..=2).zip(TAPS) {
                    for (dx, tx) in (-2i32..=2).zip(TAPS) {
                        let (nx, ny) = (x + dx * step, y + dy * step);
                        if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                            continue;
                        }
                        let j = at[(ny as u32 * w + nx as u32) as usize];
                        if j == u32::MAX {
                            continue;
                        }
                        let o = &guides[j as usize];
                        if o.chart != g.chart || o.object != g.object {
                            continue;
                        }
                        let d = o.position - g.position;
                        if d.length_squared() > max_distance2 {
                            continue;
                        }
                        let plane = g.normal.dot(d).abs() / (PLANE_SIGMA * texel_size);
                        let cos = g.normal.dot(o.normal).max(0.0);
                        let sigma = LUMINANCE_SIGMA * (variance[k] + variance[j as usize]).sqrt()
                            + 1e-6 * yc.abs();
                        let lum = (luminance(current[j as usize]) - yc).abs() / sigma.max(1e-30);
                        let weight =
                            tx * ty * cos.powi(NORMAL_POWER) * (-plane * plane - lum).exp();
                        if weight > 0.0 && weight.is_finite() {
                            sum += current[j as usize] * weight;
                            total += weight;
                        }
                    }
                }
                if total > 0.0 { sum / total } else { centre }
            })
            .collect();
    }
    current
}
