//! The exact unoccluded form factor from a differential area to a polygon (Lambert's contour
//! integral over the polygon's edges, clipped to the receiver's hemisphere), for one point
//! ([`point_to_polygon`]) or many points to one prepared triangle ([`SourceTriangle`]), four
//! at a time.

use std::f64::consts::PI;

use glam::DVec3;
use wide::f64x4;

/// Relative distance (height over distance) under which a point counts as lying in a plane:
/// about 20 f32 ulps, the rounding of vertices computed in f32.
const PLANE_TOLERANCE: f64 = 1e-6;

/// Fraction of the way from a receiving vertex toward its element's (or triangle's) centroid
/// at which it receives: a vertex on a junction lies in the plane of the surface it meets,
/// which it would see edge-on (F = 0); from just inside its own surface it gets the limit the
/// form factor converges to.
pub(crate) const RECEIVER_INSET: f64 = 1e-5;

/// The unoccluded form factor from a differential area at `x` with unit normal `n` to the
/// polygon `poly` (vertices in order, any winding), seen from the front of the polygon only
/// when `shooter_normal` is given (one-sided: zero when `x` is behind it).
///
/// The polygon is clipped to the receiver's upper hemisphere, then
/// F = 1/(2 pi) |sum_k gamma_k n . (R_k x R_k+1) / |R_k x R_k+1||, where R_k are the vertices
/// relative to `x` and gamma_k the angle between consecutive ones. It stays bounded where the
/// receiver touches the polygon (an edge through `x` contributes nothing), unlike the disc
/// approximation, and is exact for any distance.
pub fn point_to_polygon(x: DVec3, n: DVec3, poly: &[DVec3], shooter_normal: Option<DVec3>) -> f64 {
    let (centroid, reach) = centroid_and_reach(poly);
    prepared_point_to_polygon(x, n, poly, centroid, reach, shooter_normal)
}

/// A polygon's centroid (the mean of its vertices) and its reach (the largest distance of a
/// vertex from the centroid), as [`point_to_polygon`] measures "in the polygon's plane" by.
fn centroid_and_reach(poly: &[DVec3]) -> (DVec3, f64) {
    let centroid = poly.iter().sum::<DVec3>() / poly.len() as f64;
    let reach = poly
        .iter()
        .map(|p| (*p - centroid).length())
        .fold(0.0, f64::max);
    (centroid, reach)
}

/// A triangle prepared as the source of many point form factors: [`point_to_polygon`] to it,
/// bit for bit, from any number of points, with what every evaluation needs (its centroid and
/// reach) computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceTriangle {
    /// Corners, scene units.
    pub corners: [DVec3; 3],
    /// The mean of the corners, scene units.
    pub(super) centroid: DVec3,
    /// Largest distance of a corner from the centroid, scene units.
    reach: f64,
}

impl SourceTriangle {
    /// The triangle with corners `corners`.
    pub fn new(corners: [DVec3; 3]) -> Self {
        let (centroid, reach) = centroid_and_reach(&corners);
        Self {
            corners,
            centroid,
            reach,
        }
    }

    /// [`point_to_polygon`] from `x` (unit normal `n`) to this triangle: the unoccluded form
    /// factor, one-sided when `shooter_normal` is given.
    pub fn form_factor(&self, x: DVec3, n: DVec3, shooter_normal: Option<DVec3>) -> f64 {
        prepared_point_to_polygon(
            x,
            n,
            &self.corners,
            self.centroid,
            self.reach,
            shooter_normal,
        )
    }

    /// [`SourceTriangle::form_factor`] (dimensionless, in [0, 1]) from four points `x` (scene
    /// units, as the shooter's corners) with unit normals `n` at once, bit for bit: the
    /// operations of the scalar evaluation in four f64 lanes where no corner lies near the
    /// receiver's plane (none clipped), the scalar evaluation for the lanes where one does.
    pub fn form_factors(
        &self,
        x: [DVec3; 4],
        n: [DVec3; 4],
        shooter_normal: Option<DVec3>,
    ) -> [f64; 4] {
        let splat = f64x4::splat;
        let lanes = |v: [DVec3; 4]| {
            [
                f64x4::new(v.map(|p| p.x)),
                f64x4::new(v.map(|p| p.y)),
                f64x4::new(v.map(|p| p.z)),
            ]
        };
        let dot = |a: [f64x4; 3], b: [f64x4; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (xs, ns) = (lanes(x), lanes(n));
        // Lanes known to give 0 (behind the shooter, or the shooter wholly below the
        // receiver's horizon) and lanes left to the scalar evaluation (a corner near the
        // receiver's plane, or across it).
        let mut zero = 0u32;
        if let Some(normal) = shooter_normal {
            let c = self.centroid;
            let d = [xs[0] - splat(c.x), xs[1] - splat(c.y), xs[2] - splat(c.z)];
            let height = dot(d, [splat(normal.x), splat(normal.y), splat(normal.z)]);
            let bound = splat(PLANE_TOLERANCE) * (splat(self.reach) + dot(d, d).sqrt());
            zero |= height.simd_le(bound).to_bitmask();
        }
        let arms = self
            .corners
            .map(|p| [splat(p.x) - xs[0], splat(p.y) - xs[1], splat(p.z) - xs[2]]);
        let (mut above, mut below) = (0b1111u32, 0b1111u32);
        for r in &arms {
            // Clear of the plane as `prepared_point_to_polygon` decides it without a root.
            let h = dot(*r, ns);
            let margin = splat(1.75 * PLANE_TOLERANCE) * r[0].abs().max(r[1].abs()).max(r[2].abs());
            above &= h.simd_gt(margin).to_bitmask();
            below &= (-h).simd_gt(margin).to_bitmask();
        }
        zero |= below & !above;
        let scalar = !(above | zero) & 0b1111;
        let mut sum = splat(0.0);
        for k in 0..3 {
            let (r0, r1) = (arms[k], arms[(k + 1) % 3]);
            let c = [
                r0[1] * r1[2] - r1[1] * r0[2],
                r0[2] * r1[0] - r1[2] * r0[0],
                r0[0] * r1[1] - r1[0] * r0[1],
            ];
            let len = dot(c, c).sqrt();
            let skip = len.simd_le(splat(1e-300))
                | dot(r0, r0).simd_eq(splat(0.0))
                | dot(r1, r1).simd_eq(splat(0.0));
            let gamma = len.atan2(dot(r0, r1));
            sum = skip.select(sum, sum + gamma * dot(ns, c) / len);
        }
        let f = (sum.abs() / splat(2.0 * PI)).to_array();
        std::array::from_fn(|i| {
            if zero & (1 << i) != 0 {
                0.0
            } else if scalar & (1 << i) != 0 {
                self.form_factor(x[i], n[i], shooter_normal)
            } else {
                f[i].min(1.0)
            }
        })
    }

    /// [`SourceTriangle::form_factor`] from every point `x[i]` (unit normal `n[i]`) into
    /// `out[i]`, four at a time ([`SourceTriangle::form_factors`]).
    ///
    /// # Panics
    /// When the three slices differ in length.
    pub fn form_factors_into(
        &self,
        x: &[DVec3],
        n: &[DVec3],
        shooter_normal: Option<DVec3>,
        out: &mut [f64],
    ) {
        assert!(x.len() == n.len() && x.len() == out.len());
        for (start, out) in (0..x.len()).step_by(4).zip(out.chunks_mut(4)) {
            let at = |i: usize| (start + i).min(x.len() - 1);
            let f = self.form_factors(
                [0, 1, 2, 3].map(|i| x[at(i)]),
                [0, 1, 2, 3].map(|i| n[at(i)]),
                shooter_normal,
            );
            out.copy_from_slice(&f[..out.len()]);
        }
    }
}

/// [`point_to_polygon`] with the polygon's centroid and reach given.
fn prepared_point_to_polygon(
    x: DVec3,
    n: DVec3,
    poly: &[DVec3],
    centroid: DVec3,
    reach: f64,
    shooter_normal: Option<DVec3>,
) -> f64 {
    if let Some(ns) = shooter_normal
        && (x - centroid).dot(ns) <= PLANE_TOLERANCE * (reach + (x - centroid).length())
    {
        return 0.0;
    }
    // Clip against the receiver's tangent plane (Sutherland-Hodgman, one plane). Heights within
    // a hair of the plane count as on it: a polygon lying in the receiver's plane subtends no
    // projected solid angle, but rounding would otherwise leave it a full 2 pi of winding.
    // One plane adds at most one vertex per edge; a triangle or quad clips on the stack.
    let mut stack = [DVec3::ZERO; 8];
    let mut heap = Vec::new();
    let buffer: &mut [DVec3] = if 2 * poly.len() <= stack.len() {
        &mut stack
    } else {
        heap.resize(2 * poly.len(), DVec3::ZERO);
        &mut heap
    };
    let h = |p: DVec3| {
        let r = p - x;
        let d = r.dot(n);
        // Far off the plane (|r| is at most sqrt(3) times its largest component, and 1.75
        // leaves room for rounding) no square root decides it.
        if d.abs() > (1.75 * PLANE_TOLERANCE) * r.abs().max_element() {
            d
        } else if d.abs() <= PLANE_TOLERANCE * r.length() {
            0.0
        } else {
            d
        }
    };
    let mut len = 0;
    let mut hb = h(poly[0]);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let ha = hb;
        hb = h(b);
        if ha > 0.0 {
            buffer[len] = a;
            len += 1;
        }
        if (ha > 0.0) != (hb > 0.0) && ha != hb {
            let t = ha / (ha - hb);
            buffer[len] = a + (b - a) * t;
            len += 1;
        }
    }
    let clipped = &buffer[..len];
    if clipped.len() < 3 {
        return 0.0;
    }
    // Per edge: the angle it subtends (four edges at a time, with the arctangent
    // `SourceTriangle::form_factors` uses), times the cosine of its plane's normal to the
    // receiver's; summed edge by edge.
    let mut sum = 0.0;
    for first in (0..clipped.len()).step_by(4) {
        // (|r0 x r1|, r0 . r1, n . (r0 x r1)) per edge; zero for an edge that contributes
        // nothing: zero-length arms or an edge through x (the bounded limit).
        let mut arms = [(0.0, 0.0, 0.0); 4];
        for (k, arm) in (first..clipped.len().min(first + 4)).zip(&mut arms) {
            let r0 = clipped[k] - x;
            let r1 = clipped[(k + 1) % clipped.len()] - x;
            let c = r0.cross(r1);
            let len = c.length();
            if len > 1e-300 && r0.length_squared() != 0.0 && r1.length_squared() != 0.0 {
                *arm = (len, r0.dot(r1), n.dot(c));
            }
        }
        let gamma = f64x4::new(arms.map(|a| a.0)).atan2(f64x4::new(arms.map(|a| a.1)));
        for (gamma, (len, _, normal)) in gamma.to_array().into_iter().zip(arms) {
            if len > 0.0 {
                sum += gamma * normal / len;
            }
        }
    }
    (sum.abs() / (2.0 * PI)).min(1.0)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    fn square(z: f64, half: f64) -> Vec<DVec3> {
        vec![
            DVec3::new(-half, -half, z),
            DVec3::new(half, -half, z),
            DVec3::new(half, half, z),
            DVec3::new(-half, half, z),
        ]
    }

    #[test]
    fn differential_area_below_a_square_matches_closed_forms() {
        // Siegel & Howell: unit square at height 1 above a differential area at its centre.
        let f = point_to_polygon(DVec3::ZERO, DVec3::Z, &square(1.0, 0.5), None);
        assert!((f - 0.239456).abs() < 1e-6, "{f}");
        let f = point_to_polygon(DVec3::ZERO, DVec3::Z, &square(0.1, 0.5), None);
        assert!((f - 0.968340).abs() < 1e-6, "{f}");
    }

    #[test]
    fn coaxial_disc_limit() {
        // A 256-gon approximates a disc of radius R at height H: F = R^2 / (R^2 + H^2).
        let (r, hgt) = (0.7_f64, 1.3_f64);
        let n = 256;
        let poly: Vec<DVec3> = (0..n)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / n as f64;
                DVec3::new(r * a.cos(), r * a.sin(), hgt)
            })
            .collect();
        // Inscribed polygon area ratio n sin(2pi/n)/(2pi) corrects to first order.
        let area_ratio = n as f64 * (2.0 * PI / n as f64).sin() / (2.0 * PI);
        let exact = r * r / (r * r + hgt * hgt);
        let f = point_to_polygon(DVec3::ZERO, DVec3::Z, &poly, None);
        assert!(
            (f - exact * area_ratio).abs() < 1e-4 * exact,
            "{f} vs {exact}"
        );
    }

    #[test]
    fn touching_receivers_stay_bounded() {
        // A unit square wall standing on the x axis, receiver on the floor at the junction.
        let wall = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        for x in [0.0, 0.5, 1.0, 1e-9] {
            for y in [0.0, 1e-12, 1e-6] {
                let f = point_to_polygon(DVec3::new(x, y, 0.0), DVec3::Z, &wall, None);
                assert!(
                    f.is_finite() && (0.0..=0.5 + 1e-9).contains(&f),
                    "{f} at {x}, {y}"
                );
            }
        }
        // Approaching the junction from the room, F converges (no blow-up, unlike the disc
        // approximation, whose 1/r^2 diverges there).
        let near = point_to_polygon(DVec3::new(0.5, 1e-6, 0.0), DVec3::Z, &wall, None);
        let nearer = point_to_polygon(DVec3::new(0.5, 1e-9, 0.0), DVec3::Z, &wall, None);
        assert!(
            (near - nearer).abs() < 1e-5 && near < 0.5,
            "{near} vs {nearer}"
        );
        // A wall much larger than the distance to its edges fills the receiver's half of the
        // hemisphere toward it: F -> 1/2 (Siegel & Howell, perpendicular plates sharing an edge).
        let big = [
            DVec3::new(-1e4, 0.0, 0.0),
            DVec3::new(1e4, 0.0, 0.0),
            DVec3::new(1e4, 0.0, 1e4),
            DVec3::new(-1e4, 0.0, 1e4),
        ];
        let f = point_to_polygon(DVec3::new(0.0, 1e-3, 0.0), DVec3::Z, &big, None);
        assert!((f - 0.5).abs() < 1e-4, "{f}");
    }

    #[test]
    fn coplanar_polygons_contribute_nothing() {
        let sq = square(0.0, 0.5);
        // The receiver inside, on the edge of, and outside a polygon in its own plane, with
        // rounding noise in the heights.
        for x in [
            DVec3::new(0.1, 0.2, 1e-9),
            DVec3::new(0.5, 0.0, -1e-9),
            DVec3::new(2.0, 0.0, 0.0),
        ] {
            assert_eq!(
                point_to_polygon(x, DVec3::Z, &sq, Some(DVec3::Z)),
                0.0,
                "{x}"
            );
            assert_eq!(point_to_polygon(x, DVec3::Z, &sq, None), 0.0, "{x}");
        }
    }

    #[test]
    fn one_sided_and_clipped() {
        let sq = square(1.0, 0.5);
        // Shooter facing +z: a receiver below it is behind, sees nothing.
        assert_eq!(
            point_to_polygon(DVec3::ZERO, DVec3::Z, &sq, Some(DVec3::Z)),
            0.0
        );
        assert!(point_to_polygon(DVec3::ZERO, DVec3::Z, &sq, Some(-DVec3::Z)) > 0.0);
        // A receiver facing away sees nothing; one tilted sideways sees part of it.
        assert_eq!(point_to_polygon(DVec3::ZERO, -DVec3::Z, &sq, None), 0.0);
        let side = point_to_polygon(DVec3::ZERO, DVec3::X, &sq, None);
        assert!(side > 0.0 && side < 0.239456);
    }

    /// A unit vector from two uniform numbers.
    fn direction(u: f64, v: f64) -> DVec3 {
        let z = 2.0 * u - 1.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * v;
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// The four-lane evaluation gives the scalar one's value bit for bit for every lane,
    /// whatever its neighbours, at scene scales from 1e-4 to 1e5: receivers in front of,
    /// behind and in the plane of the shooter, facing it, away from it and edge-on, with
    /// corners near the receiver's plane (the lanes left to the scalar evaluation) and across
    /// it (clipped).
    #[test]
    fn four_lanes_agree_with_the_scalar_evaluation() {
        let mut r = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let mut lanes_of = [0usize; 3];
        for scale in [1e-4, 1.0, 1e5] {
            for _ in 0..2000 {
                let mut u = || r.random::<f64>();
                let corners = [0, 1, 2].map(|_| DVec3::new(u(), u(), u()) * scale);
                let source = SourceTriangle::new(corners);
                let ns = (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .normalize();
                let mut points = Vec::new();
                for k in 0..8 {
                    let (x, n) = match k {
                        // Anywhere around it, any normal.
                        0..=3 => (
                            DVec3::new(u(), u(), u()) * 3.0 * scale - scale,
                            direction(u(), u()),
                        ),
                        // In the shooter's plane.
                        4 => (
                            corners[0] + (corners[1] - corners[0]) * (3.0 * u() - 1.0),
                            direction(u(), u()),
                        ),
                        // With a corner in (or a hair off) the receiver's plane.
                        5 | 6 => {
                            let x = DVec3::new(u(), u(), u()) * 3.0 * scale - scale;
                            let arm = corners[(u() * 3.0) as usize % 3] - x;
                            let side = direction(u(), u()).cross(arm).normalize();
                            let tilt = if k == 5 { 0.0 } else { 4e-6 * (u() - 0.5) };
                            (x, (side + arm.normalize() * tilt).normalize())
                        }
                        // Facing the shooter's centroid head-on.
                        _ => {
                            let x = DVec3::new(u(), u(), u()) * 3.0 * scale - scale;
                            (x, (source.centroid - x).normalize())
                        }
                    };
                    points.push((x, n));
                }
                let shooter_normal = if u() < 0.8 { Some(ns) } else { None };
                let scalar: Vec<f64> = points
                    .iter()
                    .map(|&(x, n)| source.form_factor(x, n, shooter_normal))
                    .collect();
                // Each point in every lane of a batch beside the others.
                for shift in 0..4 {
                    let at = |i: usize| points[(i + shift) % points.len()];
                    let f = source.form_factors(
                        [0, 1, 2, 3].map(|i| at(i).0),
                        [0, 1, 2, 3].map(|i| at(i).1),
                        shooter_normal,
                    );
                    for i in 0..4 {
                        let expected = scalar[(i + shift) % points.len()];
                        assert_eq!(
                            f[i].to_bits(),
                            expected.to_bits(),
                            "scale {scale}, lane {i}: {} vs {expected}",
                            f[i]
                        );
                        assert!(f[i].is_finite() && (0.0..=1.0).contains(&f[i]));
                    }
                }
                let mut all = vec![0.0; points.len()];
                let (x, n): (Vec<DVec3>, Vec<DVec3>) = points.iter().copied().unzip();
                source.form_factors_into(&x, &n, shooter_normal, &mut all);
                assert_eq!(all, scalar);
                for f in &scalar {
                    lanes_of[usize::from(*f > 0.0) + usize::from(*f >= 0.1)] += 1;
                }
            }
        }
        // The draws reach zero, small and large form factors alike.
        assert!(lanes_of.iter().all(|&c| c > 200), "{lanes_of:?}");
    }

    /// The four-lane path against closed forms: the unit square at height 1 above a
    /// differential area at its centre (Siegel & Howell, 0.239456) and at height 0.1
    /// (0.968340), as two triangles, each evaluated from four receivers at once.
    #[test]
    fn four_lanes_match_closed_forms() {
        for (height, exact) in [(1.0, 0.239456), (0.1, 0.968340)] {
            let sq = square(height, 0.5);
            let total: f64 = [[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]]
                .iter()
                .map(|&t| {
                    let f = SourceTriangle::new(t).form_factors(
                        [DVec3::ZERO; 4],
                        [DVec3::Z; 4],
                        Some(-DVec3::Z),
                    );
                    assert!(f.iter().all(|&v| v == f[0]));
                    f[0]
                })
                .sum();
            assert!((total - exact).abs() < 1e-6, "{total} vs {exact}");
        }
    }
}
