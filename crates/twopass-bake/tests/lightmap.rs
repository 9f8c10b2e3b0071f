//! The lightmap bake: the `.glb` holds the scene's own triangles with `TEXCOORD_1` charts that
//! preserve area (texel size x texel size scene units per texel) and do not overlap, the
//! texels near every chart corner are filled (padding), the lightmap carries the solution's
//! radiant power, and its EXR and PNG read back with the `exr` and `png` readers.

use std::sync::OnceLock;

use glam::{DVec2, Vec2, Vec3};
use twopass_bake::lightmap::{AtlasSource, Lightmap, LightmapSettings, TexelSource, bake_lightmap};
use twopass_bake::{self as bake, ColorMapping};
use twopass_radiosity::{Options, Solution, Solver};

use crate::common::{cornell, solved};
use twopass_scene::{DiffuseRadiance, Scene};

const TEXEL: f32 = 5.0;

/// The lightmap of `solution` over `scene` at `texel` scene units per texel, 2 texels of
/// padding, the scene's default quantity, texels from the solution.
fn bake_solution(scene: &Scene, solution: &Solution, texel: f32) -> Lightmap {
    let settings = LightmapSettings {
        texel_size: Some(texel),
        padding: 2,
        quantity: None,
        ..Default::default()
    };
    bake_lightmap(
        TexelSource::Solution(solution),
        scene,
        &settings,
        ColorMapping::auto(solution),
    )
    .unwrap()
}

fn baked() -> &'static (Scene, Solution, Lightmap) {
    static BAKED: OnceLock<(Scene, Solution, Lightmap)> = OnceLock::new();
    BAKED.get_or_init(|| {
        let (scene, solution) = cornell(60.0);
        let lm = bake_solution(&scene, &solution, TEXEL);
        (scene, solution, lm)
    })
}

#[test]
fn the_texel_size_is_the_given_one_or_the_scene_diagonal_over_200() {
    let (scene, solution, given) = baked();
    assert_eq!(given.texel_size, TEXEL);
    let settings = LightmapSettings::default();
    assert_eq!(settings.texel_size, None);
    let derived = bake_lightmap(
        TexelSource::Solution(solution),
        scene,
        &settings,
        ColorMapping::auto(solution),
    )
    .unwrap();
    assert_eq!(derived.texel_size, scene.bounds.diagonal() / 200.0);
}

/// Every triangle of the `.glb`: object name, positions (m) and TEXCOORD_1 (texels).
fn triangles(lm: &Lightmap) -> Vec<(String, [Vec3; 3], [DVec2; 3])> {
    let gltf = gltf::Gltf::from_slice(&lm.glb).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let size = DVec2::new(f64::from(lm.width), f64::from(lm.height));
    let mut out = Vec::new();
    for mesh in gltf.meshes() {
        let prim = mesh.primitives().next().unwrap();
        let material = prim.material();
        let info = material.emissive_texture().expect("emissive lightmap");
        assert_eq!(info.tex_coord(), 1);
        let reader = prim.reader(|_| Some(blob));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let uv: Vec<[f32; 2]> = reader.read_tex_coords(1).unwrap().into_f32().collect();
        // Set 0 repeats the atlas (glTF numbers sets from 0; the scene has no UVs of its own).
        let uv0: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        assert_eq!(uv0, uv);
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        for t in idx.chunks(3) {
            out.push((
                mesh.name().unwrap().to_owned(),
                [0, 1, 2].map(|k| Vec3::from(pos[t[k] as usize])),
                [0, 1, 2].map(|k| Vec2::from(uv[t[k] as usize]).as_dvec2() * size),
            ));
        }
    }
    out
}

#[test]
fn glb_is_the_scene_mesh_with_area_preserving_charts() {
    let (scene, _, lm) = baked();
    let tris = triangles(lm);
    assert_eq!(
        tris.len(),
        scene.mesh.triangle_count(),
        "the user's triangles, not the elements"
    );
    let texel_m = f64::from(TEXEL) * scene.unit.metres();
    let (mut uv_area, mut area) = (0.0, 0.0);
    for (name, p, uv) in &tris {
        let a = f64::from((p[1] - p[0]).cross(p[2] - p[0]).length()) / 2.0;
        let u = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs() / 2.0 * texel_m * texel_m;
        // Each chart is an orthogonal projection onto the triangle's own plane: no stretch.
        assert!(
            (u - a).abs() <= 1e-3 * a,
            "{name}: {u} m^2 in UV, {a} m^2 in space"
        );
        for q in uv {
            assert!(q.x >= 0.0 && q.y >= 0.0, "{name}: {q}");
            assert!(
                q.x <= f64::from(lm.width) && q.y <= f64::from(lm.height),
                "{name}: {q}"
            );
        }
        uv_area += u;
        area += a;
    }
    // The Cornell box's surfaces, from the scene itself, in m^2.
    let expect = scene.total_area() * scene.unit.metres().powi(2);
    assert!((area - expect).abs() < 1e-4 * expect, "{area} vs {expect}");
    assert!((uv_area - expect).abs() < 1e-3 * expect);
    // The charts use the atlas well (packing and padding cost less than half).
    let fill = lm.covered_texels as f64 / f64::from(lm.width * lm.height);
    assert!(
        fill > 0.5,
        "{} covered of {} x {}",
        lm.covered_texels,
        lm.width,
        lm.height
    );
}

fn inside(uv: &[DVec2; 3], p: DVec2, eps: f64) -> Option<[f64; 3]> {
    let det = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
    let w1 = (p - uv[0]).perp_dot(uv[2] - uv[0]) / det;
    let w2 = (uv[1] - uv[0]).perp_dot(p - uv[0]) / det;
    let w = [1.0 - w1 - w2, w1, w2];
    w.iter().all(|&k| k > eps).then_some(w)
}

/// The lightmap's power, summed channels: every texel whose centre lies strictly inside a
/// triangle, its radiance times the surface area it stands for (`texel_area(positions in m,
/// atlas corners in texels)`, scene units squared). Panics if two triangles claim a texel
/// (triangles of one chart may share a centre only on their common edge, which the strict
/// test leaves out).
fn lightmap_power(
    lm: &Lightmap,
    tris: &[(String, [Vec3; 3], [DVec2; 3])],
    texel_area: impl Fn(&[Vec3; 3], &[DVec2; 3]) -> f64,
) -> f64 {
    let w = lm.width as usize;
    let pixels = lm.radiance.pixels();
    let mut owner = vec![false; w * lm.height as usize];
    let mut power = 0.0;
    for (name, pos, uv) in tris {
        let weight = texel_area(pos, uv);
        let lo = uv[0].min(uv[1]).min(uv[2]).floor();
        let hi = uv[0].max(uv[1]).max(uv[2]).ceil();
        for y in lo.y as usize..hi.y as usize {
            for x in lo.x as usize..hi.x as usize {
                let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                if inside(uv, c, 1e-6).is_some() {
                    let j = y * w + x;
                    assert!(!owner[j], "texel ({x}, {y}) of {name} is taken");
                    owner[j] = true;
                    power += f64::from(pixels[j].element_sum()) * weight;
                }
            }
        }
    }
    power
}

/// The solution's integral of L over every element (the linear interpolant's exact mean),
/// summed channels.
fn element_mesh_power(solution: &Solution) -> f64 {
    let mesh = solution.mesh();
    let l = solution.vertex_radiosity();
    mesh.leaves()
        .map(|n| {
            let node = &mesh.nodes[n as usize];
            let mean: f32 = node
                .vertices
                .iter()
                .map(|&v| l[v as usize].element_sum())
                .sum::<f32>()
                / 3.0;
            f64::from(node.area) * f64::from(mean) / std::f64::consts::PI
        })
        .sum()
}

#[test]
fn charts_do_not_overlap_and_carry_the_radiant_power() {
    let (_, solution, lm) = baked();
    let tris = triangles(lm);
    let texel2 = f64::from(TEXEL).powi(2);
    let power_map = lightmap_power(lm, &tris, |_, _| texel2);
    let power_mesh = element_mesh_power(solution);
    // Counting texel centres measures each triangle's area to within about its perimeter
    // times half a 5 mm texel, with errors of both signs; the radiance per texel is the
    // solution's own. Over the whole box: 1 %.
    assert!(
        (power_map / power_mesh - 1.0).abs() < 0.01,
        "lightmap {power_map}, element mesh {power_mesh}"
    );
}

#[test]
fn padding_fills_every_texel_bilinear_filtering_reads_at_the_corners() {
    let (_, _, lm) = baked();
    let pixels = lm.radiance.pixels();
    let w = lm.width as i64;
    for (name, _, uv) in triangles(lm) {
        for q in uv {
            // Bilinear filtering at q reads the 2 x 2 texels around q - 0.5.
            let base = (q - DVec2::splat(0.5)).floor();
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (x, y) = (base.x as i64 + dx, base.y as i64 + dy);
                let v = pixels[(y * w + x) as usize];
                // Every Cornell surface gets light in every channel.
                assert!(
                    v.min_element() > 0.0,
                    "{name}: texel ({x}, {y}) is empty near {q}"
                );
            }
        }
    }
}

#[test]
fn exr_and_png_read_back() {
    let (_, _, lm) = baked();
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("lightmap.exr");
    bake::write_atomic(&exr, &lm.exr).unwrap();
    let back = twopass_composite::write::read_exr(&exr).unwrap();
    assert_eq!(&back, &lm.radiance);
    let decoder = png::Decoder::new(std::io::Cursor::new(&lm.png));
    let reader = decoder.read_info().unwrap();
    assert_eq!(
        (reader.info().width, reader.info().height),
        (lm.width, lm.height)
    );
    // The .glb embeds exactly this PNG.
    let gltf = gltf::Gltf::from_slice(&lm.glb).unwrap();
    let image = gltf.images().next().unwrap();
    let gltf::image::Source::View { view, mime_type } = image.source() else {
        panic!("image not embedded");
    };
    assert_eq!(mime_type, "image/png");
    let blob = gltf.blob.as_deref().unwrap();
    assert_eq!(
        &blob[view.offset()..view.offset() + view.length()],
        lm.png.as_slice()
    );
}

/// A floor under a light, each an OBJ with its own `vt` (light's in `light_vt`), in metres.
fn obj_scene(light_vt: [[f32; 2]; 4]) -> (tempfile::TempDir, Scene) {
    let dir = tempfile::tempdir().unwrap();
    // A horizontal square at height `y`, from `lo` to `hi` in x and z, facing up or down.
    let quad = |name: &str, y: f32, [lo, hi]: [f32; 2], up: bool, vt: [[f32; 2]; 4]| {
        let (a, b) = if up {
            ([lo, hi], [hi, lo])
        } else {
            ([hi, lo], [lo, hi])
        };
        let corners = [[lo, lo], [a[0], a[1]], [hi, hi], [b[0], b[1]]];
        let mut text = String::new();
        for [x, z] in corners {
            text += &format!("v {x} {y} {z}\n");
        }
        for t in vt {
            text += &format!("vt {} {}\n", t[0], t[1]);
        }
        text += "f 1/1 2/2 3/3 4/4\n";
        std::fs::write(dir.path().join(name), text).unwrap();
    };
    let floor_vt = [[0.0, 0.0], [0.0, 0.5], [0.5, 0.5], [0.5, 0.0]];
    quad("floor.obj", 0.0, [0.0, 1.0], true, floor_vt);
    quad("light.obj", 0.9, [0.3, 0.7], false, light_vt);
    let toml = "version = 1\n[camera]\nposition = [0.5, 0.5, -2]\nlook_at = [0.5, 0.5, 0]\n\
                fov_y = 40\n[[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
                [[object]]\nname = \"floor\"\nmaterial = \"white\"\n\
                shape = { type = \"obj\", file = \"floor.obj\" }\n\
                [[object]]\nname = \"light\"\nmaterial = \"white\"\nemission = [10, 10, 10]\n\
                shape = { type = \"obj\", file = \"light.obj\" }\n";
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    let (scene, _) = twopass_scene::load(&path).unwrap();
    (dir, scene)
}

fn bake_obj(scene: &Scene) -> Lightmap {
    let mut solver = Solver::new(scene, Options::default()).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    let solution = solver.solution();
    bake_solution(scene, &solution, 0.01)
}

#[test]
fn obj_texture_coordinates_become_the_lightmap_atlas_when_they_fit() {
    let (_dir, scene) = obj_scene([[0.6, 0.6], [0.9, 0.6], [0.9, 0.9], [0.6, 0.9]]);
    let lm = bake_obj(&scene);
    assert_eq!(lm.atlas, AtlasSource::Scene);
    let gltf = gltf::Gltf::from_slice(&lm.glb).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let floor = gltf.meshes().find(|m| m.name() == Some("floor")).unwrap();
    let prim = floor.primitives().next().unwrap();
    let reader = prim.reader(|_| Some(blob));
    let mut uv: Vec<[f32; 2]> = reader.read_tex_coords(1).unwrap().into_f32().collect();
    uv.sort_by(|a, b| a.partial_cmp(b).unwrap());
    // The OBJ's vt with v flipped (OBJ's v points up, glTF's down).
    assert_eq!(uv, [[0.0, 0.5], [0.0, 1.0], [0.5, 0.5], [0.5, 1.0]]);
    // The floor under the light is lit where its coordinates put it, and the light is bright
    // where its coordinates put it.
    let at = |u: f32, v: f32| {
        let (x, y) = (
            (u * lm.width as f32) as u32,
            ((1.0 - v) * lm.height as f32) as u32,
        );
        lm.radiance.pixels()[(y * lm.width + x) as usize]
    };
    assert!(at(0.25, 0.25).min_element() > 0.0);
    assert!(at(0.75, 0.75).min_element() >= 10.0, "{}", at(0.75, 0.75));
    // Outside every island, nothing (beyond the dilated padding).
    assert_eq!(at(0.75, 0.25), Vec3::ZERO);
}

#[test]
fn overlapping_obj_texture_coordinates_fall_back_to_generated_charts() {
    let (_dir, scene) = obj_scene([[0.1, 0.1], [0.4, 0.1], [0.4, 0.4], [0.1, 0.4]]);
    let lm = bake_obj(&scene);
    match &lm.atlas {
        AtlasSource::Generated(why) => assert!(why.contains("overlap"), "{why}"),
        other => panic!("{other:?}"),
    }
    // The Cornell box's built-in shapes have no coordinates at all.
    let (_, _, cornell) = baked();
    match &cornell.atlas {
        AtlasSource::Generated(why) => assert!(why.contains("no texture coordinates"), "{why}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn curved_surfaces_unwrap_into_few_charts_that_carry_their_power() {
    // The spheres of cornell-spheres.toml (5,120 triangles each) are flattened by conformal
    // maps into a few charts, not one per triangle; a texel then covers a triangle's surface
    // area over its atlas area, and the lightmap's power matches the element mesh's.
    let (scene, solution) = solved("scenes/cornell-spheres.toml", 60.0);
    let texel = 2.0;
    let lm = bake_solution(&scene, &solution, texel);
    assert!(
        lm.charts * 100 < scene.mesh.triangle_count(),
        "{} charts for {} triangles",
        lm.charts,
        scene.mesh.triangle_count()
    );
    // Positions are metres in the .glb, the scene is in millimetres.
    let power_map = lightmap_power(&lm, &triangles(&lm), |pos, uv| {
        let p = pos.map(|q| q.as_dvec3() * 1000.0);
        let area = (p[1] - p[0]).cross(p[2] - p[0]).length() / 2.0;
        area / ((uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs() / 2.0)
    });
    let power_mesh = element_mesh_power(&solution);
    // As for the box: counting texel centres measures each chart's area to within its
    // perimeter times half a texel, with errors of both signs.
    assert!(
        (power_map / power_mesh - 1.0).abs() < 0.01,
        "lightmap {power_map}, element mesh {power_mesh}"
    );
}

/// Barycentrics of `p` in triangle `t` in the horizontal (x, z) plane, if it lies inside.
fn horizontal_barycentric(t: [Vec3; 3], p: Vec3) -> Option<[f32; 3]> {
    let [a, b, c] = t.map(|q| Vec2::new(q.x, q.z));
    let q = Vec2::new(p.x, p.z);
    let det = (b - a).perp_dot(c - a);
    let w1 = (q - a).perp_dot(c - a) / det;
    let w2 = (b - a).perp_dot(q - a) / det;
    let w = [1.0 - w1 - w2, w1, w2];
    w.iter().all(|&k| k >= -1e-4).then_some(w)
}

#[test]
fn a_face_thinner_than_a_texel_is_lit_along_its_whole_length() {
    // A strip 1 m long and 4 mm wide, lit from above one end, baked with 10 mm texels: no
    // texel centre lies on it, yet the lightmap must show the light falling off along it as the
    // solution does (a shelf's front edge, a door frame, a window sill).
    let dir = tempfile::tempdir().unwrap();
    let toml = "version = 1\nunit = \"m\"\n[camera]\nposition = [0.5, 0.5, -2]\n\
                look_at = [0.5, 0, 0.5]\nfov_y = 40\n[[material]]\nname = \"white\"\n\
                type = \"lambert\"\ndiffuse = 0.5\n\
                [[object]]\nname = \"strip\"\nmaterial = \"white\"\nshape = { type = \"quad\", \
                origin = [0, 0, 0.5], edge_u = [0, 0, 0.004], edge_v = [1, 0, 0] }\n\
                [[object]]\nname = \"light\"\nmaterial = \"white\"\nemission = [10, 10, 10]\n\
                shape = { type = \"quad\", origin = [0, 0.3, 0.4], edge_u = [0.2, 0, 0], \
                edge_v = [0, 0, 0.2] }\n";
    let path = dir.path().join("strip.toml");
    std::fs::write(&path, toml).unwrap();
    let (scene, _) = twopass_scene::load(&path).unwrap();
    let mut solver = Solver::new(&scene, Options::default()).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    let solution = solver.solution();
    let lm = bake_solution(&scene, &solution, 0.01);
    let strip = scene
        .objects
        .iter()
        .position(|o| o.name == "strip")
        .unwrap() as u32;
    // The solution along the strip's middle line, from the scene's own triangles.
    let solution_at = |p: Vec3| {
        (0..scene.mesh.triangle_count() as u32)
            .filter(|&t| scene.mesh.object_of(t) == strip)
            .find_map(|t| {
                let corners = scene.mesh.triangle(t).map(|i| scene.mesh.position(i));
                horizontal_barycentric(corners, p).map(|b| solution.radiance(t, b))
            })
            .unwrap()
    };
    // The lightmap there: the .glb's TEXCOORD_1, the texels sampled bilinearly as a GPU does.
    let texel = |x: f32, y: f32| {
        let (x, y) = (
            (x.max(0.0) as u32).min(lm.width - 1),
            (y.max(0.0) as u32).min(lm.height - 1),
        );
        lm.radiance.pixels()[(y * lm.width + x) as usize]
    };
    let lightmap_at = |p: Vec3| {
        triangles(&lm)
            .into_iter()
            .filter(|(name, _, _)| name == "strip")
            .find_map(|(_, pos, uv)| {
                horizontal_barycentric(pos, p).map(|b| {
                    // In texels, texel centres at half-integers.
                    let q =
                        uv[0].as_vec2() * b[0] + uv[1].as_vec2() * b[1] + uv[2].as_vec2() * b[2]
                            - Vec2::splat(0.5);
                    let (x0, y0) = (q.x.floor(), q.y.floor());
                    let (fx, fy) = (q.x - x0, q.y - y0);
                    let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1.0, y0) * fx;
                    let bottom = texel(x0, y0 + 1.0) * (1.0 - fx) + texel(x0 + 1.0, y0 + 1.0) * fx;
                    top * (1.0 - fy) + bottom * fy
                })
            })
            .unwrap()
    };
    let points: Vec<Vec3> = (1..20)
        .map(|k| Vec3::new(k as f32 * 0.05, 0.0, 0.502))
        .collect();
    let sol: Vec<f32> = points.iter().map(|&p| solution_at(p).y).collect();
    // The light falls off along the strip (so a constant per triangle could not pass).
    assert!(sol[1] > 4.0 * sol[18], "{sol:?}");
    for (p, s) in points.iter().zip(&sol) {
        let l = lightmap_at(*p).y;
        assert!(
            (l - s).abs() <= 0.03 * s + 1e-4,
            "at x = {}: lightmap {l}, solution {s}",
            p.x
        );
    }
}
