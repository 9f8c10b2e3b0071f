//! What a solver keeps of the specular transfer ([`crate::specular`]) on its element mesh: the
//! transfer itself, the irradiance its deposits give each vertex, and what each node has sent
//! through the mirrors and glass. Both solvers hold one [`SpecularReceivers`].

use glam::DVec3;

use crate::element::ElementMesh;
use crate::specular::{self, Deposit, Specular, VertexAreas};

/// The specular transfer of a solve and the light it has brought to the element vertices.
pub(crate) struct SpecularReceivers {
    /// The transfer: its targets, every deposit so far and the rays cast.
    pub transfer: Specular,
    /// Per vertex: irradiance that arrived through specular surfaces (every deposit so far,
    /// splatted on the current mesh), W/m^2.
    pub received: Vec<DVec3>,
    /// Per vertex: the part of `received` that left an emitter as emission and went through a
    /// refraction (the focused caustic), W/m^2.
    pub focused: Vec<DVec3>,
    /// Per element-mesh node: the exitance (emitted, reflected, W/m^2) it has sent through the
    /// specular surfaces; `None` for nodes split off since (they have their parent's,
    /// [`specular::sent`]).
    pub sent: Vec<Option<[DVec3; 2]>>,
    /// The area each vertex stands for, with its leaves, on the mesh last splatted onto.
    pub vertex_areas: VertexAreas,
    /// A per-vertex buffer of zeros for the splats.
    scratch: Vec<DVec3>,
}

impl SpecularReceivers {
    /// The transfer with nothing received or sent yet (call [`Self::resplat`] before use).
    pub fn new(transfer: Specular) -> Self {
        Self {
            transfer,
            received: Vec::new(),
            focused: Vec::new(),
            sent: Vec::new(),
            vertex_areas: VertexAreas::default(),
            scratch: Vec::new(),
        }
    }

    /// The vertex areas of `mesh`, and every deposit so far splatted onto it afresh (after a
    /// refinement the deposits land on the finer elements).
    pub fn resplat(&mut self, mesh: &ElementMesh) {
        self.vertex_areas = VertexAreas::new(mesh);
        self.sent.resize(mesh.nodes.len(), None);
        self.received = vec![DVec3::ZERO; mesh.vertices.len()];
        self.focused = vec![DVec3::ZERO; mesh.vertices.len()];
        self.splat(mesh, None);
    }

    /// Splats `deposits` (or, with `None`, every deposit so far) onto the vertices of `mesh`,
    /// their whole power into [`Self::received`] and their focused part into
    /// [`Self::focused`]; returns the whole power's irradiance per touched vertex
    /// ([`specular::splat`]).
    pub fn splat(
        &mut self,
        mesh: &ElementMesh,
        deposits: Option<&mut [Deposit]>,
    ) -> Vec<(u32, DVec3)> {
        let deposits = match deposits {
            Some(d) => d,
            None => &mut self.transfer.deposits[..],
        };
        let whole = specular::splat(
            mesh,
            &self.vertex_areas,
            deposits,
            &mut self.scratch,
            specular::power,
            &mut self.received,
        );
        specular::splat(
            mesh,
            &self.vertex_areas,
            deposits,
            &mut self.scratch,
            specular::focused,
            &mut self.focused,
        );
        whole
    }

    /// What node `n` has sent through the specular surfaces ([`specular::sent`]).
    pub fn sent(&self, mesh: &ElementMesh, n: u32) -> [DVec3; 2] {
        specular::sent(mesh, &self.sent, n)
    }

    /// Notes that each node of `changes` has now sent its exitance change too.
    pub fn note_sent(&mut self, mesh: &ElementMesh, changes: &[(u32, [DVec3; 2])]) {
        for &(n, d) in changes {
            let sent = self.sent(mesh, n);
            self.sent[n as usize] = Some([sent[0] + d[0], sent[1] + d[1]]);
        }
    }

    /// Keeps the `deposits` of a shot that cast `rays` (so that they can be splatted again
    /// onto a refined mesh).
    pub fn keep(&mut self, deposits: Vec<Deposit>, rays: u64) {
        self.transfer.rays += rays;
        self.transfer.deposits.extend(deposits);
    }

    /// Rays the transfer cast and deposits it made so far.
    pub fn counts(&self) -> (u64, usize) {
        (self.transfer.rays, self.transfer.deposits.len())
    }
}
