//! `adaptive-beams`: adaptive beam tracing for surface and volume caustics
//! (Liktor & Dachsbacher 2011, "Real-Time Volume Caustics with Adaptive Beam Tracing").
//!
//! A coarse projected grid (16×16 by default) in the light's view is refined on the
//! GPU for up to four levels wherever the split oracle asks for it (Sect. 4.2): at
//! silhouettes and other discontinuities of the specular surfaces, for beams that
//! carry much light or focus it strongly, and for beams that look large from the
//! camera. Each leaf triangle becomes a beam with a tight six-triangle hull (Sect. 4.3),
//! rasterized from the camera to add volume and surface caustics. The pipeline lives
//! in the `beams` crate, shared with `static-grid`; this crate holds the method's
//! parameters and defaults (the paper's: 16² base grid, 3 levels, tight hulls; the
//! paper gives no thresholds for its oracle, so it asks for every split that misplaces
//! a pixel of light, and a beam budget of Table 1's largest count, 5,300, takes the
//! splits of highest priority, coarse levels first).

use beams::{BeamConfig, BeamMethod, BeamParams, CAPABILITIES, HullKind, Refinement};
use caustics_gpu::{GpuContext, Renderer};
use caustics_method::{Capabilities, CausticsMethod, CounterDoc, Method, MethodError, Unsupported};
use caustics_scene::Scene;

/// Registry name.
pub const NAME: &str = "adaptive-beams";

caustics_method::method_params! {
    /// Parameters of `adaptive-beams` (defaults: the paper's Sect. 8 settings).
    pub struct AdaptiveBeamsParams {
        group
        /// The beam settings shared with `static-grid`: a 16² base grid, tight hulls.
        beams: BeamParams = BeamParams { grid: 16, hull: HullKind::Tight, ..Default::default() };
        group
        /// Refinement levels and the split oracle.
        refinement: Refinement;
    }
}

impl AdaptiveBeamsParams {
    /// The pipeline configuration.
    pub fn config(&self) -> BeamConfig {
        BeamConfig {
            beams: self.beams.clone(),
            refinement: self.refinement.clone(),
        }
    }
}

/// The `adaptive-beams` method (an instance is a [`BeamMethod`]).
pub struct AdaptiveBeams;

impl Method for AdaptiveBeams {
    type Params = AdaptiveBeamsParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str = "hierarchical projected grid refined by a split oracle, tight beam hulls, surface and volume caustics";
    const SOURCE: &'static str = "Liktor & Dachsbacher 2011, Real-Time Volume Caustics with Adaptive Beam Tracing (liktor-dachsbacher-2011-adaptive-beam-tracing.txt)";
    const CAPABILITIES: Capabilities = CAPABILITIES;
    const COUNTERS: &'static [CounterDoc] = beams::COUNTER_DOCS;

    fn check_scene(scene: &Scene, _: &AdaptiveBeamsParams) -> Result<(), Unsupported> {
        beams::check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &AdaptiveBeamsParams,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        Ok(Box::new(BeamMethod::new(
            ctx,
            renderer,
            &params.config(),
            NAME,
        )?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_method::params::parse;

    #[test]
    fn defaults_are_the_papers() {
        let c = AdaptiveBeamsParams::default().config();
        assert_eq!(
            (c.beams.grid, c.refinement.levels, c.beams.hull),
            (16, 3, HullKind::Tight)
        );
        c.check().expect("defaults are valid");
    }

    #[test]
    fn a_budget_past_the_beam_buffers_is_refused_by_name() {
        let mut p = AdaptiveBeamsParams::default();
        p.refinement.beam_budget = p.beams.max_beams + 1;
        let e = p
            .config()
            .check()
            .expect_err("the budget must fit max_beams");
        assert!(e.contains("beam_budget") && e.contains("max_beams"), "{e}");
    }

    #[test]
    fn bad_params_name_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"levels": 5}), "levels"),
            (serde_json::json!({"grid": 0}), "grid"),
            (
                serde_json::json!({"hull": "sphere"}),
                "hull: expected one of: prism, tight",
            ),
            (serde_json::json!({"max_beams": 100}), "max_beams"),
            (
                serde_json::json!({"orphan_kernel_px": 1.0}),
                "orphan_kernel_px: 1 spreads the orphans' points, which only splat_orphans = true draws",
            ),
            (
                serde_json::json!({"orphan_kernel_px": 9.0, "splat_orphans": true}),
                "orphan_kernel_px",
            ),
            (
                serde_json::json!({"split_camera_px": -1.0}),
                "split_camera_px",
            ),
            (
                serde_json::json!({"split_energy_threshold": 1e12}),
                "split_energy_threshold",
            ),
            (
                serde_json::json!({"surface_filter_px": 100.0}),
                "surface_filter_px",
            ),
            (serde_json::json!({"max_focus": 0.0}), "max_focus"),
            (serde_json::json!({"split_hit_rel": 1.5}), "split_hit_rel"),
            (serde_json::json!({"split_hit_rel": -0.1}), "split_hit_rel"),
            (serde_json::json!({"beam_budget": -1}), "beam_budget"),
            (serde_json::json!({"beam_budget": 1e9}), "beam_budget"),
            (
                serde_json::json!({"split_normal_deg": "30"}),
                "split_normal_deg",
            ),
            (serde_json::json!({"levls": 2}), "known parameters"),
        ] {
            let msg = parse::<AdaptiveBeamsParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{json}: {msg}");
        }
    }
}
