//! Closed forms that several test modules check against, written once.

/// Form factor from a differential area to a parallel rectangle of sides `x` and `y` (in units
/// of the distance between their planes) with one corner straight above the differential area
/// (Howell's catalogue, C-11): F = 1/(2 pi) (X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) +
/// Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))). Any parallel rectangle is a signed sum of four of these.
pub fn corner_form_factor(x: f64, y: f64) -> f64 {
    let (a, b) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / a * (y / a).atan() + y / b * (x / b).atan()) / (2.0 * std::f64::consts::PI)
}

/// Form factor from a point of the plane y = 0 at (x, z), facing up, to the square of side
/// 0.5 at height 1 centred over the origin ([`floor_under_square`]): the signed sum of four
/// [`corner_form_factor`]s.
pub fn square_form_factor(x: f64, z: f64) -> f64 {
    let h = 0.25;
    let c = corner_form_factor;
    c(h - x, h - z) - c(-h - x, h - z) - c(h - x, -h - z) + c(-h - x, -h - z)
}

/// The scene [`square_form_factor`] describes, as scene-file text: a grey (rho 0.5) floor
/// (object 0, 4 x 4 around the origin) under a black square of side 0.5 at height 1 facing
/// down (object 1) that emits `emission` W/(m^2 sr), 0 for none.
pub fn floor_under_square(emission: f32) -> String {
    format!(
        "version = 1\n\
         [camera]\nposition = [0, 0.9, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }}\n\
         [[object]]\nname = \"square\"\nmaterial = \"black\"\nemission = {emission}\n\
         shape = {{ type = \"quad\", origin = [-0.25, 1, -0.25], edge_u = [0.5, 0, 0], edge_v = [0, 0, 0.5] }}\n"
    )
}

#[test]
fn corner_form_factor_matches_quadrature_and_its_limit() {
    // F = integral over the rectangle of cos(theta) cos(theta') / (pi r^2) dA = integral of
    // 1 / (pi (1 + x^2 + y^2)^2), by the midpoint rule.
    let quadrature = |x: f64, y: f64| {
        let n = 400;
        let (dx, dy) = (x / n as f64, y / n as f64);
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f64 + 0.5) * dx, (j as f64 + 0.5) * dy);
                sum += 1.0 / (std::f64::consts::PI * (1.0 + u * u + v * v).powi(2));
            }
        }
        sum * dx * dy
    };
    for (x, y) in [(1.0, 1.0), (0.5, 0.5), (2.0, 0.3)] {
        let (f, q) = (corner_form_factor(x, y), quadrature(x, y));
        assert!((f - q).abs() < 1e-6, "{x} x {y}: {f} vs quadrature {q}");
    }
    // A whole quadrant sees a quarter of the unit disc's area under projection: F -> 1/4.
    assert!((corner_form_factor(1e9, 1e9) - 0.25).abs() < 1e-6);
    assert_eq!(corner_form_factor(0.0, 3.0), 0.0);
}
