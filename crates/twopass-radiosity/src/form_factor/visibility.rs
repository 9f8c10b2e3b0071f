//! The visible fraction of a shooter from a receiving point by stratified shadow rays
//! ([`visibility`], [`VisibilityRays`]), and shaft culling, which finds pairs nothing can
//! come between without a ray ([`shaft_clear`], [`patches_clear`]).

use glam::{DVec3, Vec2, Vec3};
use smart_default::SmartDefault;
use twopass_brdf::random::{hash, unit_f32};
use twopass_scene::{Scene, SurfacePoint};

use super::polygon::SourceTriangle;

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

/// A stratified point on a triangle (corners `p`) for stratum `(i, j)` of `k x k`, jittered by
/// `h`; triangle-square warp of the stratum.
fn stratified_point(p: [DVec3; 3], i: u32, j: u32, k: u32, h: u64) -> (DVec3, [f64; 3]) {
    let u = Vec2::new(
        (i as f32 + unit_f32(h)) / k as f32,
        (j as f32 + unit_f32(hash(h))) / k as f32,
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
