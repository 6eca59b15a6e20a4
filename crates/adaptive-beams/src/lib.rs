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
//! parameters and defaults (the paper's: 16² base grid, 3 levels, tight hulls).

use beams::{BeamConfig, BeamMethod, CAPABILITIES, HullKind, SHARED_PARAM_DOCS};
use caustics_gpu::{GpuContext, Renderer};
use caustics_method::{
    CausticsMethod, MethodError, MethodInfo, Unsupported, param_specs, parse_params,
};
use caustics_scene::Scene;
use serde::{Deserialize, Serialize};

/// Registry name.
pub const NAME: &str = "adaptive-beams";

/// Parameters of `adaptive-beams` (defaults: the paper's Sect. 8 settings).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct AdaptiveBeamsParams {
    /// Cells per side of the base grid.
    pub grid: u32,
    /// Refinement levels, 0..=4.
    pub levels: u32,
    /// `tight` or `prism`.
    pub hull: HullKind,
    /// Split at surface discontinuities (silhouettes, normal and depth changes).
    pub split_discontinuity: bool,
    /// Normal difference between corners that splits (degrees).
    pub split_normal_deg: f64,
    /// Depth slope between corners that splits (|Δdepth| / lateral distance).
    pub split_depth_slope: f64,
    /// Photon-hit difference at edge midpoints that splits (camera pixels).
    pub split_hit_px: f64,
    /// Split beams by energy (flux share × focus).
    pub split_energy: bool,
    /// Flux share × focus above which a beam splits.
    pub split_energy_threshold: f64,
    /// Split beams that look large from the camera.
    pub split_camera: bool,
    /// Projected size (pixels) above which a beam splits.
    pub split_camera_px: f64,
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

impl Default for AdaptiveBeamsParams {
    fn default() -> Self {
        Self {
            grid: 16,
            levels: 3,
            hull: HullKind::Tight,
            split_discontinuity: true,
            split_normal_deg: 30.0,
            split_depth_slope: 4.0,
            split_hit_px: 1.0,
            split_energy: true,
            split_energy_threshold: 2.0,
            split_camera: true,
            split_camera_px: 16.0,
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

impl AdaptiveBeamsParams {
    /// The pipeline configuration.
    pub fn config(&self) -> BeamConfig {
        BeamConfig {
            grid: self.grid,
            levels: self.levels,
            hull: self.hull,
            light_resolution: self.light_resolution,
            impostor_resolution: self.impostor_resolution,
            max_beams: self.max_beams,
            split_discontinuity: self.split_discontinuity,
            split_normal_deg: self.split_normal_deg,
            split_depth_slope: self.split_depth_slope,
            split_hit_px: self.split_hit_px,
            split_energy: self.split_energy,
            split_energy_threshold: self.split_energy_threshold,
            split_camera: self.split_camera,
            split_camera_px: self.split_camera_px,
            reflections: self.reflections,
            surface_filter_px: self.surface_filter_px,
            soft_depth_m: self.soft_depth_m,
            max_focus: self.max_focus,
        }
    }
}

fn parse(params: &serde_json::Value) -> Result<BeamConfig, MethodError> {
    let config = parse_params::<AdaptiveBeamsParams>(NAME, params)?.config();
    config.validate(NAME)?;
    Ok(config)
}

/// The registry entry.
pub fn info() -> MethodInfo {
    MethodInfo {
        name: NAME,
        summary: "hierarchical projected grid refined by a split oracle, tight beam hulls, surface and volume caustics",
        source: "Liktor & Dachsbacher 2011, Real-Time Volume Caustics with Adaptive Beam Tracing (liktor-dachsbacher-2011-adaptive-beam-tracing.txt)",
        capabilities: CAPABILITIES,
        params: || {
            let mut docs = SHARED_PARAM_DOCS.to_vec();
            docs.extend_from_slice(&[
                ("levels", "refinement levels of the projected grid (0..=4)"),
                ("split_discontinuity", "split at silhouettes and surface discontinuities (Sect. 4.2)"),
                ("split_normal_deg", "corner normals differing by more than this split (degrees)"),
                ("split_depth_slope", "corner depths changing faster than this (|Δdepth|/lateral) split"),
                ("split_hit_px", "edge-midpoint photon hits off the linear prediction by more than this (camera px) split (Sect. 6)"),
                ("split_energy", "split beams that carry much light or focus it (Sect. 4.2)"),
                ("split_energy_threshold", "split while flux share x A(0)/min A(y) exceeds this"),
                ("split_camera", "split beams that look large from the camera (Sect. 4.2)"),
                ("split_camera_px", "split while the beam base spans more than this many pixels"),
            ]);
            param_specs::<AdaptiveBeamsParams>(&docs)
        },
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
    fn defaults_are_the_papers() {
        let c = AdaptiveBeamsParams::default().config();
        assert_eq!((c.grid, c.levels, c.hull), (16, 3, HullKind::Tight));
        c.validate(NAME).expect("defaults are valid");
    }

    #[test]
    fn bad_params_name_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"levels": 5}), "levels"),
            (serde_json::json!({"grid": 0}), "grid"),
            (serde_json::json!({"hull": "sphere"}), "unknown variant"),
            (serde_json::json!({"max_beams": 100}), "max_beams"),
            (
                serde_json::json!({"split_camera_px": -1.0}),
                "split_camera_px",
            ),
            (
                serde_json::json!({"surface_filter_px": 100.0}),
                "surface_filter_px",
            ),
            (serde_json::json!({"levls": 2}), "known parameters"),
        ] {
            let msg = parse(&json).expect_err("must fail").to_string();
            assert!(msg.contains(needle), "{json}: {msg}");
        }
    }
}
