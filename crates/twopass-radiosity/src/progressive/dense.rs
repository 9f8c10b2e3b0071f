//! The dense reference: the full system (I - rho F W) B = E + rho E_lamp over the vertices, with the same
//! vertex-to-patch form factors F the shots use and W the patches' area weights, solved by LU
//! decomposition (nalgebra). Progressive refinement converges to its solution.

use glam::DVec3;
use nalgebra::{DMatrix, DVector};

use super::state::ProgressiveSolver;

/// Largest vertex count the dense solve accepts (the matrix is n^2 x 8 bytes: 512 MiB here).
pub const MAX_DENSE_VERTICES: usize = 8192;

/// Solves the full radiosity system on the solver's current mesh. Returns per-vertex radiosity
/// (W/m^2), or `None` when the mesh has more than [`MAX_DENSE_VERTICES`] vertices or the
/// system is singular.
pub fn dense_solve(solver: &mut ProgressiveSolver<'_>) -> Option<Vec<DVec3>> {
    let n = solver.mesh().vertices.len();
    if n > MAX_DENSE_VERTICES {
        return None;
    }
    let rows = solver.form_factor_rows();
    let weights = solver.patch_weights();
    let (rho, emission) = solver.vertex_terms();
    // The lamps' direct light is a source term beside the emission: rho E_lamp.
    let emission: Vec<DVec3> = emission
        .iter()
        .zip(rho)
        .zip(solver.vertex_lamp_irradiance())
        .map(|((&e, &r), &l)| e + r * l)
        .collect();
    let rho = rho.to_vec();
    // K[v][u] = sum_p F[p][v] W[p][u]: radiosity arriving at v per unit radiosity of u.
    let mut k = DMatrix::<f64>::zeros(n, n);
    for (row, w) in rows.iter().zip(&weights) {
        for (v, &f) in row.iter().enumerate() {
            if f > 0.0 {
                for &(u, x) in w {
                    k[(v, u as usize)] += f64::from(f) * x;
                }
            }
        }
    }
    let mut out = vec![DVec3::ZERO; n];
    for c in 0..3 {
        let a = DMatrix::<f64>::from_fn(n, n, |v, u| {
            f64::from(u8::from(v == u)) - rho[v][c] * k[(v, u)]
        });
        let e = DVector::<f64>::from_fn(n, |v, _| emission[v][c]);
        let b = a.lu().solve(&e)?;
        for v in 0..n {
            out[v][c] = b[v];
        }
    }
    Some(out)
}
