//! The Pareto front of measured (time, error) points and the presets derived from it.

use super::args::PRESET_NAMES;
use super::measure::GATHERED_RADIOSITY;
use super::report::{Reach, SweepRow};
use super::sweep::{RunSpec, SolveSpec};
use crate::pipeline::RenderMethod;
use crate::preset::Preset;

/// Indices of the points no other point beats on both time and error (ties in both keep the
/// first), sorted by time. A point is dominated when another is no slower and no less accurate
/// and strictly better in one of the two. Points with a non-finite coordinate are never on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    // By time, then by error: each point is on the front when it beats the best error so far.
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut best = f64::INFINITY;
    let mut front = Vec::new();
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The cheapest point reaching `target` error, or, when none does, the most accurate one
/// (`false` then). `None` only for no finite point at all.
pub fn cheapest_reaching(points: &[(f64, f64)], target: f64) -> Option<(usize, bool)> {
    let front = pareto_front(points);
    // Along the front, time rises as error falls: the first point under the target is the
    // cheapest of all points under it.
    front
        .iter()
        .find(|&&i| points[i].1 <= target)
        .map(|&i| (i, true))
        .or_else(|| front.last().map(|&i| (i, false)))
}

/// The time at which a method's curve reaches `target` error, interpolated on log-log axes
/// between the two measured points around it on the method's own front; `None` when the curve
/// never reaches it (or starts below it: then the first point's time is an upper bound and is
/// returned as such, flagged `false`).
pub fn time_to_reach(points: &[(f64, f64)], target: f64) -> Option<(f64, bool)> {
    let front = pareto_front(points);
    let first = *front.first()?;
    if points[first].1 <= target {
        return Some((points[first].0, false));
    }
    for pair in front.windows(2) {
        let (a, b) = (points[pair[0]], points[pair[1]]);
        if b.1 <= target {
            let (la, lb, lt) = (a.1.ln(), b.1.ln(), target.ln());
            let s = (lt - la) / (lb - la);
            return Some(((a.0.ln() + s * (b.0.ln() - a.0.ln())).exp(), true));
        }
    }
    None
}

/// The (time, error) point of each row.
fn points(rows: &[SweepRow]) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (r.total_seconds, r.rel_rmse)).collect()
}

/// Marks the global front and each method's own front.
pub(super) fn mark_fronts(rows: &mut [SweepRow]) {
    for i in pareto_front(&points(rows)) {
        rows[i].pareto = true;
    }
    let names: Vec<&'static str> = rows.iter().map(|r| r.method).collect();
    for name in names
        .iter()
        .copied()
        .collect::<std::collections::BTreeSet<_>>()
    {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| names[i] == name).collect();
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (rows[i].total_seconds, rows[i].rel_rmse))
            .collect();
        for j in pareto_front(&pts) {
            rows[idx[j]].method_pareto = true;
        }
    }
}

/// The presets: for each target, the cheapest run reaching it.
pub(super) fn derive_presets(
    rows: &[SweepRow],
    runs: &[RunSpec],
    solves: &[SolveSpec],
    targets: &[f64],
) -> Vec<Preset> {
    // The presets configure `twopass render`, which shows a solve as solved: the final
    // gather over the element mesh is a bake's ([`SolveSpec::gather`]).
    let pts: Vec<(f64, f64)> = points(rows)
        .into_iter()
        .zip(runs)
        .map(|(p, run)| match run.solve.map(|s| solves[s].gather) {
            Some(Some(_)) => (f64::INFINITY, f64::INFINITY),
            _ => p,
        })
        .collect();
    PRESET_NAMES
        .iter()
        .zip(targets)
        .filter_map(|(name, &target)| {
            let (i, reached) = cheapest_reaching(&pts, target)?;
            Some(Preset {
                name: (*name).to_owned(),
                target_rel_rmse: target,
                reached,
                measured_rel_rmse: rows[i].rel_rmse,
                measured_seconds: rows[i].total_seconds,
                method: runs[i].method,
                render: runs[i].render,
                radiosity: runs[i].solve.map(|s| solves[s].knobs),
            })
        })
        .collect()
}

/// Time to reach each target, per method, with the ratio to the path tracer's.
pub(super) fn reach_table(
    rows: &[SweepRow],
    methods: &[RenderMethod],
    targets: &[f64],
) -> Vec<Reach> {
    let curve = |name: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.method == name)
            .map(|r| (r.total_seconds, r.rel_rmse))
            .collect()
    };
    // Each method's curve, and radiosity over a gathered element mesh as one of its own.
    let mut names: Vec<&'static str> = methods.iter().map(|m| m.name()).collect();
    if rows.iter().any(|r| r.method == GATHERED_RADIOSITY) {
        names.push(GATHERED_RADIOSITY);
    }
    let mut out = Vec::new();
    for &target in targets {
        let pt = time_to_reach(&curve(RenderMethod::Reference.name()), target);
        for &name in &names {
            let reached = time_to_reach(&curve(name), target);
            out.push(Reach {
                method: name,
                target_rel_rmse: target,
                seconds: reached.map(|r| r.0),
                interpolated: reached.is_some_and(|r| r.1),
                ratio_to_path_tracer: match (reached, pt) {
                    (Some(a), Some(b)) => Some(a.0 / b.0),
                    _ => None,
                },
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_drops_dominated_points_and_sorts_by_time() {
        // (time, error): 1 is dominated by 0 (slower and worse), 3 by 2, 4 is not finite.
        let pts = [
            (1.0, 0.10),
            (2.0, 0.20),
            (3.0, 0.05),
            (4.0, 0.06),
            (f64::NAN, 0.0),
            (0.5, 0.30),
            (10.0, 0.01),
        ];
        assert_eq!(pareto_front(&pts), vec![5, 0, 2, 6]);
    }

    #[test]
    fn equal_error_keeps_the_faster_point() {
        let pts = [(2.0, 0.1), (1.0, 0.1), (1.0, 0.1)];
        assert_eq!(pareto_front(&pts), vec![1]);
    }

    #[test]
    fn cheapest_reaching_picks_the_first_front_point_under_the_target() {
        let pts = [(1.0, 0.10), (3.0, 0.05), (10.0, 0.01), (2.0, 0.2)];
        assert_eq!(cheapest_reaching(&pts, 0.06), Some((1, true)));
        assert_eq!(cheapest_reaching(&pts, 0.5), Some((0, true)));
        assert_eq!(cheapest_reaching(&pts, 0.001), Some((2, false)));
        assert_eq!(cheapest_reaching(&[], 0.1), None);
    }

    #[test]
    fn time_to_reach_interpolates_a_power_law_exactly() {
        // error = t^-1/2, the Monte Carlo rate: 1 % is reached at t = 10^4.
        let pts: Vec<(f64, f64)> = [1.0f64, 100.0, 1e6]
            .iter()
            .map(|&t| (t, t.powf(-0.5)))
            .collect();
        let (t, interpolated) = time_to_reach(&pts, 0.01).unwrap();
        assert!(interpolated);
        assert!((t / 1e4 - 1.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to_reach(&pts, 1e-4), None);
        assert_eq!(time_to_reach(&pts, 2.0), Some((1.0, false)));
    }
}
