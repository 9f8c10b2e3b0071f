//! The direction tables of clusters: 32 fixed directions, a direction as a blend of the three
//! nearest ([`Dir`]), and the per-direction tables a cluster sends ([`Table`]) and receives
//! ([`Incoming`]) light by.
//!
//! A blend of table entries underestimates any quantity that grows linearly with the cosine
//! to a direction: the three table directions around `u` blend to a vector along `u` but
//! shorter than one (6.7 % on average with 32 directions, up to 19 %), and a flat emitter's
//! intensity or a flat cluster's projected area is read that much too low. Light sent from
//! and intercepted by flat clusters (walls, floors, strip lights split into clusters) would be
//! lost by that share. So a cluster also keeps the exact linear form of its light and area
//! (sums of `area x normal`, [`Linear`]), which holds wherever every surface inside faces the
//! direction (its normal cone lies in front of it); the table serves only directions that
//! graze some of its surfaces ([`Facing`]).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DMat3, DVec3, Mat3, Vec3, Vec4};

/// Directions of the clusters' tables: 16 spread over a hemisphere (a Fibonacci spiral) and
/// their opposites, so that bin `j ^ OPPOSITE` is the opposite of bin `j`.
pub(super) const DIRECTIONS: usize = 32;

/// `j ^ OPPOSITE` is the bin opposite bin `j` (`DIRECTIONS / 2`, a power of two).
pub(super) const OPPOSITE: u8 = (DIRECTIONS / 2) as u8;

pub(super) fn directions() -> [DVec3; DIRECTIONS] {
    let half = DIRECTIONS / 2;
    let golden = PI * (3.0 - 5f64.sqrt());
    std::array::from_fn(|j| {
        let i = j % half;
        let z = 1.0 - (i as f64 + 0.5) / half as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
        if j < half { d } else { -d }
    })
}

/// A direction as a blend of the three nearest table directions: weights `w / 255` (summing
/// to 1) chosen so that the blend points along the direction (barycentric coordinates in the
/// spherical triangle of the three). A surface facing `n` then takes close to `n . u` of a
/// beam from `u`, not the cosine to the nearest table direction, up to 20 degrees off with
/// 32 directions. It keeps the exact direction too (octahedral, 16 bits a coordinate), for
/// the clusters' exact linear forms ([`Linear`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Dir {
    bins: [u8; 3],
    w: [u8; 3],
    oct: [i16; 2],
}

impl Dir {
    /// The blend for unit direction `u`.
    pub(super) fn new(dirs: &[DVec3; DIRECTIONS], u: DVec3) -> Self {
        let mut best = [(0usize, f64::NEG_INFINITY); 3];
        for (j, d) in dirs.iter().enumerate() {
            let c = d.dot(u);
            if c > best[2].1 {
                best[2] = (j, c);
                best.sort_by(|a, b| b.1.total_cmp(&a.1));
            }
        }
        let m = DMat3::from_cols(dirs[best[0].0], dirs[best[1].0], dirs[best[2].0]);
        let raw = if m.determinant().abs() > 1e-9 {
            (m.inverse() * u).max(DVec3::ZERO)
        } else {
            DVec3::X
        };
        let sum = raw.element_sum();
        let raw = if sum > 0.0 { raw / sum } else { DVec3::X };
        let mut w = raw.to_array().map(|x| (x * 255.0).round() as u8);
        // Rounding must not lose or add weight: the largest takes the difference.
        let total: u32 = w.iter().map(|&x| u32::from(x)).sum();
        w[0] = (i64::from(w[0]) + 255 - i64::from(total)).clamp(0, 255) as u8;
        Self {
            bins: best.map(|b| b.0 as u8),
            w,
            oct: encode_octahedral(u),
        }
    }

    /// The opposite direction.
    pub(super) fn opposite(self) -> Self {
        Self {
            bins: self.bins.map(|b| b ^ OPPOSITE),
            w: self.w,
            oct: encode_octahedral(-decode_octahedral(self.oct)),
        }
    }

    /// The exact unit direction (to the octahedral encoding's 1e-4 radians).
    pub(super) fn unit(self) -> DVec3 {
        decode_octahedral(self.oct)
    }

    /// The blend's (bin, weight) pairs.
    pub(super) fn parts(self) -> impl Iterator<Item = (usize, f64)> {
        (0..3).map(move |i| (usize::from(self.bins[i]), f64::from(self.w[i]) / 255.0))
    }

    /// A per-direction quantity read along this direction.
    pub(super) fn read(self, values: &[f32; DIRECTIONS]) -> f64 {
        self.parts().map(|(j, w)| w * f64::from(values[j])).sum()
    }

    /// A per-direction colour read along this direction.
    pub(super) fn read_rgb(self, values: &[Vec3; DIRECTIONS]) -> DVec3 {
        self.parts().map(|(j, w)| values[j].as_dvec3() * w).sum()
    }
}

/// Unit vector `u` on the octahedron, unfolded onto the square and quantised to 16 bits.
fn encode_octahedral(u: DVec3) -> [i16; 2] {
    let l1 = u.x.abs() + u.y.abs() + u.z.abs();
    let (mut x, mut y) = if l1 > 0.0 {
        (u.x / l1, u.y / l1)
    } else {
        (0.0, 0.0)
    };
    if u.z < 0.0 {
        let (fx, fy) = ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum());
        (x, y) = (fx, fy);
    }
    [x, y].map(|v| (v.clamp(-1.0, 1.0) * f64::from(i16::MAX)).round() as i16)
}

/// The unit vector of an octahedral code ([`encode_octahedral`]).
fn decode_octahedral(oct: [i16; 2]) -> DVec3 {
    let [x, y] = oct.map(|v| f64::from(v) / f64::from(i16::MAX));
    let mut v = DVec3::new(x, y, 1.0 - x.abs() - y.abs());
    let t = (-v.z).max(0.0);
    v.x += if v.x >= 0.0 { -t } else { t };
    v.y += if v.y >= 0.0 { -t } else { t };
    v.normalize_or(DVec3::Z)
}

/// Which of a cluster's surfaces face a direction, from its normal cone (unit axis, half-angle
/// in radians).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Facing {
    /// Every surface faces it: the linear form is exact.
    All,
    /// None does: nothing is sent or intercepted that way.
    None,
    /// Some do and some do not (or the cone cannot tell): the table.
    Some,
}

impl Facing {
    /// For unit direction `u` and a cone holding every normal inside, given as its unit axis
    /// and [`Facing::sine`] of its half-angle: every normal is within 90 degrees of `u` when
    /// the axis is within 90 degrees less the half-angle, that is when `axis . u` exceeds the
    /// half-angle's sine (and every normal beyond 90 degrees when it is below minus that).
    pub(super) fn of(axis: DVec3, sine: f64, u: DVec3) -> Self {
        let c = axis.dot(u);
        if c > sine {
            Self::All
        } else if c < -sine {
            Self::None
        } else {
            Self::Some
        }
    }

    /// The sine [`Facing::of`] takes for a cone of half-angle `half` (radians); above one
    /// for a cone of a quarter turn or more, which faces every direction in part.
    pub(super) fn sine(half: f64) -> f64 {
        if half < FRAC_PI_2 { half.sin() } else { 2.0 }
    }
}

/// The linear forms of a cluster's light, per origin (emitted, reflected): the sum over its
/// triangles of power (W per channel) times unit normal, as a matrix whose column `k` is the
/// sum of power x normal component `k`. Times a unit direction that every triangle faces, it
/// is the cluster's radiant intensity times pi toward it, exactly.
pub(super) type Linear = [Mat3; 2];

/// No light.
pub(super) const DARK: Linear = [Mat3::ZERO; 2];

/// A table over the directions, per origin (emitted, reflected light), in f32 to keep
/// clusters small.
pub(super) type Table = [[Vec3; DIRECTIONS]; 2];

pub(super) const EMPTY: Table = [[Vec3::ZERO; DIRECTIONS]; 2];

pub(super) fn add_tables(a: &Table, b: &Table) -> Table {
    std::array::from_fn(|o| std::array::from_fn(|j| a[o][j] + b[o][j]))
}

/// Light arriving at a cluster: per table direction, the flux density (W/m^2 through a plane
/// facing the light) and where within the bin it comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Incoming {
    pub(super) flux: Table,
    /// Per bin: the luminance-weighted sum of the unit directions toward the light's sources
    /// (xyz) and the weights' sum (w), so that xyz / w is the mean direction the bin's light
    /// comes from.
    pub(super) aim: [Vec4; DIRECTIONS],
}

pub(super) const NOTHING: Incoming = Incoming {
    flux: EMPTY,
    aim: [Vec4::ZERO; DIRECTIONS],
};

impl Incoming {
    pub(super) fn add(&self, other: &Self) -> Self {
        Self {
            flux: add_tables(&self.flux, &other.flux),
            aim: std::array::from_fn(|j| self.aim[j] + other.aim[j]),
        }
    }

    /// Irradiance on a surface facing `n`. Each bin's light is taken along the mean direction
    /// it came from, not along the bin's own direction: a beam from `u` is split over the
    /// three bins around `u` (see [`Dir`]), and clamping the cosine to each of those bins'
    /// directions gives a surface nearly edge-on to `u` light from the bin on its side, up to
    /// 20 degrees past its terminator, too bright where only grazing light arrives. Along the
    /// mean direction one beam gives exactly `max(0, n . u)`.
    pub(super) fn facing(&self, dirs: &[DVec3; DIRECTIONS], n: DVec3) -> [DVec3; 2] {
        let along: [f64; DIRECTIONS] = std::array::from_fn(|j| {
            let a = self.aim[j];
            let m = if a.w > 0.0 {
                a.truncate().as_dvec3() / f64::from(a.w)
            } else {
                dirs[j]
            };
            n.dot(m)
        });
        std::array::from_fn(|o| {
            let mut e = DVec3::ZERO;
            for (j, &c) in along.iter().enumerate() {
                if c > 0.0 && self.flux[o][j] != Vec3::ZERO {
                    e += self.flux[o][j].as_dvec3() * c;
                }
            }
            e
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twopass_brdf::random::{hash, unit_f64};

    fn random_unit(k: u64) -> DVec3 {
        let (a, b) = (unit_f64(hash(k)), unit_f64(hash(k ^ 0x51)));
        let z = 1.0 - 2.0 * a;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * b;
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    #[test]
    fn a_direction_keeps_its_exact_unit_vector_and_its_opposite() {
        let dirs = directions();
        for k in 0..10_000 {
            let u = random_unit(k);
            let d = Dir::new(&dirs, u);
            assert!(d.unit().angle_between(u) < 1e-4, "{u} -> {}", d.unit());
            assert!(d.opposite().unit().angle_between(-u) < 1e-4, "{u}");
        }
        // The poles and the octahedron's edges.
        for u in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            -DVec3::Y,
            DVec3::new(1.0, 0.0, -1.0).normalize(),
        ] {
            assert!(Dir::new(&dirs, u).unit().angle_between(u) < 1e-4, "{u}");
        }
    }

    /// Facing agrees with every normal of the cone: 'All' only where each faces `u`, 'None'
    /// only where none does; and the table's blend reads a linear quantity short, which is
    /// why the linear forms exist.
    #[test]
    fn facing_matches_the_normals_in_the_cone_and_the_blend_reads_short() {
        let dirs = directions();
        let (mut short, mut count) = (0.0, 0u32);
        for k in 0..2_000u64 {
            let axis = random_unit(k);
            let half = 1.5 * unit_f64(hash(k ^ 0x77));
            let u = random_unit(k ^ 0x1234);
            let facing = Facing::of(axis, Facing::sine(half), u);
            // Normals on the cone's rim and its axis.
            let side = axis.any_orthonormal_vector();
            let rim: Vec<DVec3> = (0..64)
                .map(|j| {
                    let phi = 2.0 * PI * f64::from(j) / 64.0;
                    let w = side * phi.cos() + axis.cross(side) * phi.sin();
                    (axis * half.cos() + w * half.sin()).normalize()
                })
                .chain([axis])
                .collect();
            let all = rim.iter().all(|n| n.dot(u) > 0.0);
            let none = rim.iter().all(|n| n.dot(u) < 0.0);
            match facing {
                Facing::All => assert!(all, "{axis} {half} {u}"),
                Facing::None => assert!(none, "{axis} {half} {u}"),
                Facing::Some => assert!(!all || !none),
            }
            // A flat surface facing `axis` with unit area: the blend of its table against the
            // exact cosine, where it faces `u` well away from its horizon.
            let c = axis.dot(u);
            if c > 0.5 {
                let table: [f32; DIRECTIONS] =
                    std::array::from_fn(|j| axis.dot(dirs[j]).max(0.0) as f32);
                short += 1.0 - Dir::new(&dirs, u).read(&table) / c;
                count += 1;
            }
        }
        // The three table directions around `u` blend to a vector shorter than one: 6.7 % on
        // average over the sphere (computed apart, by the same construction in numpy).
        let mean = short / f64::from(count);
        assert!(
            mean > 0.03 && mean < 0.12,
            "the blend reads short by {mean}"
        );
    }
}
