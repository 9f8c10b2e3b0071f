//! What a closest-hit query keeps and answers: the nearest hit so far ([`Nearest`]), the
//! answer ([`TriangleHit`]), and the rule that keeps the nearer of two hits whatever order a
//! walk meets them in.

use glam::Vec3;

/// The nearest hit a closest-hit walk has found so far (its `t` is the walk's `t_max`).
#[derive(Clone, Copy)]
pub(super) struct Nearest {
    /// Where its quad starts in the tree's arena.
    pub(super) quad: u32,
    /// Its lane in the quad.
    pub(super) lane: usize,
    /// Scene triangle index.
    pub(super) id: u32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2.
    pub(super) barycentric: [f32; 3],
}

/// The result of a closest-hit query: which triangle, where along the ray, barycentrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Scene triangle index.
    pub triangle: u32,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2 (sum 1).
    pub barycentric: [f32; 3],
    /// Positions of the triangle's vertices 0, 1, 2 (the mesh's, bit for bit), from the
    /// accelerator's copy that the test just read, so the caller need not fetch them again.
    pub corners: [Vec3; 3],
}

/// `t.next_up()` four times over for a positive `t` (a hit's distance; at most infinity): one
/// integer add on its bits, capped at infinity's, the bits of consecutive positive floats
/// being consecutive integers. The general `next_up` steps (with their checks for zero,
/// negative and NaN, which a hit's distance never is) cost more than the add.
#[inline(always)]
pub(super) fn four_ulps_up(t: f32) -> f32 {
    debug_assert!(t > 0.0, "{t} is not a hit's distance");
    f32::from_bits((t.to_bits() + 4).min(f32::INFINITY.to_bits()))
}

/// The bound a closest-hit walk tests a ray's next triangles with: its `t_max`, and once it
/// has a hit (`best`), a few ulps beyond, so that a triangle at exactly the hit's `t` is not
/// rounded away by the test's early rejection and [`keep_nearer`] decides between them.
#[inline(always)]
pub(super) fn search_bound(t_max: f32, best: &Option<Nearest>) -> f32 {
    if best.is_some() {
        four_ulps_up(t_max)
    } else {
        t_max
    }
}

/// Keeps a hit of triangle `id` at `t` (`found` forms it) as the ray's nearest hit (`best`,
/// its `t` in `t_max`) when it is nearer, or as near with a smaller triangle index: the
/// answer then does not depend on the order a walk meets triangles in.
#[inline(always)]
pub(super) fn keep_nearer(
    best: &mut Option<Nearest>,
    t_max: &mut f32,
    t: f32,
    id: u32,
    found: impl FnOnce() -> Nearest,
) {
    if best.is_none_or(|b| t < *t_max || (t == *t_max && id < b.id)) {
        *t_max = t;
        *best = Some(found());
    }
}
