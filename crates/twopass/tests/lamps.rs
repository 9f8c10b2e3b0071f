//! Lamps through the command line: bad `[[light]]` tables exit 1 with the file, line, table
//! index and problem; `info` lists the lamps; a scene lit by lamps alone is rendered, not
//! refused; a bake's gathered lightmap holds their light.

use std::path::Path;

use crate::common::{assert_exit, assert_ok, cli, ok_json, twopass};

/// A grey floor seen from above (lines 1 to 14), then `lights` (or a `[sky]`).
pub(crate) fn floor_with(lights: &str) -> String {
    format!(
        "version = 1\n\
         [camera]\nposition = [0, 2, 2]\nlook_at = [0, 0, 0]\nfov_y = 50\nresolution = [16, 16]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"quad\", origin = [-1, 0, -1], edge_u = [0, 0, 2], edge_v = [2, 0, 0] }}\n\
         {lights}"
    )
}

pub(crate) fn write(dir: &Path, text: &str) -> std::path::PathBuf {
    let path = dir.join("lamps.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn bad_light_tables_exit_1_naming_the_line_table_and_problem() {
    let dir = tempfile::tempdir().unwrap();
    let good = "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 1\n";
    // Each bad table is the second light, starting at line 19 (the floor takes lines 1 to
    // 14, the good point lamp 15 to 18).
    #[rustfmt::skip]
    let cases = [
        ("[[light]]\nkind = \"point\"\nname = \"neg\"\nposition = [0, 1, 0]\nintensity = -2\n",
         ":19: light 2 `neg`: `intensity` must be finite and non-negative (got -2 W/sr)"),
        ("[[light]]\nkind = \"area\"\nposition = [0, 1, 0]\n",
         ":20:8: unknown variant `area`, expected one of `point`, `spot`, `directional`"),
        ("[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nintensity = 1\ninner_angle = 30\nouter_angle = 20\n",
         ":19: light 2: `outer_angle` (20 degrees) is smaller than `inner_angle` (30 degrees)"),
        ("[[light]]\nkind = \"directional\"\ndirection = [0, 0, 0]\nirradiance = 1\n",
         ":19: light 2: `direction` has zero length"),
        ("[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\nlook_at = [0, 1, 0]\nintensity = 1\n",
         ":19: light 2: `look_at` equals `position`: the direction has zero length"),
        ("[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 1\npower = 3\n",
         ":19: light 2: give exactly one of `intensity` (W/sr) and `power` (W)"),
        ("[[light]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\ncolour = [1, -1, 1]\n",
         ":19: light 2: `colour` channel 1 must be finite and non-negative (got -1)"),
    ];
    for (bad, expected) in cases {
        info_fails(dir.path(), &format!("{good}{bad}"), expected);
    }
}

/// `info` on the floor with `tables` ([`floor_with`]) exits 1, printing nothing on stdout
/// and as the first line of stderr the scene's path followed by `expected`.
pub(crate) fn info_fails(dir: &Path, tables: &str, expected: &str) {
    let path = write(dir, &floor_with(tables));
    let out = twopass(&["info", path.to_str().unwrap()]);
    assert_exit(&out, 1);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        err.lines().next().unwrap_or(""),
        format!("error: {}{expected}", path.display()),
        "{tables}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn info_lists_the_lamps_and_plans_a_scene_lit_by_lamps_alone() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        &floor_with(
            "[[light]]\nkind = \"point\"\nname = \"bulb\"\nposition = [0, 1, 0]\npower = 100\n\
             [[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\nlook_at = [0, 0, 0]\nintensity = 2\ninner_angle = 10\nouter_angle = 30\n\
             [[light]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 3\n",
        ),
    );
    let out = twopass(&["info", path.to_str().unwrap()]);
    assert_ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    for line in [
        "lamp       bulb: point at (0, 1, 0), intensity (7.957747e0, 7.957747e0, 7.957747e0) W/sr, power (1.000000e2, 1.000000e2, 1.000000e2)",
        "lamp       light 2: spot at (0, 1, 0) toward (0, -1, 0), cone 10.00 to 30.00 degrees, intensity (2.000000e0, 2.000000e0, 2.000000e0) W/sr",
        "lamp       light 3: directional toward (0, -1, 0), intensity (3.000000e0, 3.000000e0, 3.000000e0) W/m^2",
        "diffuse pass      required: 1 diffusely reflecting object(s) lit by 0 emitter(s) and 3 lamp(s)",
    ] {
        assert!(text.contains(line), "{line}\n{text}");
    }
    let v = ok_json(&twopass(&["info", path.to_str().unwrap(), "--json"]));
    let lamps = v["lamps"].as_array().unwrap();
    assert_eq!(lamps.len(), 3);
    assert_eq!(lamps[0]["kind"], "point");
    let p = lamps[0]["power"][0].as_f64().unwrap();
    assert!((p - 100.0).abs() < 1e-3, "{p}");
    // Lit by lamps alone, the scene renders; nothing is refused as unlit.
    renders_lit(dir.path(), &path, &["radiosity", "hybrid"]);
}

/// The scene at `path` renders with each of `methods` (into folders of `dir`), and nothing
/// refuses it as unlit.
pub(crate) fn renders_lit(dir: &Path, path: &Path, methods: &[&str]) {
    for method in methods {
        let out_dir = dir.join(method);
        let out = cli("render")
            .arg(path)
            .words(&format!("--method {method} --spp 4"))
            .output(&out_dir)
            .run();
        assert_ok(&out);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("nothing emits light"), "{err}");
    }
}

#[test]
fn a_gathered_lightmap_holds_the_lamps_light() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        &floor_with("[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 4\n"),
    );
    let out_dir = dir.path().join("bake");
    let out = cli("bake")
        .arg(&path)
        .words("--format bake --lightmap --gather 16 --json")
        .output(&out_dir)
        .run();
    assert_ok(&out);
    let exr = std::fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "exr"))
        .expect("the lightmap's EXR");
    let image = twopass_composite::write::read_exr(&exr).unwrap();
    // Under the lamp the floor's radiance is rho / pi * I / h^2 = 0.5 / pi * 4; the brightest
    // texel is about there (a texel's centre is near, not at, the foot of the lamp).
    let peak = image.pixels().iter().map(|p| p.x).fold(0.0f32, f32::max);
    let expected = 0.5 / std::f32::consts::PI * 4.0;
    assert!(
        peak > 0.9 * expected && peak < 1.05 * expected,
        "peak {peak} vs {expected}"
    );
}
