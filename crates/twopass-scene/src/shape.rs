//! Built-in shapes, tessellated in object space: quad, polygon (ear clipping), box, icosphere.

use glam::{DVec2, DVec3, Vec3};

/// A tessellated shape in object space: shared vertices, optional smooth normals, triangles
/// counter-clockwise seen from the front side.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ShapeMesh {
    /// Vertex positions, object space.
    pub positions: Vec<Vec3>,
    /// Vertex indices, three per triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Shading normals (unit); empty for flat shading.
    pub normals: Vec<Vec3>,
    /// Normal indices per triangle corner; empty for flat shading, else one per triangle.
    pub normal_indices: Vec<[u32; 3]>,
    /// Texture coordinates (an OBJ's `vt`, v up); empty when the shape has none.
    pub texcoords: Vec<glam::Vec2>,
    /// Texture-coordinate indices per triangle corner; empty, or one per triangle.
    pub texcoord_indices: Vec<[u32; 3]>,
    /// The coordinates a base colour texture is read at, per triangle corner (glTF's
    /// convention, v down); empty, or one per triangle.
    pub albedo_uvs: Vec<[glam::Vec2; 3]>,
    /// Each position's index in the source's own vertex list (an OBJ's `v` statements,
    /// 0-based, file order); empty when that is the position's own index (built-in shapes, a
    /// glTF primitive's accessor).
    pub source_vertices: Vec<u32>,
}

/// A parallelogram: two triangles over four shared vertices, front along `edge_u x edge_v`.
pub fn quad(origin: Vec3, edge_u: Vec3, edge_v: Vec3) -> Result<ShapeMesh, String> {
    if edge_u.cross(edge_v).length_squared()
        <= f32::EPSILON * edge_u.length_squared() * edge_v.length_squared()
    {
        return Err("quad edges `edge_u` and `edge_v` are zero or parallel (zero area)".into());
    }
    Ok(ShapeMesh {
        positions: vec![
            origin,
            origin + edge_u,
            origin + edge_u + edge_v,
            origin + edge_v,
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..ShapeMesh::default()
    })
}

/// Most vertices of a `polygon` shape: ear clipping takes up to cubic time in the count.
pub const MAX_POLYGON_VERTICES: usize = 1024;

/// A simple polygon, triangulated by ear clipping in its plane of best fit (Newell's normal),
/// so convex and concave polygons and slightly non-planar measured data all work.
pub fn polygon(vertices: &[Vec3]) -> Result<ShapeMesh, String> {
    if vertices.len() < 3 {
        return Err(format!(
            "a polygon needs at least 3 vertices, got {}",
            vertices.len()
        ));
    }
    if vertices.len() > MAX_POLYGON_VERTICES {
        return Err(format!(
            "a polygon has at most {MAX_POLYGON_VERTICES} vertices, got {} (its triangulation takes time cubic in the count; give a large mesh as an OBJ)",
            vertices.len()
        ));
    }
    let pts: Vec<DVec3> = vertices.iter().map(|v| v.as_dvec3()).collect();
    // Newell's method: robust polygon normal, length = twice the projected area.
    let mut normal = DVec3::ZERO;
    for (i, p) in pts.iter().enumerate() {
        let q = pts[(i + 1) % pts.len()];
        normal += DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    let extent = pts
        .iter()
        .fold(0.0_f64, |m, p| m.max((*p - pts[0]).length()));
    let twice_area = normal.length();
    if twice_area.is_nan() || twice_area <= 1e-12 * extent * extent {
        return Err("polygon has zero area (collinear or repeated vertices)".into());
    }
    let n = normal.normalize();
    let (u, mut v) = n.any_orthonormal_pair();
    if u.cross(v).dot(n) < 0.0 {
        v = -v; // keep (u, v, n) right-handed so the polygon is counter-clockwise in 2D
    }
    let flat: Vec<DVec2> = pts.iter().map(|p| DVec2::new(p.dot(u), p.dot(v))).collect();
    let triangles = ear_clip(&flat).ok_or_else(|| {
        "polygon cannot be triangulated: it is self-intersecting or has repeated vertices"
            .to_owned()
    })?;
    Ok(ShapeMesh {
        positions: vertices.to_vec(),
        triangles,
        ..ShapeMesh::default()
    })
}

fn cross2(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Ear clipping of a counter-clockwise (in the projected frame) simple polygon.
fn ear_clip(p: &[DVec2]) -> Option<Vec<[u32; 3]>> {
    let mut idx: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len() - 2);
    let scale = p.iter().fold(0.0_f64, |m, q| m.max((*q - p[0]).length()));
    let tiny = 1e-12 * scale * scale;
    while idx.len() > 3 {
        let m = idx.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (p[idx[(i + m - 1) % m]], p[idx[i]], p[idx[(i + 1) % m]]);
            if cross2(b - a, c - b) <= tiny {
                return false; // reflex or flat corner
            }
            // No other remaining vertex inside (or on) the candidate triangle.
            idx.iter().all(|&j| {
                let q = p[j];
                if q == a || q == b || q == c {
                    return true;
                }
                !(cross2(b - a, q - a) >= 0.0
                    && cross2(c - b, q - b) >= 0.0
                    && cross2(a - c, q - c) >= 0.0)
            })
        })?;
        out.push([
            idx[(ear + m - 1) % m] as u32,
            idx[ear] as u32,
            idx[(ear + 1) % m] as u32,
        ]);
        idx.remove(ear);
    }
    let (a, b, c) = (p[idx[0]], p[idx[1]], p[idx[2]]);
    if cross2(b - a, c - b) <= tiny {
        return None;
    }
    out.push([idx[0] as u32, idx[1] as u32, idx[2] as u32]);
    Some(out)
}

/// An axis-aligned box, six faces of two triangles with their own vertices (sharp edges),
/// normals pointing out.
pub fn cuboid(min: Vec3, max: Vec3) -> Result<ShapeMesh, String> {
    if !(max.cmpgt(min).all()) {
        return Err(format!(
            "box `max` {max} must exceed `min` {min} on every axis"
        ));
    }
    let c = |[x, y, z]: [bool; 3]| {
        Vec3::new(
            if x { max.x } else { min.x },
            if y { max.y } else { min.y },
            if z { max.z } else { min.z },
        )
    };
    // Each face counter-clockwise seen from outside: on the face across `axis`, with u and v
    // the next two axes in cyclic order, the + face turns from u to v, the - face from v to u.
    let square = [[false, false], [true, false], [true, true], [false, true]];
    let mut mesh = ShapeMesh::default();
    for axis in 0..3 {
        for positive in [true, false] {
            let base = mesh.positions.len() as u32;
            for [s, t] in square {
                let (u, v) = if positive { (s, t) } else { (t, s) };
                let mut at = [false; 3];
                (at[axis], at[(axis + 1) % 3], at[(axis + 2) % 3]) = (positive, u, v);
                mesh.positions.push(c(at));
            }
            mesh.triangles.push([base, base + 1, base + 2]);
            mesh.triangles.push([base, base + 2, base + 3]);
        }
    }
    Ok(mesh)
}

/// Central angle (radians) of an icosahedron's edge.
const ICOSAHEDRON_EDGE_ANGLE: f64 = 1.107_148_717_794_090_4;

/// Deepest icosphere subdivision accepted (20 * 4^8 = 1.3 million triangles).
pub const MAX_SUBDIVISIONS: u32 = 8;

/// The smallest icosphere subdivision level whose chord error (sagitta, scene units) is at most
/// `tolerance` for a sphere of `radius`, clamped to 1..=7. Each level halves the edge angle.
pub fn sphere_subdivisions_for(radius: f32, tolerance: f32) -> u32 {
    let (r, tol) = (
        f64::from(radius),
        f64::from(tolerance).max(f64::MIN_POSITIVE),
    );
    (1..=7)
        .find(|&level| {
            let theta = ICOSAHEDRON_EDGE_ANGLE / f64::from(1u32 << level);
            r * (1.0 - (theta * 0.5).cos()) <= tol
        })
        .unwrap_or(7)
}

/// An icosphere of `subdivisions` levels: shared vertices, smooth unit normals, front outside.
pub fn sphere(center: Vec3, radius: f32, subdivisions: u32) -> Result<ShapeMesh, String> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(format!("sphere radius {radius} must be finite and > 0"));
    }
    if subdivisions > MAX_SUBDIVISIONS {
        return Err(format!(
            "sphere subdivisions {subdivisions} must be at most {MAX_SUBDIVISIONS}"
        ));
    }
    let t = (1.0 + 5.0_f64.sqrt()) / 2.0;
    let mut dirs: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoint = std::collections::HashMap::<(u32, u32), u32>::new();
        let mut mid = |a: u32, b: u32, dirs: &mut Vec<DVec3>| {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                dirs.push((dirs[a as usize] + dirs[b as usize]).normalize());
                (dirs.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let (ab, bc, ca) = (
                mid(a, b, &mut dirs),
                mid(b, c, &mut dirs),
                mid(c, a, &mut dirs),
            );
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let c = center.as_dvec3();
    let r = f64::from(radius);
    Ok(ShapeMesh {
        positions: dirs.iter().map(|d| (c + *d * r).as_vec3()).collect(),
        normals: dirs.iter().map(|d| d.as_vec3()).collect(),
        normal_indices: tris.clone(),
        triangles: tris,
        ..ShapeMesh::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(m: &ShapeMesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| m.positions[i as usize].as_dvec3());
                0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
            })
            .sum()
    }

    fn normal_sum(m: &ShapeMesh) -> DVec3 {
        m.triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| m.positions[i as usize].as_dvec3());
                (p[1] - p[0]).cross(p[2] - p[0])
            })
            .sum()
    }

    #[test]
    fn quad_area_and_orientation() {
        let m = quad(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * -3.0).unwrap();
        assert!((area(&m) - 6.0).abs() < 1e-9);
        // edge_u x edge_v = X x -Z = +Y.
        assert!(normal_sum(&m).normalize().abs_diff_eq(DVec3::Y, 1e-12));
        assert!(quad(Vec3::ZERO, Vec3::X, Vec3::X * 2.0).is_err());
    }

    #[test]
    fn concave_polygon_keeps_its_area() {
        // An L shape of area 3, counter-clockwise seen from +z.
        let l = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]
            .map(|(x, y)| Vec3::new(x, y, 5.0));
        let m = polygon(&l).unwrap();
        assert_eq!(m.triangles.len(), 4);
        assert!((area(&m) - 3.0).abs() < 1e-6);
        assert!(normal_sum(&m).normalize().abs_diff_eq(DVec3::Z, 1e-9));
        // Clockwise input keeps its own orientation (-z).
        let mut rev = l;
        rev.reverse();
        assert!(
            normal_sum(&polygon(&rev).unwrap())
                .normalize()
                .abs_diff_eq(-DVec3::Z, 1e-9)
        );
    }

    #[test]
    fn bad_polygons_are_refused() {
        assert!(polygon(&[Vec3::ZERO, Vec3::X]).is_err());
        assert!(polygon(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]).is_err());
        // A bow tie crosses itself.
        let bow = [(0., 0.), (1., 1.), (1., 0.), (0., 1.)].map(|(x, y)| Vec3::new(x, y, 0.0));
        assert!(polygon(&bow).is_err());
    }

    #[test]
    fn box_is_closed_with_outward_faces() {
        let m = cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)).unwrap();
        assert!((area(&m) - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-6);
        // Closed surface: oriented area vectors sum to zero; divergence theorem gives volume.
        assert!(normal_sum(&m).length() < 1e-9);
        let volume: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let p = t.map(|i| m.positions[i as usize].as_dvec3());
                p[0].dot(p[1].cross(p[2])) / 6.0
            })
            .sum();
        assert!((volume - 6.0).abs() < 1e-9, "volume {volume}");
        assert!(cuboid(Vec3::ONE, Vec3::ONE).is_err());
    }

    #[test]
    fn sphere_converges_to_area_and_volume() {
        let r = 2.0_f64;
        let m = sphere(Vec3::new(1.0, 2.0, 3.0), r as f32, 5).unwrap();
        assert_eq!(m.triangles.len(), 20 * 4usize.pow(5));
        assert_eq!(
            m.positions.len(),
            10 * 4usize.pow(5) + 2,
            "vertices are shared"
        );
        let exact = 4.0 * std::f64::consts::PI * r * r;
        assert!((area(&m) - exact).abs() / exact < 2e-3);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(((*p - Vec3::new(1.0, 2.0, 3.0)).length() - r as f32).abs() < 1e-5);
            assert!((n.length() - 1.0).abs() < 1e-6);
        }
        assert!(normal_sum(&m).length() < 1e-6 * exact);
    }

    #[test]
    fn sphere_level_follows_the_tolerance() {
        assert!(sphere_subdivisions_for(100.0, 0.19) >= 4);
        assert!(sphere_subdivisions_for(1.0, 0.19) <= 2);
        assert_eq!(sphere_subdivisions_for(1.0, 0.0), 7);
    }
}
