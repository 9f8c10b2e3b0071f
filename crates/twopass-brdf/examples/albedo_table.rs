//! Prints the energy albedo of each model by incidence angle, the Cook-Torrance energy loss,
//! and the error of the Blinn-Phong exponent mapping n' = 4n against the Phong highlight.
//!
//! `cargo run --release -p twopass-brdf --example albedo_table`

use glam::Vec3;
use twopass_brdf::check::direction_at_deg;
use twopass_brdf::interface::incident_albedo;
use twopass_brdf::quadrature::{Quadrature, integrate_hemisphere};
use twopass_brdf::{
    BlinnPhongParams, BrdfModel, ComplexIor, CookTorranceParams, FresnelModel, Material,
    ParamError, PhongParams, Rgb, blinn_phong,
};

const ANGLES: [f32; 6] = [0.0, 30.0, 60.0, 80.0, 85.0, 89.9];

fn row(name: &str, m: &BrdfModel) {
    let a: Vec<String> = ANGLES
        .iter()
        .map(|&d| {
            let v = incident_albedo(m, direction_at_deg(d), Quadrature::default()).x;
            format!("{v:>8.4}")
        })
        .collect();
    println!("{name:<40} {}", a.join(""));
}

fn main() -> Result<(), ParamError> {
    println!("energy albedo for light from theta_i (quadrature, accurate to 1e-3)");
    println!(
        "{:<40} {}",
        "model",
        ANGLES.map(|a| format!("{a:>8}")).join("")
    );
    row(
        "lambert rho 0.8",
        &Material::lambert(Rgb::splat(0.8))?.model().unwrap(),
    );
    for normalized in [false, true] {
        let m = Material::phong(PhongParams {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.7),
            exponent: 10.0,
            ambient: Rgb::ZERO,
            normalized,
        })?;
        row(
            &format!("phong normalized={normalized} 0.3/0.7 n 10"),
            &m.model().unwrap(),
        );
        let b = Material::blinn_phong(BlinnPhongParams {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.7),
            exponent: 40.0,
            normalized,
        })?;
        row(
            &format!("blinn normalized={normalized} 0.3/0.7 n' 40"),
            &b.model().unwrap(),
        );
    }
    println!("\nCook-Torrance energy loss, 1 - albedo with F = 1 (index 1 + 1000i)");
    println!(
        "{:<40} {}",
        "roughness m",
        ANGLES.map(|a| format!("{a:>8}")).join("")
    );
    let white = ComplexIor::new(Rgb::ONE, Rgb::splat(1e3))?;
    for m in [0.1f32, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0] {
        let ct = Material::cook_torrance(CookTorranceParams {
            diffuse: Rgb::ZERO,
            specular: Rgb::ONE,
            roughness: m,
            ior: white,
            fresnel: FresnelModel::Exact,
        })?
        .model()
        .unwrap();
        let loss: Vec<String> = ANGLES
            .iter()
            .map(|&d| {
                let a = incident_albedo(&ct, direction_at_deg(d), Quadrature::default()).x;
                format!("{:>8.4}", 1.0 - a)
            })
            .collect();
        println!("{:<40} {}", format!("m = {m}"), loss.join(""));
    }

    println!(
        "\nBlinn-Phong with n' = 4n against Phong of exponent n (both lobes peak 1, no 1/cos):"
    );
    println!("relative L1 difference  int |B - P| / int P  over outgoing directions");
    println!(
        "{:<10} {}",
        "n",
        [0.0f32, 30.0, 60.0, 80.0]
            .map(|a| format!("{a:>9}"))
            .join("")
    );
    for n in [10.0f32, 100.0, 1000.0] {
        let nb = blinn_phong::exponent_matching_phong(n);
        let cells: Vec<String> = [0.0f32, 30.0, 60.0, 80.0]
            .iter()
            .map(|&d| {
                let wi = direction_at_deg(d);
                let mirror = Vec3::new(-wi.x, -wi.y, wi.z);
                let q = Quadrature::default();
                let p = |wo: Vec3| f64::from(wo.dot(mirror)).max(0.0).powf(f64::from(n));
                let b = |wo: Vec3| {
                    let h = (wo + wi).normalize();
                    f64::from(h.z).max(0.0).powf(f64::from(nb))
                };
                let ip = integrate_hemisphere(mirror, q, p);
                let diff = integrate_hemisphere(mirror, q, |wo| (b(wo) - p(wo)).abs());
                format!("{:>8.1}%", 100.0 * diff / ip)
            })
            .collect();
        println!("{:<10} {}", n, cells.join(""));
    }
    Ok(())
}
