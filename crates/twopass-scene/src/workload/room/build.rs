//! The shared vocabulary of the generated rooms: what a room is ([`Room`]), what it is made
//! from ([`RoomSettings`]), and the builder that writes a room's OBJ groups (the bulk geometry,
//! positions and faces only, as a user's export would be) and its scene file's objects.

use std::fmt::Write as _;

use glam::Vec3;

use crate::shape::{self, ShapeMesh};

/// One generated test room: a scene file and the OBJ mesh it names, both as text, and what a
/// test needs to know about them.
#[derive(Debug, Clone, PartialEq)]
pub struct Room {
    /// The room's name, also the stem of its files (`spheres`, `grazing`, ...).
    pub name: &'static str,
    /// The scene file (TOML), naming the mesh as [`Room::mesh_file`] beside it.
    pub scene: String,
    /// The OBJ mesh's file name, relative to the scene file (`<name>.obj`).
    pub mesh_file: String,
    /// The OBJ text: `v` and `f` statements in one `o` group per wall, sphere, box or slab;
    /// no normals, no texture coordinates.
    pub mesh: String,
    /// Objects the scene loads into: one per OBJ group and one per built-in shape (the lights,
    /// a coloured wall).
    pub objects: usize,
    /// Triangles of the loaded scene (OBJ and built-in shapes).
    pub triangles: usize,
    /// Further OBJ meshes beside the scene file, as (file name, text): one per material other
    /// than `grey` that OBJ groups were built in (glass and metal objects), each the scene's
    /// object of that material.
    pub other_meshes: Vec<(String, String)>,
    /// The room's inside, scene units (metres): the box the walls enclose, (min, max).
    pub interior: (Vec3, Vec3),
    /// The camera's position, scene units.
    pub camera: Vec3,
}

impl Room {
    /// The scene file's name, `<name>.toml`.
    pub fn scene_file(&self) -> String {
        format!("{}.toml", self.name)
    }

    /// Every mesh file the scene names, as (file name, text): [`Room::mesh_file`] first, then
    /// [`Room::other_meshes`].
    pub fn mesh_files(&self) -> Vec<(&str, &str)> {
        std::iter::once((self.mesh_file.as_str(), self.mesh.as_str()))
            .chain(
                self.other_meshes
                    .iter()
                    .map(|(f, t)| (f.as_str(), t.as_str())),
            )
            .collect()
    }
}

/// What a generated room is made from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RoomSettings {
    /// Triangles of the whole scene the `spheres` room aims at (its spheres' tessellation
    /// takes what the walls and boxes leave); the other rooms have a fixed size. Default
    /// 100 000.
    pub triangles: usize,
    /// Seed of the room's layout (positions and sizes); the same seed gives the same text.
    /// Default 0.
    pub seed: u64,
    /// The camera's image width and height, pixels. Default 256.
    pub resolution: u32,
}

impl Default for RoomSettings {
    fn default() -> Self {
        Self {
            triangles: 100_000,
            seed: 0,
            resolution: 256,
        }
    }
}

/// Writes a room: OBJ groups for the bulk geometry, built-in quads for the lights and
/// coloured walls, the camera and the materials.
pub(super) struct RoomBuilder {
    name: &'static str,
    interior: (Vec3, Vec3),
    obj: Obj,
    /// OBJ meshes of other materials, by material name, in the order first used.
    others: Vec<(&'static str, Obj)>,
    objects: String,
    groups: usize,
    builtins: usize,
    triangles: usize,
}

/// One OBJ file being written: its text and the vertices it holds so far.
struct Obj {
    text: String,
    vertices: usize,
}

impl Obj {
    fn new(room: &str) -> Self {
        let mut text = String::new();
        let _ = writeln!(
            text,
            "# twopass generated room `{room}`: positions and faces only"
        );
        Self { text, vertices: 0 }
    }

    /// Appends group `name` of `positions` and counter-clockwise (from the front) `triangles`.
    fn group(&mut self, name: &str, positions: &[Vec3], triangles: &[[u32; 3]]) {
        let _ = writeln!(self.text, "o {name}");
        for p in positions {
            let _ = writeln!(self.text, "v {} {} {}", p.x, p.y, p.z);
        }
        let base = self.vertices + 1;
        for t in triangles {
            let _ = writeln!(
                self.text,
                "f {} {} {}",
                base + t[0] as usize,
                base + t[1] as usize,
                base + t[2] as usize
            );
        }
        self.vertices += positions.len();
    }
}

impl RoomBuilder {
    /// An empty room `name` whose walls will enclose `interior` (min, max).
    pub(super) fn new(name: &'static str, min: Vec3, max: Vec3) -> Self {
        Self {
            name,
            interior: (min, max),
            obj: Obj::new(name),
            others: Vec::new(),
            objects: String::new(),
            groups: 0,
            builtins: 0,
            triangles: 0,
        }
    }

    /// Appends an OBJ group `name` of `positions` and counter-clockwise (from the front)
    /// `triangles` indexing them.
    pub(super) fn group(&mut self, name: &str, positions: &[Vec3], triangles: &[[u32; 3]]) {
        self.obj.group(name, positions, triangles);
        self.groups += 1;
        self.triangles += triangles.len();
    }

    /// Appends an OBJ group as [`RoomBuilder::group`] does, into the mesh of `material` (a
    /// `[[material]]` the finished scene defines): the scene's object `<material>` loads it.
    pub(super) fn group_in(
        &mut self,
        material: &'static str,
        name: &str,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) {
        let i = match self.others.iter().position(|(m, _)| *m == material) {
            Some(i) => i,
            None => {
                self.others.push((material, Obj::new(self.name)));
                self.others.len() - 1
            }
        };
        self.others[i].1.group(name, positions, triangles);
        self.groups += 1;
        self.triangles += triangles.len();
    }

    /// Appends a built-in shape's positions and triangles as an OBJ group (its normals, if
    /// any, are left out as an export without normals would).
    pub(super) fn mesh(&mut self, name: &str, mesh: &ShapeMesh) {
        self.group(name, &mesh.positions, &mesh.triangles);
    }

    /// An axis-aligned box from `min` to `max` as an OBJ group, faces out.
    pub(super) fn cuboid(&mut self, name: &str, min: Vec3, max: Vec3) {
        let mesh = shape::cuboid(min, max).expect("generated boxes have extent");
        self.mesh(name, &mesh);
    }

    /// An icosphere of `subdivisions` levels as an OBJ group; with `resting`, moved up or down
    /// so its lowest vertex lies at `center.y - radius` (on a floor there, touching it).
    pub(super) fn icosphere(
        &mut self,
        name: &str,
        center: Vec3,
        radius: f32,
        subdivisions: u32,
        resting: bool,
    ) {
        let mut mesh =
            shape::sphere(center, radius, subdivisions).expect("generated spheres are valid");
        if resting {
            let low = mesh.positions.iter().map(|p| p.y).fold(f32::MAX, f32::min);
            let lift = center.y - radius - low;
            for p in &mut mesh.positions {
                p.y += lift;
            }
        }
        self.mesh(name, &mesh);
    }

    /// A longitude-latitude sphere of `slices` around and `stacks` from pole to pole
    /// (`2 slices (stacks - 1)` triangles) as an OBJ group, the tessellation a modeller's UV
    /// sphere exports.
    pub(super) fn uv_sphere(
        &mut self,
        name: &str,
        center: Vec3,
        radius: f32,
        slices: u32,
        stacks: u32,
    ) {
        let mut positions = vec![center + Vec3::Y * radius];
        for i in 1..stacks {
            let theta = std::f32::consts::PI * i as f32 / stacks as f32;
            for j in 0..slices {
                let phi = std::f32::consts::TAU * j as f32 / slices as f32;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                positions.push(center + d * radius);
            }
        }
        positions.push(center - Vec3::Y * radius);
        let bottom = positions.len() as u32 - 1;
        // Ring i (1-based) vertex j is 1 + (i - 1) * slices + j; seen from outside, going up
        // the sphere then along -phi is counter-clockwise.
        let at = |i: u32, j: u32| 1 + (i - 1) * slices + j % slices;
        let mut triangles = Vec::new();
        for j in 0..slices {
            triangles.push([0, at(1, j + 1), at(1, j)]);
            triangles.push([bottom, at(stacks - 1, j), at(stacks - 1, j + 1)]);
        }
        for i in 1..stacks - 1 {
            for j in 0..slices {
                triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
            }
        }
        self.group(name, &positions, &triangles);
    }

    /// The six walls of the interior, facing in, as OBJ groups `floor`, `ceiling`,
    /// `wall-x-min`, `wall-x-max`, `wall-z-min`, `wall-z-max`, each split into `cells` x
    /// `cells` quads; the walls named in `skip` are left out (built elsewhere).
    pub(super) fn walls(&mut self, cells: u32, skip: &[&str]) {
        let (min, max) = self.interior;
        let size = max - min;
        // (name, origin, edge u, edge v) with u x v pointing into the room.
        let walls = [
            ("floor", min, Vec3::Z * size.z, Vec3::X * size.x),
            (
                "ceiling",
                Vec3::new(min.x, max.y, min.z),
                Vec3::X * size.x,
                Vec3::Z * size.z,
            ),
            ("wall-x-min", min, Vec3::Y * size.y, Vec3::Z * size.z),
            (
                "wall-x-max",
                Vec3::new(max.x, min.y, min.z),
                Vec3::Z * size.z,
                Vec3::Y * size.y,
            ),
            ("wall-z-min", min, Vec3::X * size.x, Vec3::Y * size.y),
            (
                "wall-z-max",
                Vec3::new(min.x, min.y, max.z),
                Vec3::Y * size.y,
                Vec3::X * size.x,
            ),
        ];
        for (name, origin, u, v) in walls {
            if skip.contains(&name) {
                continue;
            }
            let (positions, triangles) = grid(origin, u, v, cells);
            self.group(name, &positions, &triangles);
        }
    }

    /// A built-in quad object of the scene file with `material`, and `emission` (W/(m^2 sr))
    /// when it is a light; front along `u x v`.
    pub(super) fn quad(
        &mut self,
        name: &str,
        material: &str,
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        emission: Option<[f32; 3]>,
    ) {
        let _ = write!(
            self.objects,
            "\n[[object]]\nname = \"{name}\"\nmaterial = \"{material}\"\n"
        );
        if let Some([r, g, b]) = emission {
            let _ = writeln!(self.objects, "emission = [{r}, {g}, {b}]");
        }
        let _ = writeln!(
            self.objects,
            "shape = {{ type = \"quad\", origin = {}, edge_u = {}, edge_v = {} }}",
            toml_vec(origin),
            toml_vec(u),
            toml_vec(v)
        );
        self.builtins += 1;
        self.triangles += 2;
    }

    /// A square light of edge `size` centred at `center`, facing `normal`, as a built-in quad.
    pub(super) fn light(
        &mut self,
        name: &str,
        center: Vec3,
        normal: Vec3,
        size: f32,
        emission: [f32; 3],
    ) {
        let n = normal.normalize();
        let (a, b) = n.any_orthonormal_pair();
        // a x b = n, so the quad's front faces `normal`.
        let (u, v) = (a * size, b * size);
        let (u, v) = if u.cross(v).dot(n) > 0.0 {
            (u, v)
        } else {
            (v, u)
        };
        self.quad(name, "grey", center - 0.5 * (u + v), u, v, Some(emission));
    }

    /// The finished room: the scene file with the camera at `position` looking at `look_at`
    /// with a vertical field of view of `fov_degrees`, the material `grey` of reflectance
    /// `grey`, the other `materials` (TOML `[[material]]` tables), the OBJ object `room` and
    /// the built-in shapes.
    pub(super) fn finish(
        self,
        settings: &RoomSettings,
        position: Vec3,
        look_at: Vec3,
        fov_degrees: f32,
        grey: f32,
        materials: &str,
    ) -> Room {
        let mesh_file = format!("{}.obj", self.name);
        // A square film, so the image's square aspect matches it; the focal length gives the
        // field of view, 2 atan(12 / f).
        let focal = 12.0 / (0.5 * fov_degrees.to_radians()).tan();
        let r = settings.resolution;
        let mut scene = format!(
            "# twopass generated room `{}` (seed {}): see twopass_scene::workload::room\n\
             version = 1\nunit = \"m\"\n\n[camera]\nposition = {}\nlook_at = {}\n\
             focal_length = {focal}\nfilm_size = [24, 24]\nresolution = [{r}, {r}]\n\n\
             [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = {grey}\n",
            self.name,
            settings.seed,
            toml_vec(position),
            toml_vec(look_at),
        );
        scene.push_str(materials);
        let _ = write!(
            scene,
            "\n[[object]]\nname = \"room\"\nmaterial = \"grey\"\nshape = {{ type = \"obj\", file = \"{mesh_file}\" }}\n"
        );
        let mut other_meshes = Vec::new();
        for (material, obj) in self.others {
            let file = format!("{}-{material}.obj", self.name);
            let _ = write!(
                scene,
                "\n[[object]]\nname = \"{material}\"\nmaterial = \"{material}\"\nshape = {{ type = \"obj\", file = \"{file}\" }}\n"
            );
            other_meshes.push((file, obj.text));
        }
        scene.push_str(&self.objects);
        Room {
            name: self.name,
            scene,
            mesh_file,
            mesh: self.obj.text,
            other_meshes,
            objects: self.groups + self.builtins,
            triangles: self.triangles,
            interior: self.interior,
            camera: position,
        }
    }
}

/// A TOML array of a vector's components.
fn toml_vec(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// A parallelogram split into `cells` x `cells` quads of two triangles, front along `u x v`.
fn grid(origin: Vec3, u: Vec3, v: Vec3, cells: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let n = cells.max(1);
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(origin + u * (i as f32 / n as f32) + v * (j as f32 / n as f32));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    (positions, triangles)
}
