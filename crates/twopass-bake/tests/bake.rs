//! Bake I/O: the bake file round-trips bit for bit and refuses damaged or foreign files; the
//! glTF binary and the PLY read back (with the `gltf` and `ply-rs-bw` readers) with the element
//! mesh's positions and the documented colours; failed writes leave nothing behind.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use twopass_bake::{self as bake, BakeError, BakeProblem, ColorMapping, Fingerprint, Manifest};
use twopass_radiosity::MeshPart;
use twopass_radiosity::element::ElementMesh;
use twopass_radiosity::{Options, Solution, Solver, Stop};
use twopass_scene::{DiffuseRadiance, Scene};

fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.toml")
}

fn coarse() -> Options {
    Options {
        patch_size: Some(150.0),
        element_size: Some(60.0),
        stop: Stop {
            unshot_fraction: 1e-2,
            ..Stop::default()
        },
        ..Options::default()
    }
}

/// A coarse adaptive Cornell solve (refined trees, so the bake holds nested bisections), shared
/// by every test.
fn solved() -> &'static (Scene, Solution, Manifest) {
    static SOLVED: OnceLock<(Scene, Solution, Manifest)> = OnceLock::new();
    SOLVED.get_or_init(|| {
        let (scene, _) = twopass_scene::load(cornell_path()).unwrap();
        let options = coarse();
        let (solution, manifest) = {
            let mut solver = Solver::new(&scene, options.clone()).unwrap();
            let finish = solver.run(|_| std::ops::ControlFlow::Continue(()));
            let residuals = solver.residuals(50);
            let manifest = Manifest::new(
                &scene,
                &options,
                finish,
                &solver.progress(),
                &residuals,
                50,
                std::time::Duration::ZERO,
            );
            (solver.solution(), manifest)
        };
        (scene, solution, manifest)
    })
}

fn cornell_text() -> String {
    std::fs::read_to_string(cornell_path()).unwrap()
}

fn variant(text: &str) -> Scene {
    twopass_scene::load_toml(text, &cornell_path()).unwrap().0
}

#[test]
fn bake_file_round_trips_bit_for_bit() {
    let (scene, solution, _) = solved();
    assert!(
        solution.mesh().nodes.iter().any(|n| n.children.is_some()),
        "the test mesh has bisections"
    );
    let bytes = bake::encode_bake(solution, scene).unwrap();
    let loaded = bake::decode_bake(&bytes, scene).unwrap();
    assert_eq!(loaded.mesh().vertices, solution.mesh().vertices);
    assert_eq!(loaded.mesh().nodes, solution.mesh().nodes);
    assert_eq!(loaded.mesh().roots, solution.mesh().roots);
    assert_eq!(loaded.mesh().patches, solution.mesh().patches);
    let mut points = 0;
    for t in 0..scene.mesh.triangle_count() as u32 {
        for i in 0..=12 {
            for j in 0..=12 - i {
                let (b1, b2) = (i as f32 / 12.0, j as f32 / 12.0);
                let b = [1.0 - b1 - b2, b1, b2];
                let (a, c) = (solution.radiance(t, b), loaded.radiance(t, b));
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    c.to_array().map(f32::to_bits)
                );
                let (a, c) = (
                    solution.indirect_radiance(t, b),
                    loaded.indirect_radiance(t, b),
                );
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    c.to_array().map(f32::to_bits)
                );
                points += 1;
            }
        }
    }
    assert!(points > 2000);
    // Re-encoding the loaded solution gives the same bytes.
    assert_eq!(bake::encode_bake(&loaded, scene).unwrap(), bytes);
}

#[test]
fn focused_caustics_round_trip_through_the_bake_file() {
    // The spheres' solve separates the light focused through glass (format 2): it must load
    // back bit for bit, and a solution without it must load back without it.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-spheres.toml");
    let (scene, _) = twopass_scene::load(&path).unwrap();
    let options = Options {
        specular: Some(twopass_radiosity::SpecularOptions {
            rays: 1 << 14,
            ..Default::default()
        }),
        ..coarse()
    };
    let mut solver = Solver::new(&scene, options).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    let solution = solver.solution();
    let focused = solution.focused_caustics().expect("separated");
    assert!(focused.iter().any(|f| f.max_element() > 0.0));
    let bytes = bake::encode_bake(&solution, &scene).unwrap();
    let loaded = bake::decode_bake(&bytes, &scene).unwrap();
    let bits = |v: &[twopass_brdf::Rgb]| {
        v.iter()
            .map(|c| c.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits(loaded.focused_caustics().unwrap()),
        bits(focused),
        "focused part"
    );
    assert!(loaded.separates_focused_caustics());
    let (box_scene, box_solution, _) = solved();
    assert!(box_solution.focused_caustics().is_none());
    let reloaded = bake::decode_bake(
        &bake::encode_bake(box_solution, box_scene).unwrap(),
        box_scene,
    )
    .unwrap();
    assert!(reloaded.focused_caustics().is_none());
}

#[test]
fn bake_file_is_written_atomically_and_read_back() {
    let (scene, solution, _) = solved();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cornell.bake");
    std::fs::write(&path, b"old contents").unwrap();
    let bytes = bake::encode_bake(solution, scene).unwrap();
    bake::write_atomic(&path, &bytes).unwrap();
    let loaded = bake::read_bake(&path, scene).unwrap();
    assert_eq!(loaded.shot_radiosity(), solution.shot_radiosity());
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "no temporary file left behind");
}

#[test]
fn damaged_bake_files_are_clear_errors() {
    let (scene, solution, _) = solved();
    let bytes = bake::encode_bake(solution, scene).unwrap();
    let n = bytes.len() as u64;
    let problem = |b: &[u8]| bake::decode_bake(b, scene).unwrap_err();

    assert_eq!(problem(&[]), BakeProblem::NotABakeFile);
    assert_eq!(problem(b"PK\x03\x04 not a bake"), BakeProblem::NotABakeFile);
    assert_eq!(
        problem(&bytes[..10]),
        BakeProblem::Truncated {
            expected: 24,
            found: 10
        }
    );
    assert_eq!(
        problem(&bytes[..bytes.len() - 7]),
        BakeProblem::Truncated {
            expected: n,
            found: n - 7
        }
    );
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0; 3]);
    assert_eq!(problem(&longer), BakeProblem::TrailingBytes { extra: 3 });
    let mut flipped = bytes.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x10;
    assert!(matches!(problem(&flipped), BakeProblem::Checksum { .. }));
    let mut version = bytes.clone();
    version[8] = 99;
    assert_eq!(
        problem(&version),
        BakeProblem::UnsupportedVersion {
            found: 99,
            supported: bake::BAKE_FORMAT_VERSION
        }
    );

    // Through the file reader the error names the file.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("short.bake");
    std::fs::write(&path, &bytes[..bytes.len() / 3]).unwrap();
    match bake::read_bake(&path, scene) {
        Err(BakeError::Invalid {
            path: p,
            problem: BakeProblem::Truncated { .. },
        }) => assert_eq!(p, path),
        other => panic!("expected a truncation error, got {other:?}"),
    }
    let err = bake::read_bake(&dir.path().join("missing.bake"), scene).unwrap_err();
    assert!(matches!(err, BakeError::Io { .. }), "{err}");
    assert!(err.to_string().contains("missing.bake"), "{err}");
}

#[test]
fn bake_for_another_scene_is_refused() {
    let (scene, solution, _) = solved();
    let bytes = bake::encode_bake(solution, scene).unwrap();
    let text = cornell_text();
    // The light moved by 0.1 mm: other geometry.
    let moved = variant(&text.replace("548.7", "548.6"));
    match bake::decode_bake(&bytes, &moved) {
        Err(BakeProblem::SceneMismatch {
            what: Fingerprint::Geometry,
            scene: s,
            bake: b,
        }) => {
            assert_eq!(s, bake::geometry_fingerprint(&moved));
            assert_eq!(b, bake::geometry_fingerprint(scene));
        }
        other => panic!("expected a geometry mismatch, got {other:?}"),
    }
    // Same geometry, brighter light: the baked radiosity is stale.
    let brighter = variant(&text.replace("[17, 12, 4]", "[18, 12, 4]"));
    assert_eq!(
        bake::geometry_fingerprint(&brighter),
        bake::geometry_fingerprint(scene)
    );
    assert!(matches!(
        bake::decode_bake(&bytes, &brighter),
        Err(BakeProblem::SceneMismatch {
            what: Fingerprint::Lighting,
            ..
        })
    ));
    // The same scene loaded again is accepted.
    assert!(bake::decode_bake(&bytes, &variant(&text)).is_ok());
}

#[test]
fn scene_fingerprint_follows_everything_an_image_depends_on() {
    let text = cornell_text();
    let base = bake::scene_fingerprint(&variant(&text));
    assert_eq!(base, bake::scene_fingerprint(&variant(&text)), "stable");
    // Geometry and lighting, as the bake's fingerprints.
    let moved = variant(&text.replace("548.7", "548.6"));
    assert_ne!(bake::scene_fingerprint(&moved), base);
    // Same geometry and diffuse light, another view or another glossy lobe: the bake's
    // fingerprints stay, the image fingerprint changes.
    let camera = variant(&text.replace("[278, 273, -800]", "[278, 273, -801]"));
    assert_eq!(
        bake::lighting_fingerprint(&camera),
        bake::lighting_fingerprint(&variant(&text))
    );
    assert_ne!(bake::scene_fingerprint(&camera), base);
    let glossy = text.replacen(
        "type = \"lambert\"\ndiffuse = [0.725, 0.71, 0.68]",
        "type = \"phong\"\ndiffuse = [0.725, 0.71, 0.68]\nspecular = 0.1\nexponent = 20",
        1,
    );
    assert_ne!(glossy, text, "the white material is in the scene file");
    let glossy = variant(&glossy);
    assert_eq!(
        bake::lighting_fingerprint(&glossy),
        bake::lighting_fingerprint(&variant(&text))
    );
    assert_ne!(bake::scene_fingerprint(&glossy), base);
}

#[test]
fn inconsistent_meshes_are_rejected_by_from_parts() {
    let (_, solution, _) = solved();
    let m = solution.mesh();
    let parts = || {
        (
            m.vertices.clone(),
            m.nodes.clone(),
            m.roots.clone(),
            m.patches.clone(),
        )
    };
    let check = |(v, n, r, p), part: MeshPart| {
        let err = ElementMesh::from_parts(v, n, r, p).unwrap_err();
        assert_eq!(err.part, part, "{err}");
    };
    let (v, n, r, p) = parts();
    assert!(ElementMesh::from_parts(v, n, r, p).is_ok());

    let inner = m.nodes.iter().position(|n| n.children.is_some()).unwrap();
    let (v, mut n, r, p) = parts();
    n[inner].children = Some([u32::MAX, 1]);
    check((v, n, r, p), MeshPart::Node);
    // A child pointing back at its parent (a cycle).
    let (v, mut n, r, p) = parts();
    let [c0, _] = n[inner].children.unwrap();
    n[c0 as usize].children = Some([inner as u32, c0]);
    check((v, n, r, p), MeshPart::Node);
    let (v, mut n, r, p) = parts();
    n[0].vertices[1] = v.len() as u32;
    check((v, n, r, p), MeshPart::Node);
    let (mut v, n, r, p) = parts();
    v[3].position.y = f32::NAN;
    check((v, n, r, p), MeshPart::Vertex);
    let (v, n, mut r, p) = parts();
    let t = r.iter().position(|&x| x != u32::MAX).unwrap();
    r[t] = m.nodes.len() as u32 + 5;
    check((v, n, r, p), MeshPart::Root);
    let (v, n, r, mut p) = parts();
    p.swap(0, 1);
    check((v, n, r, p), MeshPart::Patch);
    let (v, mut n, r, p) = parts();
    n[2].uv[1] = n[2].uv[0];
    check((v, n, r, p), MeshPart::Node);
}

#[test]
fn glb_parses_with_one_colour_per_vertex_on_the_element_mesh() {
    let (scene, solution, _) = solved();
    let mapping = ColorMapping::auto(solution);
    assert!(mapping.exposure.is_finite() && mapping.exposure > 0.0);
    let glb = bake::encode_glb(solution, scene, mapping).unwrap();
    let gltf = gltf::Gltf::from_slice(&glb.bytes).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let mesh = solution.mesh();
    let radiance: Vec<_> = solution
        .vertex_radiosity()
        .iter()
        .map(|b| *b * std::f32::consts::FRAC_1_PI)
        .collect();
    assert!(gltf.extensions_used().any(|e| e == "KHR_materials_unlit"));
    let extras: serde_json::Value =
        serde_json::from_str(gltf.document.as_json().asset.extras.as_ref().unwrap().get()).unwrap();
    let exposure = extras["twopass"]["exposure"].as_f64().unwrap();
    assert_eq!(exposure as f32, mapping.exposure);
    assert!(
        extras["twopass"]["color_0"]
            .as_str()
            .unwrap()
            .contains("exposure * L")
    );

    let (mut vertices, mut triangles, mut clamped) = (0, 0, 0);
    let mut leaf_set = HashSet::new();
    for leaf in mesh.leaves() {
        let mut t = mesh.nodes[leaf as usize].vertices;
        t.sort_unstable();
        leaf_set.insert(t);
    }
    for gmesh in gltf.meshes() {
        let object = scene
            .objects
            .iter()
            .position(|o| Some(o.name.as_str()) == gmesh.name())
            .unwrap() as u32;
        // The documented layout: this object's vertices in ascending mesh order.
        let mut expect: Vec<u32> = mesh
            .leaves()
            .filter(|&l| scene.mesh.object_of(mesh.nodes[l as usize].scene_triangle) == object)
            .flat_map(|l| mesh.nodes[l as usize].vertices)
            .collect();
        expect.sort_unstable();
        expect.dedup();
        let prim = gmesh.primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let colors: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        let normals: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
        // The HDR radiance and its parts as custom float VEC3 attributes.
        let custom = |name: &str| -> Vec<[f32; 3]> {
            let (_, acc) = prim
                .attributes()
                .find(|(s, _)| *s == gltf::Semantic::Extras(name.into()))
                .unwrap_or_else(|| panic!("no _{name}"));
            assert_eq!(acc.data_type(), gltf::accessor::DataType::F32);
            assert_eq!(acc.dimensions(), gltf::accessor::Dimensions::Vec3);
            gltf::accessor::Iter::<[f32; 3]>::new(acc, |_| Some(blob))
                .unwrap()
                .collect()
        };
        let (hdr, direct) = (custom("RADIANCE"), custom("DIRECT"));
        assert_eq!(positions.len(), expect.len());
        assert_eq!(colors.len(), positions.len(), "one COLOR_0 per vertex");
        assert_eq!(normals.len(), positions.len());
        for (k, &v) in expect.iter().enumerate() {
            // The Cornell box is in millimetres; glTF positions are metres.
            let mm = mesh.vertices[v as usize].position;
            for (m, mm) in positions[k].iter().zip(mm.to_array()) {
                assert!(
                    (m * 1000.0 - mm).abs() <= 1e-4 * mm.abs().max(1.0),
                    "{m} m, {mm} mm"
                );
            }
            assert_eq!(hdr[k], radiance[v as usize].to_array());
            let d = solution.direct()[v as usize] * std::f32::consts::FRAC_1_PI;
            assert_eq!(direct[k], d.to_array());
            let (c, clipped) = mapping.color(radiance[v as usize]);
            assert_eq!(colors[k], c.to_array());
            assert!(colors[k].iter().all(|&x| (0.0..=1.0).contains(&x)));
            clamped += usize::from(clipped);
            let len: f32 = normals[k].iter().map(|x| x * x).sum();
            assert!((len - 1.0).abs() < 1e-5);
        }
        let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        for tri in indices.chunks(3) {
            let mut t = [0, 1, 2].map(|i| expect[tri[i] as usize]);
            t.sort_unstable();
            assert!(leaf_set.contains(&t), "glb triangle {t:?} is an element");
        }
        vertices += positions.len();
        triangles += indices.len() / 3;
    }
    assert_eq!(
        vertices,
        mesh.vertices.len(),
        "no vertex shared between objects"
    );
    assert_eq!(triangles, mesh.leaves().count());
    assert_eq!((glb.vertices, glb.triangles), (vertices, triangles));
    assert_eq!(glb.clamped_vertices, clamped);
    assert!(
        clamped > 0 && clamped * 10 < vertices,
        "auto exposure saturates only the brightest: {clamped} of {vertices}"
    );
}

#[test]
fn ply_parses_back_with_the_same_values() {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};
    let (scene, solution, _) = solved();
    let mapping = ColorMapping::auto(solution);
    let bytes = bake::encode_ply(solution, scene, mapping).unwrap();
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut bytes.as_slice())
        .unwrap();
    let mesh = solution.mesh();
    let radiosity = solution.vertex_radiosity();
    let verts = &ply.payload["vertex"];
    assert_eq!(verts.len(), mesh.vertices.len());
    let float = |e: &DefaultElement, k: &str| match e[k] {
        Property::Float(x) => x,
        ref other => panic!("{k} is {other:?}"),
    };
    for (i, e) in verts.iter().enumerate() {
        let v = &mesh.vertices[i];
        assert_eq!(
            [float(e, "x"), float(e, "y"), float(e, "z")],
            v.position.to_array()
        );
        assert_eq!(
            [float(e, "nx"), float(e, "ny"), float(e, "nz")],
            v.normal.to_array()
        );
        let l = radiosity[i] * std::f32::consts::FRAC_1_PI;
        let hdr = |p: &str| ["r", "g", "b"].map(|c| float(e, &format!("{p}_{c}")));
        assert_eq!(hdr("radiance"), l.to_array());
        let direct = solution.direct()[i] * std::f32::consts::FRAC_1_PI;
        assert_eq!(hdr("direct"), direct.to_array());
        // Emission + direct + indirect (ambient included) is the radiance.
        let emission = scene.objects[v.object as usize].emission;
        let sum = glam::Vec3::from(hdr("direct")) + glam::Vec3::from(hdr("indirect")) + emission;
        assert!(
            (sum - l).abs().max_element() <= 1e-4 * l.max_element().max(1.0),
            "{sum} vs {l}"
        );
        // The display colour is 8-bit sRGB of the clipped exposed radiance.
        let uchar = |k: &str| match e[k] {
            Property::UChar(x) => x,
            ref other => panic!("{k} is {other:?}"),
        };
        let (c, _) = mapping.color(l);
        let srgb = |x: f32| {
            let x = x.clamp(0.0, 1.0);
            if x <= 0.0031308 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            }
        };
        let expect = c.to_array().map(|x| (srgb(x) * 255.0).round() as u8);
        assert_eq!([uchar("red"), uchar("green"), uchar("blue")], expect);
    }
    // The HDR values reach above what 8-bit colour holds (the light, the lit ceiling).
    assert!(verts.iter().any(|e| float(e, "radiance_r") > 1.0));
    let faces = &ply.payload["face"];
    let leaves: Vec<[u32; 3]> = mesh
        .leaves()
        .map(|l| mesh.nodes[l as usize].vertices)
        .collect();
    assert_eq!(faces.len(), leaves.len());
    for (f, leaf) in faces.iter().zip(&leaves) {
        match &f["vertex_indices"] {
            Property::ListUInt(v) => assert_eq!(v.as_slice(), leaf),
            other => panic!("vertex_indices is {other:?}"),
        }
    }
    assert!(ply.header.comments.iter().any(|c| c.contains("W/(m^2 sr)")));
    // Positions stay in scene units, and the header says which.
    assert!(ply.header.comments.iter().any(|c| c == "unit mm"));
    assert!(ply.header.obj_infos.iter().any(|c| c == "unit mm"));
}

#[test]
fn glb_floor_is_the_measured_width_in_metres() {
    let (scene, solution, _) = solved();
    let glb = bake::encode_glb(solution, scene, ColorMapping::auto(solution)).unwrap();
    let gltf = gltf::Gltf::from_slice(&glb.bytes).unwrap();
    let floor = gltf.meshes().find(|m| m.name() == Some("floor")).unwrap();
    let bounds = floor.primitives().next().unwrap().bounding_box();
    // The Cornell data: the floor spans x from 0 to 552.8 mm and z from 0 to 559.2 mm.
    assert!(
        (bounds.max[0] - bounds.min[0] - 0.5528).abs() < 1e-6,
        "{bounds:?}"
    );
    assert!(
        (bounds.max[2] - bounds.min[2] - 0.5592).abs() < 1e-6,
        "{bounds:?}"
    );
    let extras: serde_json::Value =
        serde_json::from_str(gltf.document.as_json().asset.extras.as_ref().unwrap().get()).unwrap();
    assert_eq!(extras["twopass"]["position_unit"], "m");
    assert_eq!(extras["twopass"]["scene_unit"], "mm");
}

#[test]
fn failed_writes_leave_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    // The output folder is an existing file.
    let blocker = dir.path().join("not-a-dir");
    std::fs::write(&blocker, b"x").unwrap();
    let err = bake::write_atomic(&blocker.join("out.glb"), b"data").unwrap_err();
    assert!(matches!(err, BakeError::Io { .. }), "{err}");
    // The target is an existing directory: the rename fails after the data was written.
    let target = dir.path().join("out.ply");
    std::fs::create_dir(&target).unwrap();
    let err = bake::write_atomic(&target, b"data").unwrap_err();
    assert!(matches!(err, BakeError::Io { .. }), "{err}");
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["not-a-dir", "out.ply"],
        "no temporary file left behind"
    );
    assert_eq!(std::fs::read(&blocker).unwrap(), b"x");
}

#[test]
fn manifest_records_the_solve_and_round_trips_through_json() {
    let (scene, _, manifest) = solved();
    assert!(manifest.rays > 0 && manifest.shots > 0);
    assert!(manifest.unshot_fraction <= 1e-2);
    assert_eq!(manifest.finish, "converged");
    assert_eq!(manifest.counts.scene_triangles, scene.mesh.triangle_count());
    assert_eq!(
        manifest.geometry_fingerprint,
        format!("{:016x}", bake::geometry_fingerprint(scene))
    );
    assert_eq!(manifest.settings.element_size, Some(60.0));
    let json = manifest.to_json().unwrap();
    // serde_json parses floats to within an ulp, so compare what is exact.
    let back: Manifest = serde_json::from_slice(&json).unwrap();
    assert_eq!(back.settings, manifest.settings);
    assert_eq!(back.counts, manifest.counts);
    assert_eq!((back.rays, back.shots), (manifest.rays, manifest.shots));
    assert_eq!(back.unshot_fraction as f32, manifest.unshot_fraction as f32);
}
