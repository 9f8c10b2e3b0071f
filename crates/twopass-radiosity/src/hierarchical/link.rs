//! A link between two nodes of the hierarchy ([`Link`]) and a candidate link's evaluation
//! ([`Eval`]).

use super::directions::Dir;
use crate::cluster::NodeRef;

/// A link: light from `source` gathered at `receiver`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Link {
    pub(super) receiver: NodeRef,
    pub(super) source: NodeRef,
    /// Transport per unit of what the source sends (its exitance for a surface, its radiant
    /// table entry `dir` for a cluster), visibility included: irradiance at the receiver's
    /// three corners for a surface receiver (point values: what the vertices display); flux
    /// density from direction `dir ^ OPPOSITE` for a cluster receiver (three equal values).
    pub(super) transport: [f32; 3],
    /// The direction from the source's centre to the receiver's, as table bins.
    pub(super) dir: Dir,
    /// Area-averaged irradiance per unit source exitance less the mean of `transport`: what the
    /// linear interpolant of the corner values misses of the light the receiver gets (surface
    /// pairs; zero otherwise), added uniformly over the receiver.
    pub(super) area_correction: f32,
    /// Estimated error of the transport per unit source exitance luminance and receiver
    /// reflectance, as power: receiver area (scene units squared) times form-factor error.
    pub(super) error: f32,
    /// Shadow rays found the pair partly or wholly blocked: its visibility depends on where the
    /// source's light comes from, and is estimated again once the radiosities are known (see
    /// [`HierarchicalSolver::refresh_visibility`](super::state::HierarchicalSolver::refresh_visibility)).
    pub(super) partial: bool,
}

/// A link's evaluation.
pub(super) struct Eval {
    pub(super) transport: [f64; 3],
    /// `transport` before visibility.
    pub(super) open: [f64; 3],
    pub(super) dir: Dir,
    pub(super) area_correction: f64,
    pub(super) error: f64,
    /// An end is a cluster overlapping the other end's bounding sphere: the far-field estimate
    /// does not hold, the link must be refined.
    pub(super) near: bool,
    /// Visibility is partial (some rays blocked, some not).
    pub(super) partial: bool,
    pub(super) rays: u64,
}

impl Eval {
    /// Whether the link carries no light: no corner and no part of the receiver gets any.
    pub(super) fn carries_nothing(&self) -> bool {
        self.transport.iter().all(|&v| v <= 0.0) && self.area_correction <= 0.0
    }
}
