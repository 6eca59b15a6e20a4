//! `static-grid`: caustic beams from a regular projected grid (Liktor & Dachsbacher
//! 2010; the left half of Fig. 4 in their 2011 paper), the baseline of
//! `adaptive-beams`: the same pipeline (crate `beams`) with a fixed 64×64 grid, no
//! refinement, and Ernst et al.'s bounding prisms by default.

use beams::{BeamConfig, BeamMethod, CAPABILITIES, HullKind, SHARED_PARAM_DOCS};
use caustics_gpu::{GpuContext, Renderer};
use caustics_method::{
    CausticsMethod, MethodError, MethodInfo, Unsupported, param_specs, parse_params,
};
use caustics_scene::Scene;
use serde::{Deserialize, Serialize};

/// Registry name.
pub const NAME: &str = "static-grid";

/// Parameters of `static-grid` (default grid: the paper's 64² comparison).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct StaticGridParams {
    /// Cells per side of the grid.
    pub grid: u32,
    /// `prism` or `tight`.
    pub hull: HullKind,
    /// Light G-buffer resolution.
    pub light_resolution: u32,
    /// Distance impostor resolution.
    pub impostor_resolution: u32,
    /// Beam buffer capacity.
    pub max_beams: u32,
    /// Fresnel-reflected beams of dielectrics.
    pub reflections: bool,
    /// Low-pass sigma on surface caustics (px).
    pub surface_filter_px: f64,
    /// Soft-particle fade (m).
    pub soft_depth_m: f64,
    /// Clamp of the focus A(0)/A(y).
    pub max_focus: f64,
}

impl Default for StaticGridParams {
    fn default() -> Self {
        Self {
            grid: 64,
            hull: HullKind::Prism,
            light_resolution: 1024,
            impostor_resolution: 256,
            max_beams: 1 << 16,
            reflections: true,
            surface_filter_px: 1.0,
            soft_depth_m: 0.0,
            max_focus: 1000.0,
        }
    }
}

impl StaticGridParams {
    /// The pipeline configuration: no refinement, so no split criteria.
    pub fn config(&self) -> BeamConfig {
        BeamConfig {
            grid: self.grid,
            levels: 0,
            hull: self.hull,
            light_resolution: self.light_resolution,
            impostor_resolution: self.impostor_resolution,
            max_beams: self.max_beams,
            split_discontinuity: false,
            split_normal_deg: 180.0,
            split_depth_slope: 1e6,
            split_hit_px: 1e6,
            split_energy: false,
            split_energy_threshold: 1e12,
            split_camera: false,
            split_camera_px: 1e6,
            reflections: self.reflections,
            surface_filter_px: self.surface_filter_px,
            soft_depth_m: self.soft_depth_m,
            max_focus: self.max_focus,
        }
    }
}

fn parse(params: &serde_json::Value) -> Result<BeamConfig, MethodError> {
    let config = parse_params::<StaticGridParams>(NAME, params)?.config();
    config.validate(NAME)?;
    Ok(config)
}

/// The registry entry.
pub fn info() -> MethodInfo {
    MethodInfo {
        name: NAME,
        summary: "beams from a regular projected grid (no refinement), bounding prisms",
        source: "Liktor & Dachsbacher 2010, as the static grids of Fig. 4 in liktor-dachsbacher-2011-adaptive-beam-tracing.txt",
        capabilities: CAPABILITIES,
        params: || param_specs::<StaticGridParams>(SHARED_PARAM_DOCS),
        validate_params: |v| parse(v).map(|_| ()),
        check_scene: |scene: &Scene, _| -> Result<(), Unsupported> { beams::check_scene(scene) },
        create,
    }
}

fn create(
    ctx: &GpuContext,
    renderer: &Renderer,
    params: &serde_json::Value,
) -> Result<Box<dyn CausticsMethod>, MethodError> {
    let config = parse(params)?;
    Ok(Box::new(BeamMethod::new(ctx, renderer, &config, NAME)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_a_64_grid_with_prisms_and_no_refinement() {
        let c = StaticGridParams::default().config();
        assert_eq!((c.grid, c.levels, c.hull), (64, 0, HullKind::Prism));
        c.validate(NAME).expect("defaults are valid");
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
        ] {
            let msg = parse(&json).expect_err("must fail").to_string();
            assert!(msg.contains(needle), "{json}: {msg}");
        }
    }
}
