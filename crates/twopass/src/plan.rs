//! The planner: which passes a scene requires and why, decided before anything is computed.

use serde::Serialize;
use twopass_brdf::Lobe;
use twopass_scene::Scene;

/// Whether a pass runs, and the reason in words.
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct Decision {
    /// Whether the pass is required.
    pub required: bool,
    /// Why (or why not), for the user.
    pub reason: String,
}

/// The passes a scene requires.
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct Plan {
    /// Radiosity: needed when something reflects diffusely and something emits.
    pub diffuse: Decision,
    /// Ray-traced specular terms: needed when a used material has a non-diffuse lobe.
    pub specular: Decision,
    /// Specular transfer in the radiosity pass (light through mirrors and glass onto diffuse
    /// surfaces, `twopass_radiosity::specular`): needed when a mirror, conductor or dielectric
    /// faces diffuse surfaces that light it and that it lights (both solvers carry it).
    pub specular_transfer: Decision,
    /// Per-pixel caustics in the hybrids (light traced through glass onto the diffuse surfaces
    /// the camera sees, `twopass_trace::light_tracing`): needed when the specular transfer
    /// runs and a dielectric is among the specular objects.
    pub caustics: Decision,
    /// The sky (`[sky]`): lights every ray that escapes the scene, in both passes; without one
    /// nothing is sampled for it.
    pub sky: Decision,
    /// The radiosity solver `--solver auto` runs, and why.
    pub solver: SolverDecision,
}

/// Which radiosity solver runs by default, and the reason in words.
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct SolverDecision {
    /// `progressive` or `hierarchical`.
    pub method: String,
    /// Why, for the user.
    pub reason: String,
}

/// Decides the passes from the objects' materials, emission and the lamps (unused materials
/// don't count).
pub fn plan(scene: &Scene) -> Plan {
    let used = || {
        scene
            .objects
            .iter()
            .map(|o| (o, &scene.materials[o.material as usize]))
    };
    let diffuse_objects: Vec<&str> = used()
        .filter(|(_, m)| m.material.reflects_diffusely())
        .map(|(o, _)| o.name.as_str())
        .collect();
    let lamps = scene.lamps.len();
    let sky_lit = usize::from(scene.sky.is_some());
    let emitters = scene.emitters.len() + lamps + sky_lit;
    let diffuse = match (diffuse_objects.len(), emitters) {
        (_, 0) => Decision {
            required: false,
            reason: "nothing emits light".into(),
        },
        (0, _) => Decision {
            required: false,
            reason: "no surface reflects diffusely".into(),
        },
        (n, e) => Decision {
            required: true,
            reason: match (lamps, sky_lit) {
                (0, 0) => format!("{n} diffusely reflecting object(s) lit by {e} emitter(s)"),
                (l, 0) => format!(
                    "{n} diffusely reflecting object(s) lit by {} emitter(s) and {l} lamp(s)",
                    e - l
                ),
                (l, _) => format!(
                    "{n} diffusely reflecting object(s) lit by {} emitter(s), {l} lamp(s) and the sky",
                    e - l - 1
                ),
            },
        },
    };
    let mut lobes: Vec<String> = used()
        .filter_map(|(_, m)| {
            m.material
                .lobe()
                .map(|l| format!("{} ({})", m.name, lobe_name(l)))
        })
        .collect();
    lobes.sort();
    lobes.dedup();
    let specular = if lobes.is_empty() {
        Decision {
            required: false,
            reason: "every material is purely diffuse".into(),
        }
    } else if emitters == 0 {
        Decision {
            required: false,
            reason: "nothing emits light".into(),
        }
    } else {
        Decision {
            required: true,
            reason: format!("non-diffuse materials: {}", lobes.join(", ")),
        }
    };
    let (method, reason) = twopass_radiosity::Method::Auto.choose(scene);
    let specular_transfer = if diffuse.required {
        let (needed, why) = twopass_radiosity::specular::decide(scene);
        Decision {
            required: needed,
            reason: why,
        }
    } else {
        Decision {
            required: false,
            reason: "no radiosity pass".into(),
        }
    };
    let glass: Vec<&str> = used()
        .filter(|(_, m)| m.material.is_dielectric())
        .map(|(o, _)| o.name.as_str())
        .collect();
    let caustics = if !specular_transfer.required {
        Decision {
            required: false,
            reason: "no light through mirrors and glass in the radiosity pass".into(),
        }
    } else if glass.is_empty() {
        Decision {
            required: false,
            reason: "no refracting surface focuses light: the element mesh shows what mirrors \
                     reflect"
                .into(),
        }
    } else {
        Decision {
            required: true,
            reason: format!(
                "light focused through {} is light-traced per pixel by the hybrids instead of \
                 shown blurred by the element mesh",
                glass.join(", ")
            ),
        }
    };
    let solver = SolverDecision {
        method: method.name().into(),
        reason,
    };
    let sky = match &scene.sky {
        Some(sky) => Decision {
            required: true,
            reason: sky.describe(),
        },
        None => Decision {
            required: false,
            reason: "no [sky] table: rays that leave the scene see black".into(),
        },
    };
    Plan {
        diffuse,
        specular,
        specular_transfer,
        caustics,
        sky,
        solver,
    }
}

/// The scene-file name of a lobe's model.
pub fn lobe_name(lobe: &Lobe) -> &'static str {
    match lobe {
        Lobe::Phong {
            normalized: false, ..
        } => "phong",
        Lobe::Phong {
            normalized: true, ..
        } => "phong, normalized",
        Lobe::BlinnPhong {
            normalized: false, ..
        } => "blinn_phong",
        Lobe::BlinnPhong {
            normalized: true, ..
        } => "blinn_phong, normalized",
        Lobe::CookTorrance { .. } => "cook_torrance",
        Lobe::Mirror { .. } => "mirror",
        Lobe::Dielectric { .. } => "dielectric",
        Lobe::Conductor { .. } => "conductor",
        _ => "other",
    }
}
