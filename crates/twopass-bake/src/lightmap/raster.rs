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
}
