//! `static-grid`: caustic beams from a regular projected grid (Liktor & Dachsbacher
//! 2010; the left half of Fig. 4 in their 2011 paper), the baseline of
//! `adaptive-beams`: the same pipeline (crate `beams`) with a fixed 64×64 grid, no
//! refinement, and Ernst et al.'s bounding prisms by default.

use beams::{BeamConfig, BeamMethod, BeamParams, CAPABILITIES, HullKind, Refinement};
use caustics_gpu::{GpuContext, Renderer};
use caustics_method::{Capabilities, CausticsMethod, CounterDoc, Method, MethodError, Unsupported};
use caustics_scene::Scene;

/// Registry name.
pub const NAME: &str = "static-grid";

caustics_method::method_params! {
    /// Parameters of `static-grid`: the shared beam settings only (no refinement).
    pub struct StaticGridParams {
        group
        /// The beam settings; default grid: the paper's 64² comparison, with prisms.
        beams: BeamParams = BeamParams { grid: 64, hull: HullKind::Prism, ..Default::default() };
    }
}

impl StaticGridParams {
    /// The pipeline configuration: no refinement, so no split criteria.
    pub fn config(&self) -> BeamConfig {
        BeamConfig {
            beams: self.beams.clone(),
            refinement: Refinement::none(),
        }
    }
}

/// The `static-grid` method (an instance is a [`BeamMethod`]).
pub struct StaticGrid;

impl Method for StaticGrid {
    type Params = StaticGridParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str =
        "beams from a regular projected grid (no refinement), bounding prisms";
    const SOURCE: &'static str = "Liktor & Dachsbacher 2010, as the static grids of Fig. 4 in liktor-dachsbacher-2011-adaptive-beam-tracing.txt";
    const CAPABILITIES: Capabilities = CAPABILITIES;
    const COUNTERS: &'static [CounterDoc] = beams::COUNTER_DOCS;

    fn check_scene(scene: &Scene, _: &StaticGridParams) -> Result<(), Unsupported> {
        beams::check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &StaticGridParams,
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
    fn defaults_are_a_64_grid_with_prisms_and_no_refinement() {
        let c = StaticGridParams::default().config();
        assert_eq!(
            (c.beams.grid, c.refinement.levels, c.beams.hull),
            (64, 0, HullKind::Prism)
        );
        c.check().expect("defaults are valid");
    }

    #[test]
    fn bad_params_name_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"grid": 1000}), "grid"),
            (serde_json::json!({"levels": 2}), "known parameters"),
            (
                serde_json::json!({"light_resolution": 8}),
                "light_resolution",
            ),
            (serde_json::json!({"max_beams": 8191}), "max_beams"),
            (serde_json::json!({"max_focus": 1e12}), "max_focus"),
        ] {
            let msg = parse::<StaticGridParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{json}: {msg}");
        }
    }
}
