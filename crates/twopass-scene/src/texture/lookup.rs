//! Reading a texture: the value at a point (the sampler's filter on the full-resolution level)
//! and the area-weighted mean over a triangle of texture space (from the mip level whose
//! texels fit it).

use glam::Vec2;
use twopass_brdf::Rgb;

use super::raster::{AlbedoTexture, Filter, MipLevel, Texture, Wrap};

/// Texels across a region, about, at the mip level its mean is read from: enough that the
/// level's box filter blurs nothing the region's own size does not.
const TEXELS_ACROSS: f32 = 4.0;

/// Most subdivisions per edge of a region's quadrature (its points: the square of this).
const MAX_SUBDIVISIONS: u32 = 16;

/// Texel index `i` brought into [0, n) by `wrap`.
fn wrapped(i: i64, n: u32, wrap: Wrap) -> usize {
    let n = i64::from(n);
    (match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m >= n { 2 * n - 1 - m } else { m }
        }
    }) as usize
}

impl MipLevel {
    fn texel(&self, x: i64, y: i64, t: &AlbedoTexture) -> Rgb {
        let (x, y) = (
            wrapped(x, self.width, t.wrap_u),
            wrapped(y, self.height, t.wrap_v),
        );
        self.texels[y * self.width as usize + x]
    }

    /// The level read at texture coordinates `uv` (already scaled and offset) with `filter`.
    fn read(&self, uv: Vec2, t: &AlbedoTexture, filter: Filter) -> Rgb {
        let (x, y) = (uv.x * self.width as f32, uv.y * self.height as f32);
        match filter {
            Filter::Nearest => self.texel(x.floor() as i64, y.floor() as i64, t),
            Filter::Linear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (i, j) = (x0 as i64, y0 as i64);
                let top = self.texel(i, j, t) * (1.0 - fx) + self.texel(i + 1, j, t) * fx;
                let bottom =
                    self.texel(i, j + 1, t) * (1.0 - fx) + self.texel(i + 1, j + 1, t) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }
}

impl Texture {
    /// The linear value at texture coordinates `uv` as `t` reads it: its scale and offset
    /// applied, its wrap modes and filter on the full-resolution level.
    pub fn sample(&self, t: &AlbedoTexture, uv: Vec2) -> Rgb {
        self.levels[0].read(uv * t.scale + t.offset, t, t.filter)
    }

    /// The area-weighted mean value over the triangle of texture space with corners `uv` (as
    /// `t` reads them: scaled, offset, wrapped). The level read is the one on which the
    /// triangle spans about 4 texels (the full resolution for smaller ones);
    /// the mean is the midpoint rule over a uniform subdivision of the triangle into n^2 equal
    /// triangles, n = four times the texels across on that level (4 to 16),
    /// reading the level bilinearly: exact for a value varying linearly over the triangle, and
    /// within the level's box filter of the exact mean otherwise.
    pub fn mean_over(&self, t: &AlbedoTexture, uv: [Vec2; 3]) -> Rgb {
        let uv = uv.map(|p| p * t.scale + t.offset);
        let base = &self.levels[0];
        let (e1, e2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let texel_area = 0.5 * e1.perp_dot(e2).abs() * base.width as f32 * base.height as f32;
        let across = texel_area.sqrt();
        let level = if across.is_finite() && across > TEXELS_ACROSS {
            ((across / TEXELS_ACROSS).log2().floor() as usize).min(self.levels.len() - 1)
        } else {
            0
        };
        let across_level = across / (1u64 << level) as f32;
        let n = if across_level.is_finite() {
            ((4.0 * across_level).ceil() as u32).clamp(4, MAX_SUBDIVISIONS)
        } else {
            MAX_SUBDIVISIONS
        };
        let l = &self.levels[level];
        let inv = 1.0 / n as f32;
        let at = |b1: f32, b2: f32| l.read(uv[0] + e1 * b1 + e2 * b2, t, Filter::Linear);
        let mut sum = Rgb::ZERO;
        for i in 0..n {
            for j in 0..n - i {
                let (fi, fj) = (i as f32, j as f32);
                sum += at((fi + 1.0 / 3.0) * inv, (fj + 1.0 / 3.0) * inv);
                if i + j + 1 < n {
                    sum += at((fi + 2.0 / 3.0) * inv, (fj + 2.0 / 3.0) * inv);
                }
            }
        }
        sum / (n * n) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::super::pyramid;
    use super::*;

    fn texture(width: u32, height: u32, f: impl Fn(u32, u32) -> Rgb) -> Texture {
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect();
        Texture {
            name: "test".into(),
            levels: pyramid::build(MipLevel {
                width,
                height,
                texels,
            }),
        }
    }

    /// Bilinear look-ups at texel centres give the texels; halfway between two texels, their
    /// mean; nearest look-ups the texel the point is in; each wrap mode maps an outside point
    /// where it should.
    #[test]
    fn point_lookups_follow_filter_and_wrap() {
        let tex = texture(4, 1, |x, _| Rgb::splat(x as f32));
        let mut t = AlbedoTexture::new(0);
        let at = |t: &AlbedoTexture, u: f32| tex.sample(t, Vec2::new(u, 0.5)).x;
        assert_eq!(at(&t, 0.375), 1.0);
        assert_eq!(at(&t, 0.5), 1.5);
        // Repeat: u = 1.125 is texel 0's centre again; u = 0 is halfway between 3 and 0.
        assert_eq!(at(&t, 1.125), 0.0);
        assert_eq!(at(&t, 0.0), 1.5);
        t.wrap_u = Wrap::ClampToEdge;
        assert_eq!(at(&t, 0.0), 0.0);
        assert_eq!(at(&t, 7.0), 3.0);
        t.wrap_u = Wrap::MirroredRepeat;
        // u = 1.125 is in the mirrored copy: texel 3.
        assert_eq!(at(&t, 1.125), 3.0);
        t.filter = Filter::Nearest;
        t.wrap_u = Wrap::Repeat;
        assert_eq!(at(&t, 0.49), 1.0);
        t.scale = Vec2::splat(2.0);
        t.offset = Vec2::new(0.25, 0.0);
        // 0.2 * 2 + 0.25 = 0.65: texel 2.
        assert_eq!(at(&t, 0.2), 2.0);
    }

    /// The mean over a region equals the analytic mean of a known texture over it: a 64 x 64
    /// ramp (value = u at each texel centre, so the bilinear image is u itself inside the
    /// texel centres) averaged over a triangle is u at the triangle's centroid; a 2 x 2
    /// checker of a and b repeated 8 times each way, averaged over the whole square (two
    /// triangles, read from the 1 x 1 level), is (a + b) / 2, and a corner inside one texel
    /// is its own colour.
    #[test]
    fn region_means_match_the_analytic_means() {
        let ramp = texture(64, 64, |x, _| Rgb::splat((x as f32 + 0.5) / 64.0));
        let t = AlbedoTexture {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            ..AlbedoTexture::new(0)
        };
        for tri in [
            [
                Vec2::new(0.1, 0.1),
                Vec2::new(0.9, 0.2),
                Vec2::new(0.3, 0.8),
            ],
            [
                Vec2::new(0.2, 0.3),
                Vec2::new(0.25, 0.3),
                Vec2::new(0.2, 0.34),
            ],
        ] {
            let centroid = (tri[0] + tri[1] + tri[2]).x / 3.0;
            let m = ramp.mean_over(&t, tri);
            assert!((m.x - centroid).abs() < 1e-5, "{} vs {centroid}", m.x);
        }
        let (a, b) = (Rgb::new(0.8, 0.1, 0.1), Rgb::new(0.1, 0.7, 0.1));
        let checker = texture(2, 2, |x, y| if (x + y).is_multiple_of(2) { a } else { b });
        let t = AlbedoTexture {
            scale: Vec2::splat(8.0),
            ..AlbedoTexture::new(0)
        };
        let whole = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let other = [Vec2::X, Vec2::ONE, Vec2::Y];
        let mean = (checker.mean_over(&t, whole) + checker.mean_over(&t, other)) * 0.5;
        // f32 sums of up to 256 samples: rounding below 256 * 2^-24 * 0.8 = 1.2e-5.
        assert!(
            (mean - (a + b) * 0.5).abs().max_element() < 1.2e-5,
            "{mean}"
        );
        // A quarter of the top-left texel's interior, at full resolution, nearest texels only.
        let t = AlbedoTexture {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
            ..AlbedoTexture::new(0)
        };
        let corner = [Vec2::ZERO, Vec2::new(0.25, 0.0), Vec2::new(0.0, 0.25)];
        assert!((checker.mean_over(&t, corner) - a).abs().max_element() < 1e-6);
    }
}
