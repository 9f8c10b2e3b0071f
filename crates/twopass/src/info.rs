//! `twopass info SCENE`: what a scene holds and which passes it requires.

use std::collections::BTreeMap;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use crate::context::Context;
use crate::error::CliError;
use crate::plan::{Plan, lobe_name, plan};

/// Arguments of `twopass info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Scene file (.toml), mesh (.obj) or glTF 2.0 (.gltf, .glb).
    pub scene: PathBuf,
}

#[derive(Serialize)]
struct EmitterInfo {
    object: String,
    /// W/(m^2 sr) per channel.
    radiance: [f32; 3],
    /// Scene units squared.
    area: f32,
    /// pi * L_e * area per channel.
    power: [f32; 3],
}

#[derive(Serialize)]
struct LampInfo {
    name: String,
    /// `point`, `spot` or `directional`.
    kind: &'static str,
    /// Scene units (point and spot lamps).
    position: Option<[f32; 3]>,
    /// Unit direction the light travels (spot: the cone's axis; directional).
    direction: Option<[f32; 3]>,
    /// Inner and outer cone half angles, degrees (spot lamps).
    cone_degrees: Option<[f32; 2]>,
    /// W/sr per channel (point, spot: on the axis), or W/m^2 (directional).
    intensity: [f32; 3],
    /// W per channel; a directional lamp's is what crosses the scene's bounding sphere.
    power: [f32; 3],
}

impl LampInfo {
    fn of(lamp: &twopass_scene::Lamp, scene_diagonal: f32) -> Self {
        use twopass_scene::LampKind;
        let (kind, position, direction, cone_degrees) = match lamp.kind {
            LampKind::Point => ("point", Some(lamp.position.to_array()), None, None),
            LampKind::Spot {
                direction,
                cos_inner,
                cos_outer,
            } => (
                "spot",
                Some(lamp.position.to_array()),
                Some(direction.to_array()),
                Some([cos_inner, cos_outer].map(|c| c.clamp(-1.0, 1.0).acos().to_degrees())),
            ),
            LampKind::Directional { direction } => {
                ("directional", None, Some(direction.to_array()), None)
            }
        };
        Self {
            name: lamp.name.clone(),
            kind,
            position,
            direction,
            cone_degrees,
            intensity: lamp.intensity.to_array(),
            power: lamp.power(scene_diagonal).to_array(),
        }
    }

    /// One line of `twopass info`'s text.
    fn line(&self) -> String {
        let v = |a: [f32; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
        let e = |a: [f32; 3]| format!("({:.6e}, {:.6e}, {:.6e})", a[0], a[1], a[2]);
        let mut s = format!("lamp       {}: {}", self.name, self.kind);
        if let Some(p) = self.position {
            s += &format!(" at {}", v(p));
        }
        if let Some(d) = self.direction {
            s += &format!(" toward {}", v(d));
        }
        if let Some([inner, outer]) = self.cone_degrees {
            s += &format!(", cone {inner:.2} to {outer:.2} degrees");
        }
        let unit = if self.kind == "directional" {
            "W/m^2"
        } else {
            "W/sr"
        };
        s += &format!(
            ", intensity {} {unit}, power {}",
            e(self.intensity),
            e(self.power)
        );
        s
    }
}

#[derive(Serialize)]
struct Info {
    scene: PathBuf,
    /// Every triangle the passes see, placed copies of instanced meshes included.
    triangles: usize,
    vertices: usize,
    /// Triangles stored in memory: the placed copies repeat stored ones.
    stored_triangles: usize,
    /// Objects that are placed copies of another's mesh (glTF instancing).
    placed_copies: usize,
    /// Memory of the mesh and its trees, bytes.
    geometry_bytes: usize,
    objects: usize,
    materials_by_type: BTreeMap<String, usize>,
    emitters: Vec<EmitterInfo>,
    lamps: Vec<LampInfo>,
    bounds_min: [f32; 3],
    bounds_max: [f32; 3],
    total_area: f64,
    resolution: [u32; 2],
    bvh_nodes: usize,
    bvh_build_ms: f64,
    plan: Plan,
    warnings: Vec<String>,
}

/// Loads the scene and prints its summary (text, or JSON with `--json`).
pub fn run(args: &InfoArgs, ctx: &Context) -> Result<(), CliError> {
    let (scene, warnings) = ctx.load_scene(&args.scene)?;
    let camera = ctx.camera(&scene.camera)?;
    let mut materials_by_type = BTreeMap::new();
    for m in &scene.materials {
        let kind = m.material.lobe().map_or("lambert", lobe_name);
        *materials_by_type.entry(kind.to_owned()).or_insert(0) += 1;
    }
    let info = Info {
        scene: args.scene.clone(),
        triangles: scene.mesh.triangle_count(),
        vertices: scene.mesh.vertex_count(),
        stored_triangles: scene.mesh.stored_triangle_count(),
        placed_copies: scene.mesh.repeats().len(),
        geometry_bytes: scene.mesh.bytes() + scene.accel().bytes(),
        objects: scene.objects.len(),
        materials_by_type,
        emitters: scene
            .emitters
            .iter()
            .map(|e| EmitterInfo {
                object: scene.objects[e.object as usize].name.clone(),
                radiance: e.radiance.to_array(),
                area: e.area,
                power: e.power.to_array(),
            })
            .collect(),
        lamps: scene
            .lamps
            .iter()
            .map(|l| LampInfo::of(l, scene.bounds.diagonal()))
            .collect(),
        bounds_min: scene.bounds.min.to_array(),
        bounds_max: scene.bounds.max.to_array(),
        total_area: scene.total_area(),
        resolution: [camera.width, camera.height],
        bvh_nodes: scene.accel().node_count(),
        bvh_build_ms: scene.accel().build_time().as_secs_f64() * 1e3,
        plan: plan(&scene),
        warnings: warnings.iter().map(ToString::to_string).collect(),
    };
    if ctx.json {
        crate::output::print_json(&info)?;
        return Ok(());
    }
    for w in &info.warnings {
        errln!("warning: {w}");
    }
    if ctx.quiet {
        return Ok(());
    }
    outln!("scene      {}", info.scene.display());
    outln!(
        "geometry   {} triangles, {} vertices, {} objects, area {:.6e} units^2",
        info.triangles,
        info.vertices,
        info.objects,
        info.total_area
    );
    if info.placed_copies > 0 {
        outln!(
            "instances  {} objects are placed copies: {} of the triangles stored, {:.1} MiB of mesh and trees",
            info.placed_copies,
            info.stored_triangles,
            info.geometry_bytes as f64 / (1 << 20) as f64
        );
    }
    let kinds: Vec<String> = info
        .materials_by_type
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    outln!("materials  {}", kinds.join(", "));
    outln!(
        "bounds     [{:.1}, {:.1}, {:.1}] to [{:.1}, {:.1}, {:.1}]",
        info.bounds_min[0],
        info.bounds_min[1],
        info.bounds_min[2],
        info.bounds_max[0],
        info.bounds_max[1],
        info.bounds_max[2]
    );
    outln!(
        "camera     {} x {} pixels",
        info.resolution[0],
        info.resolution[1]
    );
    outln!(
        "bvh        {} nodes, built in {:.2} ms",
        info.bvh_nodes,
        info.bvh_build_ms
    );
    if info.emitters.is_empty() {
        outln!("emitters   none");
    }
    for e in &info.emitters {
        outln!(
            "emitter    {}: radiance ({}, {}, {}) W/(m^2 sr), area {:.6e}, power ({:.6e}, {:.6e}, {:.6e})",
            e.object,
            e.radiance[0],
            e.radiance[1],
            e.radiance[2],
            e.area,
            e.power[0],
            e.power[1],
            e.power[2]
        );
    }
    for l in &info.lamps {
        outln!("{}", l.line());
    }
    let say = |name: &str, d: &crate::plan::Decision| -> Result<(), CliError> {
        outln!(
            "{name:<17} {}: {}",
            if d.required { "required" } else { "skipped " },
            d.reason
        );
        Ok(())
    };
    say("diffuse pass", &info.plan.diffuse)?;
    say("specular pass", &info.plan.specular)?;
    say("specular transfer", &info.plan.specular_transfer)?;
    say("caustics", &info.plan.caustics)?;
    say("sky", &info.plan.sky)?;
    if info.plan.diffuse.required {
        outln!(
            "radiosity         {}: {}",
            info.plan.solver.method,
            info.plan.solver.reason
        );
    }
    Ok(())
}
