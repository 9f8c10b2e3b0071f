//! The scene's triangle mesh: the triangles stored once, and the placed copies of stored
//! objects ([`Repeat`], a glTF mesh that several nodes show) that are not stored again.
//!
//! Every triangle, vertex, shading normal and texture coordinate has one index over the whole
//! scene: the stored ones first, then each copy's in turn. The accessors answer for any index
//! in world space, transforming a copy's data from its source on the fly, so every consumer
//! (radiosity, tracer, lightmap) sees one mesh whatever is instanced.

use std::ops::Range;

use glam::{Affine3A, DVec3, Mat3A, Vec2, Vec3, Vec3A};

use crate::accel::{Accel, Placement, SurfacePoint, transform_error};

/// A placed copy of one stored object: its triangles, vertices, normals and texture
/// coordinates are the source's, moved by `to_world`, and take the index ranges after the
/// stored data and the copies before it.
#[derive(Debug, Clone, PartialEq)]
pub struct Repeat {
    /// Index of the copy's own object in [`Scene::objects`](crate::Scene::objects).
    pub object: u32,
    /// The triangles of the copy (mesh-wide indices).
    pub triangles: Range<u32>,
    /// The first of the source's triangles (a stored index; the copy has as many).
    pub source_triangle: u32,
    /// The copy's vertices (mesh-wide indices).
    pub vertices: Range<u32>,
    /// The first of the source's vertices (a stored index).
    pub source_vertex: u32,
    /// The copy's shading normals (mesh-wide indices).
    pub normals: Range<u32>,
    /// The first of the source's shading normals (a stored index).
    pub source_normal: u32,
    /// The copy's texture coordinates (mesh-wide indices).
    pub texcoords: Range<u32>,
    /// The first of the source's texture coordinates (a stored index).
    pub source_texcoord: u32,
    /// The transform from the source's world position to the copy's, scene units.
    pub to_world: Affine3A,
    /// Its inverse.
    pub from_world: Affine3A,
    /// The normal transform: inverse transpose of `to_world`'s linear part.
    pub normal: Mat3A,
    /// Whether `to_world` mirrors: the copy's corners 1 and 2 are swapped so that its front
    /// side stays the source's.
    pub flips: bool,
    /// |det| of `to_world`'s linear part: a copy's triangle has the source's area times this
    /// times the transformed normal's length.
    pub det: f32,
}

impl Repeat {
    /// A corner triple (or a barycentric triple) of the source in the copy's order.
    #[inline]
    pub fn order<T>(&self, mut c: [T; 3]) -> [T; 3] {
        if self.flips {
            c.swap(1, 2);
        }
        c
    }

    /// A source point in the copy's world.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p)
    }

    /// A source unit normal in the copy's world (unit).
    #[inline]
    pub fn direction(&self, n: Vec3) -> Vec3 {
        Vec3::from(self.normal * Vec3A::from(n)).normalize_or_zero()
    }

    /// A bound on the rounding a point of the copy at `position` (world) picks up through the
    /// two transforms a ray query makes (into the source's space and its hit back out), per
    /// axis, scene units: added to the point's own error bound so that rays leaving the copy
    /// are offset clear of it.
    pub fn point_error(&self, position: Vec3) -> Vec3 {
        transform_error(&self.to_world, &self.from_world, position)
    }
}

/// The indexed triangle mesh of the whole scene. Vertices are shared within an object, so
/// quantities stored per vertex (radiosity) are continuous across its triangles. Indices are
/// mesh-wide (the stored data, then each [`Repeat`]'s); every accessor answers in world
/// space, scene units.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Stored vertex positions.
    pub(crate) positions: Vec<Vec3>,
    /// Stored shading normals (unit), indexed by `normal_indices`.
    pub(crate) normals: Vec<Vec3>,
    /// Vertex indices of each stored triangle, counter-clockwise seen from the front.
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Shading-normal indices of each stored triangle's corners.
    pub(crate) normal_indices: Vec<[u32; 3]>,
    /// Unit geometric normal of each stored triangle (front side by winding).
    pub(crate) geometric_normals: Vec<Vec3>,
    /// Area of each stored triangle.
    pub(crate) areas: Vec<f32>,
    /// Object of each stored triangle.
    pub(crate) triangle_object: Vec<u32>,
    /// Stored texture coordinates (an OBJ's `vt`, v up, as written).
    pub(crate) texcoords: Vec<Vec2>,
    /// Texture-coordinate indices of each stored triangle's corners, or `None`.
    pub(crate) texcoord_indices: Vec<Option<[u32; 3]>>,
    /// Base colour coordinates of each stored triangle (empty when nothing is textured).
    pub(crate) albedo_uvs: Vec<Option<[Vec2; 3]>>,
    /// Each stored position's index in its source's own vertex list.
    pub(crate) source_vertices: Vec<u32>,
    /// Whether each stored triangle's shading normal is its flat normal.
    pub(crate) flat: Vec<bool>,
    /// The placed copies, in index order.
    pub(crate) repeats: Vec<Repeat>,
}

impl Mesh {
    /// Number of triangles, copies included.
    pub fn triangle_count(&self) -> usize {
        self.repeats
            .last()
            .map_or(self.triangles.len(), |r| r.triangles.end as usize)
    }

    /// Number of vertices, copies included.
    pub fn vertex_count(&self) -> usize {
        self.repeats
            .last()
            .map_or(self.positions.len(), |r| r.vertices.end as usize)
    }

    /// Number of shading normals, copies included.
    pub fn normal_count(&self) -> usize {
        self.repeats
            .last()
            .map_or(self.normals.len(), |r| r.normals.end as usize)
    }

    /// Number of triangles stored in memory (copies are not).
    pub fn stored_triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The placed copies of stored objects.
    pub fn repeats(&self) -> &[Repeat] {
        &self.repeats
    }

    /// The copy triangle `t` belongs to, with its source triangle; `None` for a stored one.
    #[inline]
    pub fn repeat_of(&self, t: u32) -> Option<(&Repeat, u32)> {
        self.locate(t, self.triangles.len(), |r| {
            (&r.triangles, r.source_triangle)
        })
    }

    fn repeat_of_vertex(&self, v: u32) -> Option<(&Repeat, u32)> {
        self.locate(v, self.positions.len(), |r| (&r.vertices, r.source_vertex))
    }

    fn repeat_of_normal(&self, n: u32) -> Option<(&Repeat, u32)> {
        self.locate(n, self.normals.len(), |r| (&r.normals, r.source_normal))
    }

    /// The copy whose range (`span` gives it, with its source's first stored index) holds
    /// mesh-wide index `i`, and the stored index `i` repeats; `None` for one of the `stored`.
    #[inline]
    fn locate(
        &self,
        i: u32,
        stored: usize,
        span: impl Fn(&Repeat) -> (&Range<u32>, u32),
    ) -> Option<(&Repeat, u32)> {
        if (i as usize) < stored {
            return None;
        }
        let r = &self.repeats[self.repeats.partition_point(|r| span(r).0.start <= i) - 1];
        let (range, source) = span(r);
        Some((r, source + (i - range.start)))
    }

    /// Vertex indices of triangle `t`, counter-clockwise seen from the front.
    #[inline]
    pub fn triangle(&self, t: u32) -> [u32; 3] {
        match self.repeat_of(t) {
            None => self.triangles[t as usize],
            Some((r, s)) => {
                r.order(self.triangles[s as usize].map(|v| v - r.source_vertex + r.vertices.start))
            }
        }
    }

    /// Every triangle's vertex indices, in index order.
    pub fn triangles(&self) -> impl ExactSizeIterator<Item = [u32; 3]> + '_ {
        (0..self.triangle_count() as u32).map(|t| self.triangle(t))
    }

    /// Position of vertex `v`, scene units.
    #[inline]
    pub fn position(&self, v: u32) -> Vec3 {
        match self.repeat_of_vertex(v) {
            None => self.positions[v as usize],
            Some((r, s)) => r.point(self.positions[s as usize]),
        }
    }

    /// Every vertex position, in index order.
    pub fn positions(&self) -> impl ExactSizeIterator<Item = Vec3> + '_ {
        (0..self.vertex_count() as u32).map(|v| self.position(v))
    }

    /// Shading normal `n` (unit).
    pub fn normal(&self, n: u32) -> Vec3 {
        match self.repeat_of_normal(n) {
            None => self.normals[n as usize],
            Some((r, s)) => r.direction(self.normals[s as usize]),
        }
    }

    /// Shading-normal indices of triangle `t`'s corners.
    pub fn normal_indices(&self, t: u32) -> [u32; 3] {
        match self.repeat_of(t) {
            None => self.normal_indices[t as usize],
            Some((r, s)) => r.order(
                self.normal_indices[s as usize].map(|n| n - r.source_normal + r.normals.start),
            ),
        }
    }

    /// Unit geometric normal of triangle `t` (front side by winding).
    #[inline]
    pub fn geometric_normal(&self, t: u32) -> Vec3 {
        match self.repeat_of(t) {
            None => self.geometric_normals[t as usize],
            Some((r, s)) => r.direction(self.geometric_normals[s as usize]),
        }
    }

    /// Area of triangle `t`, scene units squared.
    #[inline]
    pub fn area(&self, t: u32) -> f32 {
        match self.repeat_of(t) {
            None => self.areas[t as usize],
            Some((r, s)) => {
                let n = Vec3A::from(self.geometric_normals[s as usize]);
                self.areas[s as usize] * r.det * (r.normal * n).length()
            }
        }
    }

    /// Every triangle's area, in index order.
    pub fn areas(&self) -> impl ExactSizeIterator<Item = f32> + '_ {
        (0..self.triangle_count() as u32).map(|t| self.area(t))
    }

    /// Object of triangle `t` (index into [`Scene::objects`](crate::Scene::objects)).
    #[inline]
    pub fn object_of(&self, t: u32) -> u32 {
        match self.repeat_of(t) {
            None => self.triangle_object[t as usize],
            Some((r, _)) => r.object,
        }
    }

    /// Texture-coordinate indices of triangle `t`'s corners (mesh-wide, into
    /// [`Mesh::texcoord`]), or `None` for a triangle without them (built-in shapes, OBJ groups
    /// lacking `vt`).
    pub fn texcoord_indices(&self, t: u32) -> Option<[u32; 3]> {
        match self.repeat_of(t) {
            None => self.texcoord_indices[t as usize],
            Some((r, s)) => self.texcoord_indices[s as usize]
                .map(|i| r.order(i.map(|k| k - r.source_texcoord + r.texcoords.start))),
        }
    }

    /// Texture coordinate `k` (an OBJ's `vt`, v up, as written).
    pub fn texcoord(&self, k: u32) -> Vec2 {
        let s = self
            .locate(k, self.texcoords.len(), |r| {
                (&r.texcoords, r.source_texcoord)
            })
            .map_or(k, |(_, s)| s);
        self.texcoords[s as usize]
    }

    /// The texture coordinates of triangle `t`'s corners, or `None`.
    pub fn texcoords_of(&self, t: u32) -> Option<[Vec2; 3]> {
        self.texcoord_indices(t)
            .map(|i| i.map(|k| self.texcoord(k)))
    }

    /// The coordinates triangle `t`'s base colour texture is read at, per corner (glTF's
    /// convention: (0, 0) the image's top left, v down), or `None` for a triangle without
    /// them or a scene without textures.
    #[inline]
    pub fn albedo_uv(&self, t: u32) -> Option<[Vec2; 3]> {
        match self.repeat_of(t) {
            None => self.albedo_uvs.get(t as usize).copied().flatten(),
            Some((r, s)) => self
                .albedo_uvs
                .get(s as usize)
                .copied()
                .flatten()
                .map(|uv| r.order(uv)),
        }
    }

    /// Whether any triangle has base colour coordinates.
    pub fn has_albedo_uvs(&self) -> bool {
        !self.albedo_uvs.is_empty()
    }

    /// Vertex `v`'s index in its source's own vertex list, so an output on the user's mesh can
    /// name the user's vertex: an OBJ's `v` statements (0-based, file order), a glTF
    /// primitive's accessor, a built-in shape's vertices (the index within its object).
    pub fn source_vertex(&self, v: u32) -> u32 {
        match self.repeat_of_vertex(v) {
            None => self.source_vertices[v as usize],
            Some((_, s)) => self.source_vertices[s as usize],
        }
    }

    /// Whether triangle `t`'s shading normal is its own flat normal because its input gave
    /// none (an OBJ group without `vn`, a glTF primitive without `NORMAL`, a flat shape).
    pub fn is_flat(&self, t: u32) -> bool {
        self.stored_is_flat(self.repeat_of(t).map_or(t, |(_, s)| s) as usize)
    }

    /// [`Mesh::is_flat`] of stored triangle `s` (a copy's source).
    fn stored_is_flat(&self, s: usize) -> bool {
        self.flat.get(s).copied().unwrap_or(false)
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: u32) -> [Vec3; 3] {
        match self.repeat_of(t) {
            None => self.triangles[t as usize].map(|i| self.positions[i as usize]),
            Some((r, s)) => {
                r.order(self.triangles[s as usize].map(|i| r.point(self.positions[i as usize])))
            }
        }
    }

    /// The interpolated unit shading normal of triangle `t` at barycentrics `b`.
    pub fn shading_normal(&self, t: u32, b: [f32; 3]) -> Vec3 {
        let repeat = self.repeat_of(t);
        let stored = repeat.map_or(t, |(_, s)| s) as usize;
        // A flat triangle's three stored normals are its geometric normal (unit), so the
        // interpolation would only round it: every hit of a flat scene takes this path.
        if self.stored_is_flat(stored) {
            let g = self.geometric_normals[stored];
            return repeat.map_or(g, |(r, _)| r.direction(g));
        }
        let corners = self.normal_indices[stored];
        let n = match repeat {
            None => corners.map(|i| self.normals[i as usize]),
            Some((r, _)) => r.order(corners.map(|i| r.direction(self.normals[i as usize]))),
        };
        let s = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
        s.try_normalize()
            .unwrap_or_else(|| self.geometric_normal(t))
    }

    /// [`Mesh::shading_normal`] turned to the front side, the side of the geometric normal
    /// (unit): the normal a surface point is shaded with.
    pub fn front_shading_normal(&self, t: u32, b: [f32; 3]) -> Vec3 {
        let n = self.shading_normal(t, b);
        if n.dot(self.geometric_normal(t)) < 0.0 {
            -n
        } else {
            n
        }
    }

    /// The surface point of triangle `t` at barycentrics `b`, its corners given (the mesh's
    /// own, as [`Mesh::corners`] gives them): a copy's point also bounds the rounding of
    /// the transforms a ray query makes.
    #[inline]
    pub fn surface_point_on(&self, t: u32, corners: [Vec3; 3], b: [f32; 3]) -> SurfacePoint {
        match self.repeat_of(t) {
            None => SurfacePoint::on_triangle(corners, b, self.geometric_normals[t as usize], t),
            Some((r, s)) => {
                let mut p = SurfacePoint::on_triangle(
                    corners,
                    b,
                    r.direction(self.geometric_normals[s as usize]),
                    t,
                );
                p.error += r.point_error(p.position);
                p
            }
        }
    }

    /// The surface point of triangle `t` at barycentrics `b`.
    pub fn surface_point(&self, t: u32, b: [f32; 3]) -> SurfacePoint {
        self.surface_point_on(t, self.corners(t), b)
    }

    /// The surface point of triangle `t` nearest to `position` (projected into the triangle's
    /// plane, barycentrics from the projection), with its error bound: for points computed
    /// elsewhere, such as the vertices of a finer mesh over the triangle.
    pub fn surface_point_at(&self, t: u32, position: Vec3) -> SurfacePoint {
        self.surface_point(
            t,
            self.barycentric(t, position.as_dvec3()).map(|b| b as f32),
        )
    }

    /// Barycentric weights on triangle `t` of `position` projected into its plane, in f64
    /// (they sum to 1; all in [0, 1] for points inside).
    pub fn barycentric(&self, t: u32, position: DVec3) -> [f64; 3] {
        let [p0, p1, p2] = self.corners(t).map(|p| p.as_dvec3());
        let (e1, e2, d) = (p1 - p0, p2 - p0, position - p0);
        let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (r1, r2) = (d.dot(e1), d.dot(e2));
        let det = a * c - b * b;
        let (b1, b2) = ((c * r1 - b * r2) / det, (a * r2 - b * r1) / det);
        [1.0 - b1 - b2, b1, b2]
    }

    /// A point uniformly distributed over triangle `t` for `u` in [0, 1)^2.
    pub fn sample_triangle(&self, t: u32, u: Vec2) -> SurfacePoint {
        let s = u.x.sqrt();
        let (b1, b2) = (s * (1.0 - u.y), s * u.y);
        self.surface_point(t, [1.0 - b1 - b2, b1, b2])
    }

    /// The accelerator over the mesh: the stored triangles' tree, and the copies' through one
    /// shared tree per source ([`Accel::build_placed`]).
    pub fn accel(&self) -> Accel {
        let placements: Vec<Placement> = self
            .repeats
            .iter()
            .map(|r| Placement {
                source: r.source_triangle,
                count: r.triangles.end - r.triangles.start,
                first: r.triangles.start,
                to_world: r.to_world,
                from_world: r.from_world,
                flips: r.flips,
            })
            .collect();
        Accel::build_placed(&self.positions, &self.triangles, &placements)
    }

    /// Copies the whole mesh into plain world-space arrays (positions, triangles), copies of
    /// instanced objects included: for tools that want them as slices, such as exporting the
    /// scene to another ray engine.
    pub fn flattened(&self) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (self.positions().collect(), self.triangles().collect())
    }

    /// Bytes of the stored mesh data (copies are not stored).
    pub fn bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.positions.as_slice())
            + size_of_val(self.normals.as_slice())
            + size_of_val(self.triangles.as_slice())
            + size_of_val(self.normal_indices.as_slice())
            + size_of_val(self.geometric_normals.as_slice())
            + size_of_val(self.areas.as_slice())
            + size_of_val(self.triangle_object.as_slice())
            + size_of_val(self.texcoords.as_slice())
            + size_of_val(self.texcoord_indices.as_slice())
            + size_of_val(self.albedo_uvs.as_slice())
            + size_of_val(self.source_vertices.as_slice())
            + size_of_val(self.flat.as_slice())
            + size_of_val(self.repeats.as_slice())
    }
}

/// The index ranges of one stored object's data, which a copy of it repeats.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct StoredSpans {
    /// Its triangles.
    pub(crate) triangles: Range<u32>,
    /// Its vertices.
    pub(crate) vertices: Range<u32>,
    /// Its shading normals.
    pub(crate) normals: Range<u32>,
    /// Its texture coordinates.
    pub(crate) texcoords: Range<u32>,
}

impl Mesh {
    /// Appends a copy of the stored object whose data `source` spans, placed by `to_world`
    /// (from the source's world), as object `object`. Returns the copy's triangle range.
    pub(crate) fn push_repeat(
        &mut self,
        source: &StoredSpans,
        to_world: Affine3A,
        object: u32,
    ) -> Range<u32> {
        let next = |end: usize, n: u32| end as u32..end as u32 + n;
        let len = |r: &Range<u32>| r.end - r.start;
        let linear = to_world.matrix3;
        let det = linear.determinant();
        let repeat = Repeat {
            object,
            triangles: next(self.triangle_count(), len(&source.triangles)),
            source_triangle: source.triangles.start,
            vertices: next(self.vertex_count(), len(&source.vertices)),
            source_vertex: source.vertices.start,
            normals: next(self.normal_count(), len(&source.normals)),
            source_normal: source.normals.start,
            texcoords: next(
                self.repeats
                    .last()
                    .map_or(self.texcoords.len(), |r| r.texcoords.end as usize),
                len(&source.texcoords),
            ),
            source_texcoord: source.texcoords.start,
            to_world,
            from_world: to_world.inverse(),
            normal: linear.inverse().transpose(),
            flips: det < 0.0,
            det: det.abs(),
        };
        let range = repeat.triangles.clone();
        self.repeats.push(repeat);
        range
    }
}
