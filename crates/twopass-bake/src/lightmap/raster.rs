//! The texel centres an atlas triangle covers, found row by row: per row only the span between
//! the triangle's edges is tested, so the cost is the covered texels plus the rows, never the
//! triangle's bounding box (a long thin diagonal triangle covers few texels of a large box).

use glam::Vec2;

/// Calls `visit(x, y, barycentric)` for every texel centre `(x + 0.5, y + 0.5)` of a grid of
/// `size` texels whose barycentrics in triangle `[a, b, c]` (texel units) all pass `inside`.
/// The barycentrics are computed as `1 - w1 - w2, w1, w2` with `w1`, `w2` from the
/// perp-dot products over the triangle's doubled signed area; a triangle of zero area visits
/// nothing. Each row's candidates are the texels between its crossings of the edges, widened
/// by one texel on each side, so `inside` alone decides, as a test of the whole bounding box
/// would.
pub(super) fn for_each_texel(
    [a, b, c]: [Vec2; 3],
    size: [u32; 2],
    inside: impl Fn([f32; 3]) -> bool,
    mut visit: impl FnMut(u32, u32, [f32; 3]),
) {
    let det = (b - a).perp_dot(c - a);
    if det.abs() <= f32::MIN_POSITIVE {
        return;
    }
    let (w, h) = (size[0] as f32, size[1] as f32);
    let lo_y = a.y.min(b.y).min(c.y).floor().max(0.0);
    let hi_y = a.y.max(b.y).max(c.y).ceil().min(h);
    for y in lo_y as u32..hi_y as u32 {
        let yc = y as f32 + 0.5;
        // The row's crossings of the three edges (an edge along the row gives its ends).
        let (mut x0, mut x1) = (f32::INFINITY, f32::NEG_INFINITY);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let (ylo, yhi) = (p.y.min(q.y), p.y.max(q.y));
            if yc < ylo - 1.0 || yc > yhi + 1.0 {
                continue;
            }
            if (q.y - p.y).abs() <= f32::EPSILON * (p.y.abs() + q.y.abs() + 1.0) {
                x0 = x0.min(p.x.min(q.x));
                x1 = x1.max(p.x.max(q.x));
            } else {
                let t = ((yc - p.y) / (q.y - p.y)).clamp(0.0, 1.0);
                let x = p.x + t * (q.x - p.x);
                x0 = x0.min(x);
                x1 = x1.max(x);
            }
        }
        if x0 > x1 {
            continue;
        }
        let from = (x0 - 1.5).floor().max(0.0) as u32;
        let to = (x1 + 1.5).ceil().min(w).max(0.0) as u32;
        for x in from..to {
            let p = Vec2::new(x as f32 + 0.5, yc);
            let w1 = (p - a).perp_dot(c - a) / det;
            let w2 = (b - a).perp_dot(p - a) / det;
            let bary = [1.0 - w1 - w2, w1, w2];
            if inside(bary) {
                visit(x, y, bary);
            }
        }
    }
}

/// Calls `visit(x, y)` for every texel of a grid of `size` texels whose square
/// `[x, x + 1] x [y, y + 1]` overlaps triangle `[a, b, c]` (texel units) with positive area or
/// along an edge: conservative rasterization. Each row's candidates are the texels over the
/// triangle's extent within the row's band (its edges clipped to the band, and its corners
/// inside it); a candidate is kept unless one of the triangle's edge lines separates it (the
/// separating-axis test, whose other two axes the band and the extent already decide). A
/// triangle of zero area visits nothing.
pub(super) fn for_each_overlapped_texel(
    [a, b, c]: [Vec2; 3],
    size: [u32; 2],
    mut visit: impl FnMut(u32, u32),
) {
    let det = (b - a).perp_dot(c - a);
    if det.abs() <= f32::MIN_POSITIVE {
        return;
    }
    // Inward edge normals (the third corner on the positive side) and their lines' offsets.
    let sign = det.signum();
    let edges = [(a, b), (b, c), (c, a)].map(|(p, q)| {
        let n = (q - p).perp() * sign;
        (n, n.dot(p))
    });
    let (w, h) = (size[0] as f32, size[1] as f32);
    let lo_y = a.y.min(b.y).min(c.y).floor().max(0.0);
    let hi_y = a.y.max(b.y).max(c.y).ceil().min(h);
    let mut y = lo_y;
    while y < hi_y {
        let (band_lo, band_hi) = (y, y + 1.0);
        let (mut x0, mut x1) = (f32::INFINITY, f32::NEG_INFINITY);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            // The part of edge p-q inside the band, by its parameter range.
            let (mut t0, mut t1) = (0.0f32, 1.0f32);
            let dy = q.y - p.y;
            if dy == 0.0 {
                if p.y < band_lo || p.y > band_hi {
                    continue;
                }
            } else {
                let (ta, tb) = ((band_lo - p.y) / dy, (band_hi - p.y) / dy);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
                if t0 > t1 {
                    continue;
                }
            }
            for t in [t0, t1] {
                let x = p.x + t * (q.x - p.x);
                x0 = x0.min(x);
                x1 = x1.max(x);
            }
        }
        if x0 <= x1 {
            let from = x0.floor().max(0.0);
            let to = (x1.floor() + 1.0).min(w);
            let mut x = from;
            while x < to {
                let square = [
                    Vec2::new(x, band_lo),
                    Vec2::new(x + 1.0, band_lo),
                    Vec2::new(x, band_hi),
                    Vec2::new(x + 1.0, band_hi),
                ];
                let separated = edges
                    .iter()
                    .any(|&(n, d)| square.iter().all(|&s| n.dot(s) < d));
                if !separated {
                    visit(x as u32, y as u32);
                }
                x += 1.0;
            }
        }
        y += 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texels the whole bounding box finds, for comparison.
    fn by_box(t: [Vec2; 3], size: [u32; 2], tol: f32) -> Vec<(u32, u32)> {
        let [a, b, c] = t;
        let det = (b - a).perp_dot(c - a);
        let mut out = Vec::new();
        let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
        let hi = a
            .max(b)
            .max(c)
            .ceil()
            .min(Vec2::new(size[0] as f32, size[1] as f32));
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let w1 = (p - a).perp_dot(c - a) / det;
                let w2 = (b - a).perp_dot(p - a) / det;
                if [1.0 - w1 - w2, w1, w2].iter().all(|&k| k >= -tol) {
                    out.push((x, y));
                }
            }
        }
        out
    }

    #[test]
    fn rows_find_exactly_the_texels_the_bounding_box_finds() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let size = [97, 61];
        for k in 0..2000 {
            let scale = if k % 3 == 0 { 100.0 } else { 12.0 };
            let t = [(); 3].map(|_| Vec2::new(next() * scale - 5.0, next() * scale * 0.7 - 3.0));
            let mut rows = Vec::new();
            for_each_texel(
                t,
                size,
                |b| b.iter().all(|&k| k >= -1e-5),
                |x, y, _| rows.push((x, y)),
            );
            assert_eq!(rows, by_box(t, size, 1e-5), "triangle {t:?}");
        }
    }

    #[test]
    fn a_thin_diagonal_triangle_costs_its_rows_not_its_box() {
        // A 4096-texel diagonal sliver: its box holds 16.7 million texels, its rows a few each.
        let t = [
            Vec2::new(0.0, 0.0),
            Vec2::new(4096.0, 4096.0),
            Vec2::new(4096.5, 4095.0),
        ];
        let mut candidates = 0u64;
        for_each_texel(t, [4100, 4100], |_| true, |_, _, _| candidates += 1);
        assert!(candidates < 8 * 4096, "{candidates} texels tested");
    }

    /// Whether the texel square at `(x, y)` and the triangle overlap, by sampling the square
    /// finely and testing each sample against the triangle (with a little slack for samples on
    /// an edge).
    fn overlaps_by_sampling([a, b, c]: [Vec2; 3], x: u32, y: u32) -> bool {
        let det = (b - a).perp_dot(c - a);
        let k = 48;
        (0..=k).any(|i| {
            (0..=k).any(|j| {
                let p = Vec2::new(
                    x as f32 + i as f32 / k as f32,
                    y as f32 + j as f32 / k as f32,
                );
                let w1 = (p - a).perp_dot(c - a) / det;
                let w2 = (b - a).perp_dot(p - a) / det;
                [1.0 - w1 - w2, w1, w2].iter().all(|&w| w >= -1e-6)
            })
        })
    }

    #[test]
    fn conservative_rasterization_finds_every_texel_the_triangle_touches_and_no_other() {
        let mut seed = 11u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let size = [23, 19];
        for k in 0..300 {
            // Slivers thinner than a texel, shallow edges and ordinary triangles.
            let t = if k % 3 == 0 {
                let p = Vec2::new(next() * 20.0, next() * 16.0);
                let d = Vec2::new(next() * 12.0 - 6.0, next() * 12.0 - 6.0);
                [p, p + d, p + d * 0.5 + d.perp().normalize_or_zero() * 0.05]
            } else {
                [(); 3].map(|_| Vec2::new(next() * 26.0 - 2.0, next() * 22.0 - 2.0))
            };
            let mut found = Vec::new();
            for_each_overlapped_texel(t, size, |x, y| found.push((x, y)));
            let mut expected = Vec::new();
            for y in 0..size[1] {
                for x in 0..size[0] {
                    if overlaps_by_sampling(t, x, y) {
                        expected.push((x, y));
                    }
                }
            }
            // Sampling at 1/48 of a texel can miss a corner that only just pokes into a
            // square; every texel it finds must be found, and nothing far from the triangle.
            for e in &expected {
                assert!(found.contains(e), "triangle {t:?}: texel {e:?} missed");
            }
            let extra = found.iter().filter(|f| !expected.contains(f)).count();
            assert!(
                extra <= 2,
                "triangle {t:?}: {extra} texels it does not touch"
            );
        }
    }

    #[test]
    fn a_sliver_thinner_than_a_texel_touches_every_texel_along_its_length() {
        // 0.05 texels tall and 10 long, between two rows of texel centres (the square at x = 12
        // touches its vertical edge).
        let t = [
            Vec2::new(2.0, 3.1),
            Vec2::new(12.0, 3.1),
            Vec2::new(12.0, 3.15),
        ];
        let mut found = Vec::new();
        for_each_overlapped_texel(t, [20, 20], |x, y| found.push((x, y)));
        let expected: Vec<(u32, u32)> = (2..=12).map(|x| (x, 3)).collect();
        assert_eq!(found, expected);
        // Its centres: none.
        let mut centres = 0;
        for_each_texel(
            t,
            [20, 20],
            |b| b.iter().all(|&k| k >= 0.0),
            |_, _, _| centres += 1,
        );
        assert_eq!(centres, 0);
    }
}
