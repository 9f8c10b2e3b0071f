//! A radiosity solution: per-vertex radiosity over the element mesh, and its lookup at any
//! surface point for the ray tracer.

use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;

use crate::element::{ElementMesh, Locator};

/// Per-vertex radiosity (W/m^2 per RGB channel, areas in scene units) over the element mesh,
/// split into emission, direct and indirect parts, plus the ambient term of a partial solve.
#[derive(Debug, Clone)]
pub struct Solution {
    mesh: ElementMesh,
    /// The mesh laid out for the per-sample lookup.
    locator: Locator,
    /// Emission + all reflected light (without the ambient term).
    radiosity: Vec<Rgb>,
    /// Light reflected once from the emitters (seen directly: what shadow rays find).
    direct: Vec<Rgb>,
    /// Light reflected after two or more bounces, or carried through specular surfaces.
    indirect: Vec<Rgb>,
    /// The ambient estimate of what is not shot yet, times the reflectance.
    ambient: Vec<Rgb>,
    /// The part of `indirect` that left an emitter as emission and reached the surface through
    /// at least one refraction (the focused caustic, L S+ D with a refraction in S+); empty when
    /// the solve did not separate it.
    focused: Vec<Rgb>,
}

impl Solution {
    /// A solution from its per-vertex parts (all the length of `mesh.vertices`).
    pub fn new(
        mesh: ElementMesh,
        radiosity: Vec<Rgb>,
        direct: Vec<Rgb>,
        indirect: Vec<Rgb>,
        ambient: Vec<Rgb>,
    ) -> Self {
        let n = mesh.vertices.len();
        assert!(
            radiosity.len() == n && direct.len() == n && indirect.len() == n && ambient.len() == n,
            "one value per vertex"
        );
        Self {
            locator: Locator::new(&mesh),
            mesh,
            radiosity,
            direct,
            indirect,
            ambient,
            focused: Vec::new(),
        }
    }

    /// The same solution with its focused caustic part per vertex, W/m^2 (the part of the
    /// indirect light that left an emitter and reached the surface through a refraction: the
    /// light a renderer may show per pixel instead, [`DiffuseRadiance::focused_caustic_radiance`]).
    /// `focused` has one value per vertex, or none (the solve did not separate it).
    pub fn with_focused_caustics(mut self, focused: Vec<Rgb>) -> Self {
        assert!(
            focused.is_empty() || focused.len() == self.mesh.vertices.len(),
            "one value per vertex"
        );
        self.focused = focused;
        self
    }

    /// The focused caustic part per vertex, W/m^2, when the solve separated it.
    pub fn focused_caustics(&self) -> Option<&[Rgb]> {
        (!self.focused.is_empty()).then_some(&self.focused[..])
    }

    /// The element mesh the values live on.
    pub fn mesh(&self) -> &ElementMesh {
        &self.mesh
    }

    /// Radiosity per vertex including the ambient term, W/m^2: what is displayed.
    pub fn vertex_radiosity(&self) -> Vec<Rgb> {
        self.radiosity
            .iter()
            .zip(&self.ambient)
            .map(|(b, a)| *b + *a)
            .collect()
    }

    /// Radiosity per vertex without the ambient term (emission + shot light), W/m^2.
    pub fn shot_radiosity(&self) -> &[Rgb] {
        &self.radiosity
    }

    /// Direct part per vertex (light reflected once from the emitters, seen directly), W/m^2.
    pub fn direct(&self) -> &[Rgb] {
        &self.direct
    }

    /// Indirect part per vertex (two or more bounces, or through mirrors and glass; without
    /// ambient), W/m^2.
    pub fn indirect(&self) -> &[Rgb] {
        &self.indirect
    }

    /// Ambient term per vertex (reflectance times the ambient radiosity), W/m^2.
    pub fn ambient(&self) -> &[Rgb] {
        &self.ambient
    }

    fn interpolate(&self, values: impl Fn(usize) -> Rgb, triangle: u32, b: [f32; 3]) -> Rgb {
        match self.locator.locate(&self.mesh, triangle, b[1], b[2]) {
            None => Rgb::ZERO,
            Some((leaf, w)) => {
                let v = self.mesh.nodes[leaf as usize].vertices;
                let w = w.map(|x| x.clamp(0.0, 1.0));
                let sum = (w[0] + w[1] + w[2]).max(f32::MIN_POSITIVE);
                (values(v[0] as usize) * w[0]
                    + values(v[1] as usize) * w[1]
                    + values(v[2] as usize) * w[2])
                    / sum
            }
        }
    }

    /// The radiance (W/(m^2 sr)) of a Lambertian surface whose radiosity is the per-vertex
    /// `part` plus the ambient term, interpolated at `barycentric` on `triangle`.
    fn with_ambient(&self, part: &[Rgb], triangle: u32, barycentric: [f32; 3]) -> Rgb {
        let radiosity = |v: usize| part[v] + self.ambient[v];
        self.interpolate(radiosity, triangle, barycentric) * std::f32::consts::FRAC_1_PI
    }
}

impl DiffuseRadiance for Solution {
    fn radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb {
        self.with_ambient(&self.radiosity, triangle, barycentric)
    }

    fn indirect_radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb {
        self.with_ambient(&self.indirect, triangle, barycentric)
    }

    fn separates_focused_caustics(&self) -> bool {
        !self.focused.is_empty()
    }

    fn focused_caustic_radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb {
        if self.focused.is_empty() {
            return Rgb::ZERO;
        }
        self.interpolate(|v| self.focused[v], triangle, barycentric) * std::f32::consts::FRAC_1_PI
    }
}
