//! Push-pull over the hierarchy: irradiance pushed down to the leaves (linearly interpolated
//! inside surfaces), the leaves' exitance computed, area-averaged exitance pulled back up.
//!
//! The walk keeps its own stack of open nodes instead of recursing: the input decides how deep
//! the hierarchy is (a cluster tree over thousands of coincident triangles, a bisection tree
//! refined to a tiny element size), and the call stack must not.

use glam::{DVec3, Mat3};
use twopass_brdf::colour::luminance_f64;

use super::directions::{DARK, EMPTY, Incoming, Linear, NOTHING, Table, add_tables};
use super::state::HierarchicalSolver;
use crate::cluster::{Kind, NodeRef};
use crate::element::barycentric_2d;

/// Irradiance (W/m^2) at a surface node's three corners and its uniform shift, emitted and
/// reflected part.
type Corners = [[DVec3; 4]; 2];

/// What a finished node hands up: its area-weighted exitance sum (W, emitted and reflected)
/// and the range of its leaves' exitance luminance.
type Pulled = ([DVec3; 2], (f64, f64));

/// The light a node has: from above plus its own gather.
enum Light {
    /// A cluster's, by direction (boxed: a table is a kilobyte and the stack can be deep).
    Cluster(Box<Incoming>),
    /// A surface node's, by corner.
    Surface(Corners),
}

/// A node just entered. (An open node is moved once, into the walk's stack: boxing it would
/// cost an allocation per node and gather.)
#[allow(clippy::large_enum_variant)]
enum Entered {
    /// An inner node: its children come next.
    Open(Open),
    /// A leaf, finished: its result for its parent.
    Done(Pulled),
}

/// A node of the walk whose children are not all finished.
struct Open {
    node: NodeRef,
    light: Light,
    /// The next child to enter; 2 once both are.
    next: usize,
    /// Sums of the finished children's [`Pulled`].
    power: [DVec3; 2],
    range: (f64, f64),
    /// A cluster's power toward each direction and its linear form, summed over its finished
    /// children.
    radiant: Option<Box<(Table, Linear)>>,
}

impl HierarchicalSolver<'_> {
    /// Push irradiance down to the leaves (linearly interpolated inside surfaces), compute the
    /// leaves' exitance, pull area-averaged exitance back up.
    pub(super) fn push_pull(&mut self) {
        let root = self.clusters.root;
        let light = match root.kind() {
            Kind::Cluster(_) => Light::Cluster(Box::new(NOTHING)),
            Kind::Surface(_) => Light::Surface([[DVec3::ZERO; 4]; 2]),
        };
        let mut stack: Vec<Open> = Vec::new();
        // A root that is a leaf is finished at once: nothing above it to hand its result to.
        if let Entered::Open(open) = self.enter(root, light) {
            stack.push(open);
        }
        while let Some(top) = stack.last_mut() {
            if top.next < 2 {
                let k = top.next;
                top.next += 1;
                let child = self.children(top.node)[k];
                let light = self.handed_down(top, child);
                match self.enter(child, light) {
                    Entered::Open(open) => stack.push(open),
                    Entered::Done(pulled) => {
                        let top = stack.last_mut().expect("the parent is open");
                        self.hand_up(top, child, &pulled);
                    }
                }
                continue;
            }
            let done = stack.pop().expect("the stack has a top");
            let node = done.node;
            let pulled = self.finish(done);
            if let Some(parent) = stack.last_mut() {
                self.hand_up(parent, node, &pulled);
            }
        }
        // Every node has sent its own light now.
        self.settled = self.mesh.nodes.len();
    }

    /// Adds the node's own gather to the light from above. A leaf is finished at once; any
    /// other node is returned open.
    fn enter(&mut self, node: NodeRef, light: Light) -> Entered {
        let light = match (node.kind(), light) {
            (Kind::Cluster(c), Light::Cluster(above)) => {
                Light::Cluster(Box::new(above.add(&self.cluster_gathered[c as usize])))
            }
            (Kind::Surface(n), Light::Surface(above)) => {
                let g = self.gathered[n as usize];
                let here: Corners =
                    std::array::from_fn(|o| std::array::from_fn(|k| above[o][k] + g[o][k]));
                if self.mesh.nodes[n as usize].children.is_none() {
                    let pulled = self.leaf(n, here);
                    self.store_surface(n, &pulled);
                    return Entered::Done(pulled);
                }
                Light::Surface(here)
            }
            _ => unreachable!("a node's light matches its kind"),
        };
        Entered::Open(Open {
            node,
            radiant: matches!(light, Light::Cluster(_)).then(|| Box::new((EMPTY, DARK))),
            light,
            next: 0,
            power: [DVec3::ZERO; 2],
            range: (f64::INFINITY, f64::NEG_INFINITY),
        })
    }

    /// The light the open node `parent` hands down to its child `child`.
    fn handed_down(&self, parent: &Open, child: NodeRef) -> Light {
        match (&parent.light, child.kind()) {
            (Light::Cluster(here), Kind::Cluster(_)) => Light::Cluster(here.clone()),
            (Light::Cluster(here), Kind::Surface(n)) => {
                // Each corner gets the cluster's light by its receiving normal.
                let normals = self.corner_normals(n);
                let at = normals.map(|nk| here.facing(&self.dirs, nk));
                Light::Surface(std::array::from_fn(|o| {
                    [at[0][o], at[1][o], at[2][o], DVec3::ZERO]
                }))
            }
            (Light::Surface(here), Kind::Surface(ch)) => {
                let Kind::Surface(p) = parent.node.kind() else {
                    unreachable!("a surface node's light is by corner")
                };
                let uv = self.mesh.nodes[p as usize].uv;
                let w = self.mesh.nodes[ch as usize]
                    .uv
                    .map(|q| barycentric_2d(uv, q));
                Light::Surface(std::array::from_fn(|o| {
                    std::array::from_fn(|c| match w.get(c) {
                        Some(w) => {
                            here[o][0] * f64::from(w[0])
                                + here[o][1] * f64::from(w[1])
                                + here[o][2] * f64::from(w[2])
                        }
                        None => here[o][3],
                    })
                }))
            }
            (Light::Surface(_), Kind::Cluster(_)) => {
                unreachable!("a surface node's children are surface nodes")
            }
        }
    }

    /// A leaf's exitance from the light it gets.
    fn leaf(&mut self, n: u32, mut here: Corners) -> Pulled {
        let node = self.mesh.nodes[n as usize];
        let t = node.scene_triangle as usize;
        // What arrived through mirrors and glass, per vertex: reflected light (vertices made
        // since the last splat get theirs at the next gather). The lamps' direct light, per
        // vertex: emitted light.
        for (k, &v) in node.vertices.iter().enumerate() {
            if let Some(e) = self.lamp.get(v as usize) {
                here[0][k] += *e;
            }
            if let Some(e) = self
                .specular
                .as_ref()
                .and_then(|s| s.received.get(v as usize))
            {
                here[1][k] += *e;
            }
        }
        // The light the leaf gets: its corners' linear interpolant plus the shifts of the
        // links above it (see [`Link::area_correction`](super::link::Link::area_correction)).
        let mean = |o: usize| (here[o][0] + here[o][1] + here[o][2]) / 3.0 + here[o][3];
        let b = [self.tri_emission[t], self.node_rho(n) * (mean(0) + mean(1))];
        self.corners_in[n as usize] = here;
        let y = luminance_f64(b[0] + b[1]);
        let area = f64::from(node.area);
        ([b[0] * area, b[1] * area], (y, y))
    }

    /// Stores a surface node's exitance and spread.
    fn store_surface(&mut self, n: u32, (power, range): &Pulled) {
        let a = f64::from(self.mesh.nodes[n as usize].area).max(f64::MIN_POSITIVE);
        self.exitance[n as usize] = [power[0] / a, power[1] / a];
        self.spread[n as usize] = range.1 - range.0;
    }

    /// Stores what an open node has summed once both children are finished.
    fn finish(&mut self, done: Open) -> Pulled {
        let pulled = (done.power, done.range);
        match done.node.kind() {
            Kind::Surface(n) => self.store_surface(n, &pulled),
            Kind::Cluster(c) => {
                let area = self.clusters.nodes[c as usize].area.max(f64::MIN_POSITIVE);
                let (power, range) = pulled;
                self.cluster_exitance[c as usize] = [power[0] / area, power[1] / area];
                self.cluster_spread[c as usize] = range.1 - range.0;
                let (table, linear) = *done.radiant.expect("a cluster sums its radiance");
                self.radiant[c as usize] = table;
                self.radiant_linear[c as usize] = linear;
            }
        }
        pulled
    }

    /// Adds a finished child's result to its open parent.
    fn hand_up(&self, parent: &mut Open, child: NodeRef, (p, r): &Pulled) {
        if let Some(sums) = &mut parent.radiant {
            let (radiant, linear) = &mut **sums;
            match child.kind() {
                Kind::Cluster(cc) => {
                    *radiant = add_tables(radiant, &self.radiant[cc as usize]);
                    let child = &self.radiant_linear[cc as usize];
                    linear[0] += child[0];
                    linear[1] += child[1];
                }
                Kind::Surface(n) => {
                    // The triangle's power toward each direction: exitance x area x cos.
                    let normal = self
                        .scene
                        .mesh
                        .geometric_normal(self.mesh.nodes[n as usize].scene_triangle)
                        .as_dvec3();
                    for (j, d) in self.dirs.iter().enumerate() {
                        let c = normal.dot(*d);
                        if c > 0.0 {
                            for (o, p) in p.iter().enumerate() {
                                radiant[o][j] += (*p * c).as_vec3();
                            }
                        }
                    }
                    for (l, p) in linear.iter_mut().zip(p) {
                        *l += Mat3::from_cols(
                            (*p * normal.x).as_vec3(),
                            (*p * normal.y).as_vec3(),
                            (*p * normal.z).as_vec3(),
                        );
                    }
                }
            }
        }
        parent.power[0] += p[0];
        parent.power[1] += p[1];
        parent.range = (parent.range.0.min(r.0), parent.range.1.max(r.1));
    }
}
