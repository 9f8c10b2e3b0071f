//! What a solve reports: where it stands ([`SolveProgress`]), its power bookkeeping
//! ([`Energy`], kept alike by both solvers in [`Bookkeeping`]), its consistency figures
//! ([`Residuals`]) and why it returned ([`Finish`]).

use std::time::{Duration, Instant};

use glam::DVec3;

use crate::options::Method;

/// Power bookkeeping, W per channel (scene units): emitted = absorbed + escaped + unshot +
/// remeshing, exactly up to rounding.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Energy {
    /// Total emitted power.
    pub emitted: DVec3,
    /// Absorbed by surfaces (the (1 - rho) part of what arrived).
    pub absorbed: DVec3,
    /// Shot but not received by any element: left through openings, or the discretization
    /// error of the vertex form factors (can then be slightly negative).
    pub escaped: DVec3,
    /// Received and reflected but not shot yet.
    pub unshot: DVec3,
    /// Change of the unshot estimate when adaptive subdivision re-estimated patch radiosities.
    pub remeshing: DVec3,
    /// Power the surfaces sent, of which `escaped` is booked as leaving: progressive
    /// refinement's shots summed, the hierarchical solver's last gather (its surfaces'
    /// exitance times area); lamps and the sky not included.
    pub sent: DVec3,
    /// Power that form factors summing above one would have created: more arriving than was
    /// sent, where surfaces are closer than the mesh resolves (a light a hair's breadth from
    /// a wall). Progressive refinement takes it out of each such shot, so it is not part of
    /// the balance; the hierarchical solver's is its last iteration's, in the balance.
    pub excess: DVec3,
}

impl Energy {
    /// Largest relative imbalance over the channels, |emitted - (sum of the rest)| / emitted.
    pub fn imbalance(&self) -> f64 {
        let rest = self.absorbed + self.escaped + self.unshot + self.remeshing;
        let d = (self.emitted - rest).abs();
        let e = self.emitted.max(DVec3::splat(f64::MIN_POSITIVE));
        (d / e).max_element()
    }

    /// Power the solve created, as a fraction of the emitted power, the largest over the
    /// channels: (absorbed + escaped - emitted) / emitted, with a negative escape (more
    /// arriving than was shot, which no opening can give back) counted as nothing escaping.
    /// A solve that conserves energy has it at or below zero (what is still unshot is neither
    /// absorbed nor escaped); [`crate::Solver::check_energy`] refuses one above
    /// [`ENERGY_TOLERANCE`].
    pub fn created_fraction(&self) -> f64 {
        let e = self.emitted.max(DVec3::splat(f64::MIN_POSITIVE));
        ((self.absorbed + self.escaped.max(DVec3::ZERO) - self.emitted) / e).max_element()
    }

    /// [`Energy::excess`] over the emitted power, the largest over the channels.
    pub fn excess_fraction(&self) -> f64 {
        let e = self.emitted.max(DVec3::splat(f64::MIN_POSITIVE));
        (self.excess.max(DVec3::ZERO) / e).max_element()
    }
}

/// Most power a solve may create ([`Energy::created_fraction`]) before its result is refused
/// ([`crate::SolveError::EnergyCreated`]): 5 % of the emitted power. Both solvers bound their
/// form factors so that no surface sends more than it has (progressive refinement per shot and
/// per re-estimate of a patch's light, the hierarchical solver per leaf, within a quarter of
/// its links' sum for the seven-point averages' errors). Measured with the default options:
/// the Cornell boxes (both solvers) and three of the five generated rooms create none
/// (absorbed plus escaped stay below the emitted by the power still unshot); the hierarchical
/// solver's links create 0.4 % in the spheres room and 1.3 % in the near-light room, and a
/// light 1e-6 of the room in front of a wall 2 % (hierarchical; progressive none).
pub const ENERGY_TOLERANCE: f64 = 0.05;

/// What both solvers keep alike about a solve: its refinement rounds, its clock and its power
/// bookkeeping, reported in [`SolveProgress`]. Crate-private; its fields are the solvers' own.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bookkeeping {
    /// Refinement rounds done (adaptive subdivision, or link refinement).
    pub rounds: u32,
    /// When the solver was created.
    pub started: Instant,
    /// Time spent building the mesh.
    pub meshing: Duration,
    /// Time spent refining.
    pub refining: Duration,
    /// Power bookkeeping, W per channel.
    pub energy: Energy,
    /// Largest relative energy imbalance seen after any step.
    pub worst_imbalance: f64,
}

impl Bookkeeping {
    /// Nothing done yet: the solver started at `started` and spent `meshing` building its mesh.
    pub(crate) fn new(started: Instant, meshing: Duration) -> Self {
        Self {
            rounds: 0,
            started,
            meshing,
            refining: Duration::ZERO,
            energy: Energy::default(),
            worst_imbalance: 0.0,
        }
    }

    /// Notes the current energy imbalance in [`Bookkeeping::worst_imbalance`].
    pub(crate) fn note_imbalance(&mut self) {
        self.worst_imbalance = self.worst_imbalance.max(self.energy.imbalance());
    }

    /// A progress report of `method` with these figures; the solver sets its own counts.
    pub(crate) fn progress(&self, method: Method) -> SolveProgress {
        SolveProgress {
            method,
            shots: 0,
            iterations: 0,
            links: 0,
            clusters: 0,
            unshot_fraction: 0.0,
            rays: 0,
            elements: 0,
            vertices: 0,
            patches: 0,
            refinement_rounds: self.rounds,
            elapsed: self.started.elapsed(),
            meshing: self.meshing,
            refining: self.refining,
            energy: self.energy,
            worst_imbalance: self.worst_imbalance,
        }
    }
}

/// Where a solve stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveProgress {
    /// The solver that runs (never [`Method::Auto`]).
    pub method: Method,
    /// Shots so far (progressive refinement; 0 for the hierarchical solver).
    pub shots: u64,
    /// Gather iterations so far (hierarchical; 0 for progressive refinement).
    pub iterations: u64,
    /// Links between hierarchy nodes (hierarchical; 0 for progressive refinement).
    pub links: usize,
    /// Clusters above the surfaces (hierarchical; 0 for progressive refinement).
    pub clusters: usize,
    /// The convergence measure: residual (unshot) power / emitted power, sums over channels.
    pub unshot_fraction: f64,
    /// Rays cast so far: shadow rays, and the specular transfer's rays (progressive).
    pub rays: u64,
    /// Elements (leaves) now.
    pub elements: usize,
    /// Vertices now.
    pub vertices: usize,
    /// Patches (shooters).
    pub patches: usize,
    /// Adaptive rounds (progressive) or link refinement rounds (hierarchical) done.
    pub refinement_rounds: u32,
    /// Wall-clock time since the solver was created.
    pub elapsed: Duration,
    /// Time spent building the patch and element mesh.
    pub meshing: Duration,
    /// Time spent in adaptive subdivision (including the new vertices' gathering), or in link
    /// refinement (hierarchical).
    pub refining: Duration,
    /// Power bookkeeping.
    pub energy: Energy,
    /// Largest energy imbalance seen after any step.
    pub worst_imbalance: f64,
}

/// Consistency figures of a solve (see [`Solver::residuals`](crate::solver::Solver::residuals)).
/// Serializable (serde derives, no format here) so that the bake manifest records them field by
/// field.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Residuals {
    /// Largest relative energy imbalance seen after any shot.
    pub energy_imbalance: f64,
    /// [`Energy::excess_fraction`]: power that form factors summing above one would have
    /// created, over the emitted power. Near zero unless surfaces are closer than the mesh
    /// resolves.
    #[serde(default)]
    pub energy_excess: f64,
    /// Smallest sampled vertex form-factor row sum.
    pub row_sum_min: f64,
    /// Mean sampled row sum.
    pub row_sum_mean: f64,
    /// Largest sampled row sum.
    pub row_sum_max: f64,
    /// Patch pairs with a non-zero form factor among those sampled.
    pub reciprocity_pairs: usize,
    /// Largest |A_p F_pq - A_q F_qp| / max of the two over the sampled pairs. Large for pairs
    /// seen through small gaps, where a few vertices and shadow rays sample visibility.
    pub reciprocity_spread: f64,
    /// The same, weighted: sum of |A_p F_pq - A_q F_qp| over sum of the larger of the two.
    pub reciprocity_mean: f64,
    /// Power the solve lost, over the emitted power: booked as escaped, but not leaving the
    /// scene by rays cast from the surfaces it lights (a closed room lets nothing out), the
    /// largest over the channels; near zero for a solve that conserves energy. Lost where
    /// surfaces are closer than the element mesh resolves, such as a light almost touching a
    /// wall. `None` where rays from the surfaces cannot tell: lamps or a sky, mirrors or glass.
    #[serde(default)]
    pub energy_lost: Option<f64>,
    /// Standard error of `energy_lost` (the rays' sampling), over the emitted power.
    #[serde(default)]
    pub energy_lost_error: Option<f64>,
}

impl Residuals {
    /// The report from its samples: the worst energy imbalance, the sampled row sums, and
    /// pairs (A_p F_pq, A_q F_qp) of power transfers that reciprocity says are equal.
    pub fn from_samples(
        energy_imbalance: f64,
        energy_excess: f64,
        row_sums: &[f64],
        pairs: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        let (mut spread, mut diff, mut scale, mut n) = (0.0f64, 0.0, 0.0, 0);
        for (a, b) in pairs {
            if a.max(b) > 0.0 {
                spread = spread.max((a - b).abs() / a.max(b));
                diff += (a - b).abs();
                scale += a.max(b);
                n += 1;
            }
        }
        Self {
            energy_imbalance,
            energy_excess,
            row_sum_min: row_sums.iter().copied().fold(f64::INFINITY, f64::min),
            row_sum_mean: row_sums.iter().sum::<f64>() / row_sums.len().max(1) as f64,
            row_sum_max: row_sums.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            reciprocity_pairs: n,
            reciprocity_spread: spread,
            reciprocity_mean: diff / scale.max(f64::MIN_POSITIVE),
            energy_lost: None,
            energy_lost_error: None,
        }
    }
}

/// Why [`Solver::run`](crate::solver::Solver::run) returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finish {
    /// The convergence measure fell below the threshold.
    Converged,
    /// The shot (or iteration) limit was reached.
    MaxShots,
    /// The time budget ran out.
    TimeBudget,
    /// The observer asked to stop.
    Cancelled,
    /// No patch had unshot power left (progressive), or the iterations stopped changing the
    /// solution (hierarchical).
    Exhausted,
}
