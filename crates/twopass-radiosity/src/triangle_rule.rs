//! Quadrature over a triangle in barycentric coordinates.

/// Dunavant's six-point rule for a triangle, exact for polynomials up to degree 4 with
/// positive weights (Dunavant 1985, table of degree 4): barycentric points and weights
/// summing to 1. A hat function times light that varies up to cubically is integrated
/// exactly.
pub const DUNAVANT_6: [([f32; 3], f32); 6] = {
    const A: f32 = 0.816_847_6;
    const B: f32 = 0.091_576_21;
    const C: f32 = 0.108_103_02;
    const D: f32 = 0.445_948_5;
    const WA: f32 = 0.109_951_74;
    const WC: f32 = 0.223_381_6;
    [
        ([A, B, B], WA),
        ([B, A, B], WA),
        ([B, B, A], WA),
        ([C, D, D], WC),
        ([D, C, D], WC),
        ([D, D, C], WC),
    ]
};

#[cfg(test)]
mod tests {
    use super::DUNAVANT_6 as RULE;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    #[test]
    fn the_rule_integrates_every_monomial_up_to_degree_four() {
        // Over a triangle of area A, the mean of l0^a l1^b l2^c is
        // 2 a! b! c! / (a + b + c + 2)! (the Dirichlet integral), for a + b + c <= 4.
        for a in 0..=4u32 {
            for b in 0..=4 - a {
                for c in 0..=4 - a - b {
                    let exact =
                        2.0 * factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 2);
                    let rule: f64 = RULE
                        .iter()
                        .map(|&(w, weight)| {
                            f64::from(weight)
                                * f64::from(w[0]).powi(a as i32)
                                * f64::from(w[1]).powi(b as i32)
                                * f64::from(w[2]).powi(c as i32)
                        })
                        .sum();
                    assert!(
                        (rule - exact).abs() < 1e-6,
                        "l0^{a} l1^{b} l2^{c}: {rule} vs {exact}"
                    );
                }
            }
        }
    }
}
