//! The sweep's plan: the knobs varied one at a time around a base setting, the two crossed
//! pairs (element size x samples per pixel for the radiosity-based methods, samples per pixel
//! x shadow grid for Whitted and the hybrids), and which solve each render reads.

use crate::pipeline::RenderMethod;
use crate::preset::{RadiosityKnobs, RenderKnobs};

/// The knobs swept, and the base setting the others vary around.
pub(super) struct Sweep {
    /// Image width, pixels (height from the scene camera's aspect ratio).
    pub(super) width: u32,
    pub(super) reference_spp: u32,
    pub(super) base_render: RenderKnobs,
    /// Base radiosity setting with the element size as a divisor of the scene diagonal.
    pub(super) base_divisor: f32,
    pub(super) base_unshot: f64,
    pub(super) base_visibility: (u32, u32),
    pub(super) element_divisors: Vec<f32>,
    /// A cheaper visibility estimate (first, most rays) crossed with every element size: on
    /// coarse meshes the discretization error hides what fewer shadow rays cost.
    pub(super) cheap_visibility: Option<(u32, u32)>,
    /// A looser stop (unshot fraction) crossed with every element size, at both visibilities:
    /// the last shots may cost more time than the error they remove (the ambient term stands
    /// in for what is left unshot).
    pub(super) loose_unshot: Option<f64>,
    pub(super) unshots: Vec<f64>,
    pub(super) visibility: Vec<(u32, u32)>,
    /// Samples per pixel crossed with shadow grids for Whitted and the hybrids.
    pub(super) spps: Vec<u32>,
    pub(super) shadow_grids: Vec<u32>,
    pub(super) depths: Vec<u32>,
    /// Gather rays per camera sample, crossed with the samples per pixel for the gathered
    /// hybrid (whose indirect light they estimate).
    pub(super) gather_rays: Vec<u32>,
    /// Samples per pixel crossed with the element sizes for the radiosity-based methods.
    pub(super) radiosity_spps: Vec<u32>,
    /// Rays per point of the final gather over the element mesh (what `twopass bake` gathers
    /// its element-mesh outputs with), crossed with `final_gather_divisors`; each gathered
    /// solve is rendered as radiosity alone at every one of `radiosity_spps`.
    pub(super) final_gathers: Vec<u32>,
    /// Element sizes (divisors of the scene diagonal) the final gathers run over: a coarse
    /// solve gathered can be cheaper than a fine one at the same error.
    pub(super) final_gather_divisors: Vec<f32>,
    /// First-pass samples per pixel of adaptive anti-aliasing, tried beside every
    /// radiosity-based setting of more samples per pixel than this (element size x samples
    /// per pixel, and the hybrids' samples x shadow grid); `None` for no adaptive runs.
    pub(super) adaptive_base: Option<u32>,
    pub(super) reference_spps: Vec<u32>,
}

impl Sweep {
    pub(super) fn full() -> Self {
        Self {
            width: 256,
            reference_spp: 8192,
            base_render: RenderKnobs {
                spp: 4,
                depth: 8,
                shadow_grid: 2,
                adaptive: None,
                gather_rays: crate::preset::default_gather_rays(),
            },
            base_divisor: 24.0,
            base_unshot: 1e-3,
            base_visibility: (4, 16),
            element_divisors: vec![8.0, 12.0, 16.0, 24.0, 32.0, 48.0],
            cheap_visibility: Some((1, 1)),
            loose_unshot: Some(1e-2),
            unshots: vec![1e-1, 1e-2, 1e-3, 1e-4],
            visibility: vec![(1, 1), (4, 16), (16, 64)],
            spps: vec![1, 4, 16],
            shadow_grids: vec![1, 2, 4],
            depths: vec![1, 2, 4, 8],
            gather_rays: vec![2, 4, 8, 16],
            radiosity_spps: vec![1, 4, 16, 64],
            final_gathers: vec![4, 16, 64],
            final_gather_divisors: vec![8.0, 16.0, 24.0],
            adaptive_base: Some(4),
            reference_spps: vec![1, 4, 16, 64, 256, 1024, 2048],
        }
    }

    pub(super) fn quick() -> Self {
        Self {
            width: 48,
            reference_spp: 256,
            base_render: RenderKnobs {
                spp: 1,
                depth: 2,
                shadow_grid: 1,
                adaptive: None,
                gather_rays: 2,
            },
            base_divisor: 8.0,
            base_unshot: 1e-2,
            base_visibility: (1, 4),
            element_divisors: vec![4.0, 8.0],
            cheap_visibility: None,
            loose_unshot: None,
            unshots: vec![1e-1, 1e-2],
            visibility: vec![(1, 4)],
            spps: vec![1, 2],
            shadow_grids: vec![1],
            depths: vec![2],
            gather_rays: vec![1, 2],
            radiosity_spps: vec![1],
            final_gathers: vec![2],
            final_gather_divisors: vec![8.0],
            adaptive_base: None,
            reference_spps: vec![1, 4],
        }
    }
}

/// One solve of the sweep: which knob it varies and its settings.
pub(super) struct SolveSpec {
    pub(super) knob: &'static str,
    pub(super) knobs: RadiosityKnobs,
    /// Rays per point of a final gather over the element mesh after the solve (`None`: the
    /// solution as solved). Only radiosity alone renders a gathered solve.
    pub(super) gather: Option<u32>,
}

/// One render of the sweep.
pub(super) struct RunSpec {
    pub(super) method: RenderMethod,
    pub(super) knob: &'static str,
    pub(super) render: RenderKnobs,
    /// Index into the solves, for the radiosity-based methods.
    pub(super) solve: Option<usize>,
}

/// The solves and runs of a sweep for `methods`.
pub(super) fn plan_runs(
    sweep: &Sweep,
    diagonal: f32,
    methods: &[RenderMethod],
) -> (Vec<SolveSpec>, Vec<RunSpec>) {
    let knobs =
        |divisor: f32, unshot: f64, (vmin, vmax): (u32, u32), adaptive: bool| RadiosityKnobs {
            element_size: diagonal / divisor,
            unshot,
            visibility_min: vmin,
            visibility_max: vmax,
            adaptive,
        };
    let base = knobs(
        sweep.base_divisor,
        sweep.base_unshot,
        sweep.base_visibility,
        true,
    );
    let mut solves = vec![SolveSpec {
        knob: "base",
        knobs: base,
        gather: None,
    }];
    let mut add_gathered = |knob: &'static str, k: RadiosityKnobs, gather: Option<u32>| {
        if !solves.iter().any(|s| s.knobs == k && s.gather == gather) {
            solves.push(SolveSpec {
                knob,
                knobs: k,
                gather,
            });
        }
    };
    let mut add = |knob: &'static str, k: RadiosityKnobs| add_gathered(knob, k, None);
    for &d in &sweep.element_divisors {
        add(
            "element-size",
            knobs(d, sweep.base_unshot, sweep.base_visibility, true),
        );
    }
    for &u in &sweep.unshots {
        add(
            "unshot",
            knobs(sweep.base_divisor, u, sweep.base_visibility, true),
        );
    }
    for &v in &sweep.visibility {
        add(
            "visibility-rays",
            knobs(sweep.base_divisor, sweep.base_unshot, v, true),
        );
    }
    // Every element size at the cheaper visibility and the looser stop too.
    let crossings = [
        (
            "element-size-visibility",
            sweep.cheap_visibility,
            Some(sweep.base_unshot),
        ),
        (
            "element-size-unshot",
            Some(sweep.base_visibility),
            sweep.loose_unshot,
        ),
        (
            "element-size-visibility-unshot",
            sweep.cheap_visibility,
            sweep.loose_unshot,
        ),
    ];
    for (knob, visibility, unshot) in crossings {
        if let (Some(v), Some(u)) = (visibility, unshot) {
            for &d in &sweep.element_divisors {
                add(knob, knobs(d, u, v, true));
            }
        }
    }
    add(
        "adaptive",
        knobs(
            sweep.base_divisor,
            sweep.base_unshot,
            sweep.base_visibility,
            false,
        ),
    );
    if methods.contains(&RenderMethod::Radiosity) {
        for &d in &sweep.final_gather_divisors {
            for &rays in &sweep.final_gathers {
                let k = knobs(d, sweep.base_unshot, sweep.base_visibility, true);
                add_gathered("final-gather", k, Some(rays));
            }
        }
    }
    if !methods.iter().any(|m| m.needs_radiosity()) {
        solves.clear();
    }

    let base_render = sweep.base_render;
    let mut runs = Vec::new();
    for &method in methods {
        let mut push = |knob: &'static str, render: RenderKnobs, solve: Option<usize>| {
            let dup = runs
                .iter()
                .any(|r: &RunSpec| r.method == method && r.render == render && r.solve == solve);
            if !dup {
                runs.push(RunSpec {
                    method,
                    knob,
                    render,
                    solve,
                });
            }
        };
        if method == RenderMethod::Reference {
            for &spp in &sweep.reference_spps {
                push("spp", RenderKnobs { spp, ..base_render }, None);
            }
            continue;
        }
        if method.needs_radiosity() {
            // Every solve at the base render, then the two knobs that dominate the error
            // (element size and samples per pixel) crossed.
            for (i, s) in solves.iter().enumerate() {
                if s.gather.is_none() || method == RenderMethod::Radiosity {
                    push(s.knob, base_render, Some(i));
                }
            }
            for (i, s) in solves.iter().enumerate() {
                if s.gather.is_some() {
                    // A gathered element mesh against anti-aliasing, as the solves below.
                    if method == RenderMethod::Radiosity {
                        for &spp in &sweep.radiosity_spps {
                            let render = RenderKnobs { spp, ..base_render };
                            push("final-gather-spp", render, Some(i));
                        }
                    }
                    continue;
                }
                let k = &s.knobs;
                let visibility = (k.visibility_min, k.visibility_max);
                let crossed = k.adaptive
                    && (visibility == sweep.base_visibility
                        || Some(visibility) == sweep.cheap_visibility)
                    && (k.unshot == sweep.base_unshot || Some(k.unshot) == sweep.loose_unshot);
                if crossed {
                    for &spp in &sweep.radiosity_spps {
                        let render = RenderKnobs { spp, ..base_render };
                        push("element-size-spp", render, Some(i));
                        if let Some(adaptive) = sweep.adaptive_base.filter(|&b| b < spp) {
                            let render = RenderKnobs {
                                adaptive: Some(adaptive),
                                ..render
                            };
                            push("element-size-spp-adaptive", render, Some(i));
                        }
                    }
                }
            }
            if method == RenderMethod::Radiosity {
                continue; // no shadow rays, no recursion: nothing else to vary
            }
        }
        // Whitted and the hybrids (on the base solve): anti-aliasing against shadow rays, and
        // the recursion depth.
        let solve = method.needs_radiosity().then_some(0);
        push("base", base_render, solve);
        for &spp in &sweep.spps {
            for &shadow_grid in &sweep.shadow_grids {
                let render = RenderKnobs {
                    spp,
                    shadow_grid,
                    ..base_render
                };
                push("spp-shadow-grid", render, solve);
                let adaptive = sweep.adaptive_base.filter(|&b| b < spp);
                if let (Some(adaptive), true) = (adaptive, method.needs_radiosity()) {
                    let render = RenderKnobs {
                        adaptive: Some(adaptive),
                        ..render
                    };
                    push("spp-shadow-grid-adaptive", render, solve);
                }
            }
        }
        if method == RenderMethod::Hybrid {
            for &spp in &sweep.spps {
                for &gather_rays in &sweep.gather_rays {
                    let render = RenderKnobs {
                        spp,
                        gather_rays,
                        ..base_render
                    };
                    push("spp-gather-rays", render, solve);
                }
            }
        }
        for &depth in &sweep.depths {
            push(
                "depth",
                RenderKnobs {
                    depth,
                    ..base_render
                },
                solve,
            );
        }
    }
    (solves, runs)
}
