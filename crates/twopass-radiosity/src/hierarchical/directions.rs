//! The direction tables of clusters: 32 fixed directions, a direction as a blend of the three
//! nearest ([`Dir`]), and the per-direction tables a cluster sends ([`Table`]) and receives
//! ([`Incoming`]) light by.

use std::f64::consts::PI;

use glam::{DMat3, DVec3, Vec3, Vec4};

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
/// 32 directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Dir {
    bins: [u8; 3],
    w: [u8; 3],
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
        }
    }

    /// The opposite direction.
    pub(super) fn opposite(self) -> Self {
        Self {
            bins: self.bins.map(|b| b ^ OPPOSITE),
            w: self.w,
        }
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
