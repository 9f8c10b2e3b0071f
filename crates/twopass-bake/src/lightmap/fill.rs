//! The texels of one atlas region: the solution's radiance at every texel centre on a
//! triangle, then the padding filled by dilation within the chart.

use glam::Vec2;
use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;

use super::layout::{Layout, Region};

/// One region's texels (its rectangle, row-major), which of them hold a value, and how many
/// texel centres lie on a triangle.
pub(super) fn fill_region(
    region: &Region,
    layout: &Layout,
    radiance: &dyn DiffuseRadiance,
    padding: u32,
) -> (Vec<Rgb>, Vec<bool>, usize) {
    let [w, h] = region.size;
    let mut value = vec![Rgb::ZERO; (w * h) as usize];
    let mut filled = vec![false; (w * h) as usize];
    let origin = Vec2::new(region.at[0] as f32, region.at[1] as f32);
    let mut covered = 0;
    for &t in &region.triangles {
        let [a, b, c] = layout.corners[t as usize].map(|p| p - origin);
        let det = (b - a).perp_dot(c - a);
        if det.abs() <= f32::MIN_POSITIVE {
            continue;
        }
        let weights = |p: Vec2| {
            let w1 = (p - a).perp_dot(c - a) / det;
            let w2 = (b - a).perp_dot(p - a) / det;
            [1.0 - w1 - w2, w1, w2]
        };
        let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
        let hi = a.max(b).max(c).ceil().min(Vec2::new(w as f32, h as f32));
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let bary = weights(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                if bary.iter().all(|&k| k >= -1e-5) {
                    let i = (y * w + x) as usize;
                    covered += usize::from(!filled[i]);
                    value[i] = radiance.radiance(t, bary.map(|k| k.max(0.0)));
                    filled[i] = true;
                }
            }
        }
        // A sliver may cover no texel centre: its centroid's texel still gets its light.
        let centroid = ((a + b + c) / 3.0).max(Vec2::ZERO);
        let (x, y) = (
            (centroid.x as u32).min(w - 1),
            (centroid.y as u32).min(h - 1),
        );
        let i = (y * w + x) as usize;
        if !filled[i] {
            value[i] = radiance.radiance(t, [1.0 / 3.0; 3]);
            filled[i] = true;
            covered += 1;
        }
    }
    // Dilation: each pass gives every empty texel the mean of its filled 8-neighbours.
    for _ in 0..padding {
        let (before_v, before_f) = (value.clone(), filled.clone());
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if before_f[i] {
                    continue;
                }
                let (mut sum, mut n) = (Rgb::ZERO, 0u32);
                for dy in -1i32..=1 {
                    for dx in -1i32..=1 {
                        let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                        if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                            continue;
                        }
                        let j = (ny as u32 * w + nx as u32) as usize;
                        if before_f[j] {
                            sum += before_v[j];
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    value[i] = sum / n as f32;
                    filled[i] = true;
                }
            }
        }
    }
    (value, filled, covered)
}
