//! Form factors from a receiving point to a shooting polygon: the exact differential-area-to-
//! polygon form factor (Lambert's contour integral over the polygon's edges) for the
//! unoccluded part, times the visible fraction measured with stratified shadow rays.

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};
use smart_default::SmartDefault;
use twopass_scene::{Scene, SurfacePoint};
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
    centroid: DVec3,
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

/// How many shadow rays a visibility estimate may use.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq, Eq)]
pub struct VisibilityRays {
    /// Rays of the first, coarse estimate (rounded to a square number), at least 1.
    #[default(4)]
    pub min: u32,
    /// Rays when the coarse estimate is partial or the receiver is close (square), >= `min`.
    #[default(16)]
    pub max: u32,
}

impl VisibilityRays {
    /// Rays of the first, coarse estimate as [`visibility`] casts them: `min` rounded to the
    /// nearest square (at least 1).
    pub fn coarse(&self) -> u32 {
        grid_side(self.min).pow(2)
    }
}

/// The side of the square grid of stratified shadow rays nearest to `count` rays (at least 1).
fn grid_side(count: u32) -> u32 {
    (f64::from(count).sqrt().round() as u32).max(1)
}

/// `MIN,MAX`, as the command line writes it (`4,16`).
impl std::fmt::Display for VisibilityRays {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.min, self.max)
    }
}

/// A small counter-based hash (SplitMix64): random numbers from (seed, ids) that do not depend
/// on thread scheduling; the workspace's one home of random streams.
pub(crate) use twopass_brdf::random::hash;

fn unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A stratified point on a triangle (corners `p`) for stratum `(i, j)` of `k x k`, jittered by
/// `h`; triangle-square warp of the stratum.
fn stratified_point(p: [DVec3; 3], i: u32, j: u32, k: u32, h: u64) -> (DVec3, [f64; 3]) {
    let u = Vec2::new(
        (i as f32 + unit(h)) / k as f32,
        (j as f32 + unit(hash(h))) / k as f32,
    );
    let s = f64::from(u.x).sqrt();
    let (b1, b2) = (s * (1.0 - f64::from(u.y)), s * f64::from(u.y));
    let w = [1.0 - b1 - b2, b1, b2];
    (p[0] * w[0] + p[1] * w[1] + p[2] * w[2], w)
}

/// Whether nothing in the scene can block any segment from receiver `from` to shooter
/// triangle `shooter` (shaft culling, [`twopass_scene::Accel::shaft_clear`], with the
/// receiver's plane: what lies behind it cannot block). Then [`visibility`] is 1 without a
/// ray, up to [`twopass_scene::SHAFT_TOLERANCE`]: at a vertex on a crease, where shadow rays
/// leave one surface already a hair beyond the other and find it blocking, the shaft sees
/// both surfaces meet at the vertex and blocking nothing.
pub fn shaft_clear(scene: &Scene, from: &SurfacePoint, shooter: [DVec3; 3]) -> bool {
    scene.accel().shaft_clear(
        from.position,
        Some(from.normal),
        shooter.map(|c| c.as_vec3()),
    )
}

/// Whether nothing in the scene can block any segment between receiver patch `receiver` and
/// shooter patch `shooter` (each its corners and its scene triangle's unit geometric normal):
/// shaft culling with the convex hull of the two, [`twopass_scene::Accel::shaft_clear_between`].
/// Every point of the receiver then sees the whole shooter, and its [`visibility`] is 1
/// without a ray or its own test, [`shaft_clear`], whose tetrahedron lies inside this hull.
/// The hull clears some pairs that test cannot: a vertex on a crease lies in the plane of the
/// wall it meets, and its tetrahedron to that wall is flat.
pub fn patches_clear(
    scene: &Scene,
    (receiver, receiver_normal): ([DVec3; 3], Vec3),
    (shooter, shooter_normal): ([DVec3; 3], Vec3),
) -> bool {
    scene.accel().shaft_clear_between(
        receiver.map(|c| c.as_vec3()),
        receiver_normal,
        shooter.map(|c| c.as_vec3()),
        shooter_normal,
    )
}

/// A shooter triangle prepared for [`visibility`] and its form factors: its corners and scene
/// triangle, and what every estimate from it needs (the corners' barycentrics on the scene
/// triangle, its longest edge, centroid and reach), computed once per shooter instead of once
/// per receiver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shooter {
    /// Its corners, as the source of point form factors.
    pub source: SourceTriangle,
    /// The scene triangle the shooter lies on.
    pub triangle: u32,
    /// Barycentrics of each corner on the scene triangle.
    barycentric: [[f64; 3]; 3],
    /// Longest edge, scene units.
    size: f64,
}

impl Shooter {
    /// The shooter with corners `corners` on scene triangle `triangle` of `scene`.
    pub fn new(scene: &Scene, corners: [DVec3; 3], triangle: u32) -> Self {
        Self {
            source: SourceTriangle::new(corners),
            triangle,
            barycentric: corners.map(|c| scene.mesh.barycentric(triangle, c)),
            size: (corners[1] - corners[0])
                .length()
                .max((corners[2] - corners[0]).length())
                .max((corners[2] - corners[1]).length()),
        }
    }
}

/// The visible fraction of `shooter` from receiver `from`, by stratified shadow rays. Samples
/// behind the receiver's plane do not count. Starts with `rays.min` rays and goes to `rays.max`
/// when they disagree or when the receiver is closer than twice the shooter's size; when the
/// finer grid nests the coarser (4 and 16 rays: 2 x 2 and 4 x 4), the coarse samples are kept
/// as samples of the fine grid, and only the fine strata without one get a ray. Deterministic
/// for a `seed`. Returns the fraction and the number of shadow rays cast.
pub fn visibility(
    scene: &Scene,
    from: &SurfacePoint,
    receiver_normal: Vec3,
    shooter: &Shooter,
    rays: VisibilityRays,
    seed: u64,
) -> (f64, u64) {
    let x = from.position.as_dvec3();
    let Shooter {
        source:
            SourceTriangle {
                corners: shooter,
                centroid,
                ..
            },
        triangle: shooter_tri,
        barycentric,
        size,
    } = *shooter;
    // Only a finer grid than the first asks how near the shooter is.
    let near = || (centroid - x).length() < 2.0 * size;
    // One shadow ray to a point of stratum (i, j) of the shooter's k x k grid, jittered by `h`:
    // `None` when the point is behind the receiver's plane (it does not count), else whether
    // the segment is unblocked.
    let sample = |i: u32, j: u32, k: u32, h: u64| -> Option<bool> {
        let (p, w) = stratified_point(shooter, i, j, k, h);
        if (p - x).dot(receiver_normal.as_dvec3()) <= 0.0 {
            return None;
        }
        // The sample's barycentrics on the scene triangle, from the corners' (the map is
        // affine), instead of solving for them per ray.
        let b = [0, 1, 2].map(|c| {
            (barycentric[0][c] * w[0] + barycentric[1][c] * w[1] + barycentric[2][c] * w[2]) as f32
        });
        let target = scene.mesh.surface_point(shooter_tri, b);
        Some(!scene.occluded_between(from, &target))
    };
    let (k1, k2) = (grid_side(rays.min), grid_side(rays.max.max(rays.min)));
    // When the fine grid splits every coarse stratum into r x r whole ones, each coarse sample
    // is drawn in one of its fine strata chosen at random (so it is still uniform over the
    // coarse stratum), and the fine estimate keeps it: that stratum gets no second ray.
    let r = k2 / k1;
    let nested = k2 % k1 == 0 && r > 1 && (k1 * k1) as usize <= FIRST_PASS_MAX;
    // The coarse samples, kept only when the fine grid nests them (not filled otherwise).
    let mut first = nested.then_some([(0u32, None::<bool>); FIRST_PASS_MAX]);
    let (mut seen, mut total) = (0u32, 0u32);
    for i in 0..k1 {
        for j in 0..k1 {
            let h = hash(seed ^ (u64::from(i) << 32 | u64::from(j)));
            let result = if nested {
                let sub = (hash(h ^ 0x5eed) % u64::from(r * r)) as u32;
                let result = sample(i * r + sub / r, j * r + sub % r, k2, h);
                if let Some(first) = &mut first {
                    first[(i * k1 + j) as usize] = (sub, result);
                }
                result
            } else {
                sample(i, j, k1, h)
            };
            if let Some(open) = result {
                total += 1;
                seen += u32::from(open);
            }
        }
    }
    let mut cast = u64::from(total);
    if k2 == k1 || (total > 0 && !near() && (seen == 0 || seen == total)) {
        if total > 0 {
            return (f64::from(seen) / f64::from(total), cast);
        }
    } else {
        let mut new = 0u32;
        (seen, total) = (0, 0);
        for i in 0..k2 {
            for j in 0..k2 {
                let kept = first
                    .as_ref()
                    .map(|f| f[((i / r) * k1 + j / r) as usize])
                    .filter(|&(sub, _)| sub == (i % r) * r + j % r);
                let result = match kept {
                    Some((_, result)) => result,
                    None => {
                        let h = hash(seed ^ 0x5151_5151 ^ (u64::from(i) << 32 | u64::from(j)));
                        let result = sample(i, j, k2, h);
                        new += u32::from(result.is_some());
                        result
                    }
                };
                if let Some(open) = result {
                    total += 1;
                    seen += u32::from(open);
                }
            }
        }
        cast += u64::from(new);
        if total > 0 {
            return (f64::from(seen) / f64::from(total), cast);
        }
    }
    // Only a sliver is above the receiver's horizon: one ray to the shooter's centroid.
    let target = scene.mesh.surface_point_at(shooter_tri, centroid.as_vec3());
    let open = !scene.occluded_between(from, &target);
    (f64::from(u8::from(open)), cast + 1)
}

/// Most coarse strata whose samples [`visibility`] keeps for its fine estimate (an 8 x 8 grid).
const FIRST_PASS_MAX: usize = 64;

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
