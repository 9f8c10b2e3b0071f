//! The per-vertex bake on the scene's own mesh: the `.glb` has the scene's triangles and
//! vertices (in metres), and each vertex the radiance of the element-mesh vertex at the same
//! place (every Cornell polygon is flat and one object, so exactly one).

use glam::Vec3;
use twopass_bake::{self as bake, ColorMapping, RadianceParts};

use crate::common::cornell;

#[test]
fn vertex_glb_holds_the_element_values_at_the_users_vertices() {
    let (scene, solution) = cornell(80.0);
    let mapping = ColorMapping::auto(&solution);
    let glb = bake::encode_vertex_glb(&solution, &scene, mapping, None).unwrap();
    let parts = RadianceParts::of(&solution);
    let mesh = solution.mesh();

    let gltf = gltf::Gltf::from_slice(&glb.bytes).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let (mut triangles, mut vertices, mut singles) = (0, 0, 0);
    for gmesh in gltf.meshes() {
        let object = scene
            .objects
            .iter()
            .position(|o| Some(o.name.as_str()) == gmesh.name())
            .unwrap();
        let o = &scene.objects[object];
        let prim = gmesh.primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let col: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        let (_, acc) = prim
            .attributes()
            .find(|(s, _)| *s == gltf::Semantic::Extras("RADIANCE".into()))
            .unwrap();
        let hdr: Vec<[f32; 3]> = gltf::accessor::Iter::<[f32; 3]>::new(acc, |_| Some(blob))
            .unwrap()
            .collect();
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(
            idx.len() / 3,
            o.triangles.len(),
            "{}: its own triangles",
            o.name
        );
        assert_eq!(pos.len(), o.vertices.len(), "{}: its own vertices", o.name);
        for (k, p) in pos.iter().enumerate() {
            let mm = Vec3::from(*p) * 1000.0;
            // The element-mesh vertex of this object at this place.
            let found: Vec<usize> = mesh
                .vertices
                .iter()
                .enumerate()
                .filter(|(_, v)| v.object as usize == object && (v.position - mm).length() < 1e-2)
                .map(|(i, _)| i)
                .collect();
            // One element vertex, or one per side of a crease where a measured wall is not
            // quite planar: the user's vertex is the mean over its triangles, so it lies
            // between them (and equals the one).
            assert!(!found.is_empty(), "{} vertex {mm}", o.name);
            let lo = found
                .iter()
                .fold(Vec3::INFINITY, |a, &i| a.min(parts.radiance[i]));
            let hi = found
                .iter()
                .fold(Vec3::NEG_INFINITY, |a, &i| a.max(parts.radiance[i]));
            let got = Vec3::from(hdr[k]);
            let tol = 1e-5 * hi.max_element().max(1e-3);
            assert!(
                got.cmpge(lo - tol).all() && got.cmple(hi + tol).all(),
                "{}: {got} not in {lo}..{hi}",
                o.name
            );
            singles += usize::from(found.len() == 1);
            assert_eq!(col[k], mapping.color(got).0.to_array());
        }
        triangles += idx.len() / 3;
        vertices += pos.len();
    }
    assert_eq!(triangles, scene.mesh.triangle_count());
    assert!(
        singles * 2 > vertices,
        "most vertices match one element vertex exactly"
    );
    assert_eq!((glb.triangles, glb.vertices), (triangles, vertices));
}
