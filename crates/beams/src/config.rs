//! The configuration of the beam pipeline, shared by `static-grid` and
//! `adaptive-beams` (each method crate exposes its own parameters and defaults).

use caustics_method::MethodError;
use serde::{Deserialize, Serialize};

/// Bounding volume rasterized per beam (Sect. 4.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HullKind {
    /// Ernst et al. (2005): three touching planes through the base edges.
    Prism,
    /// Liktor & Dachsbacher (2011): six triangles, each edge of the base and top
    /// triangles with one vertex of the other (the convex hull of the two), falling
    /// back to the prism where a choice is not unique.
    Tight,
}

/// Everything the beam pipeline needs beyond the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamConfig {
    /// Cells per side of the base projected grid (two beam triangles per cell).
    pub grid: u32,
    /// Refinement levels (0: a static grid).
    pub levels: u32,
    /// Hull rasterized per beam.
    pub hull: HullKind,
    /// Light G-buffer resolution (texels per side).
    pub light_resolution: u32,
    /// Distance-impostor resolution (texels per cube face side).
    pub impostor_resolution: u32,
    /// Capacity of the candidate and beam buffers; more is counted as overflow.
    pub max_beams: u32,
    /// Split oracle, discontinuity criterion: split where corner normals differ by
    /// more than `split_normal_deg` or depth changes faster than `split_depth_slope`
    /// (|Δdepth| / lateral distance), and at silhouettes.
    pub split_discontinuity: bool,
    /// Degrees.
    pub split_normal_deg: f64,
    /// Dimensionless slope.
    pub split_depth_slope: f64,
    /// Photon-hit difference that splits: where an edge midpoint's light lands
    /// against the linear prediction from the corners, in camera pixels (Sect. 6).
    pub split_hit_px: f64,
    /// Split oracle, energy criterion: split while (flux share of the beam relative to
    /// a base-grid beam) × (A(0) / min A(y)) exceeds `split_energy_threshold`.
    pub split_energy: bool,
    /// Dimensionless.
    pub split_energy_threshold: f64,
    /// Split oracle, camera criterion: split while the beam's base, seen from the
    /// camera at its central ray's closest point, spans more than `split_camera_px`.
    pub split_camera: bool,
    /// Pixels.
    pub split_camera_px: f64,
    /// Also trace the Fresnel-reflected beams of dielectrics (Sect. 6).
    pub reflections: bool,
    /// Sigma (pixels) of the low-pass filter on the surface caustic (Sect. 7); 0 = off.
    pub surface_filter_px: f64,
    /// Soft-particle fade distance of volume caustics near surfaces (m); 0 = off.
    pub soft_depth_m: f64,
    /// A(y) is clamped to at least A(0)/max_focus.
    pub max_focus: f64,
}

impl BeamConfig {
    /// Range checks, with errors naming the parameter.
    pub fn validate(&self, method: &'static str) -> Result<(), MethodError> {
        let err = |message: String| Err(MethodError::Param { method, message });
        if !(1..=256).contains(&self.grid) {
            return err(format!(
                "grid: expected an integer in 1..=256, got {}",
                self.grid
            ));
        }
        if self.levels > 4 {
            return err(format!(
                "levels: expected an integer in 0..=4, got {}",
                self.levels
            ));
        }
        if !(16..=4096).contains(&self.light_resolution) {
            return err(format!(
                "light_resolution: expected an integer in 16..=4096, got {}",
                self.light_resolution
            ));
        }
        if !(16..=2048).contains(&self.impostor_resolution) {
            return err(format!(
                "impostor_resolution: expected an integer in 16..=2048, got {}",
                self.impostor_resolution
            ));
        }
        let base = 2 * self.grid * self.grid;
        if self.max_beams < 1 || self.max_beams > (1 << 22) {
            return err(format!(
                "max_beams: expected an integer in 1..={}, got {}",
                1 << 22,
                self.max_beams
            ));
        }
        if self.max_beams < base {
            return err(format!(
                "max_beams: {} cannot hold the {base} triangles of a {g}x{g} base grid",
                self.max_beams,
                g = self.grid
            ));
        }
        let positive = [
            ("split_normal_deg", self.split_normal_deg, 180.0),
            ("split_depth_slope", self.split_depth_slope, 1e6),
            ("split_hit_px", self.split_hit_px, 1e6),
            ("split_energy_threshold", self.split_energy_threshold, 1e12),
            ("split_camera_px", self.split_camera_px, 1e6),
            ("max_focus", self.max_focus, 1e12),
        ];
        for (name, v, max) in positive {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return err(format!("{name}: expected a number in (0, {max}], got {v}"));
            }
        }
        for (name, v) in [
            ("surface_filter_px", self.surface_filter_px),
            ("soft_depth_m", self.soft_depth_m),
        ] {
            if !(v.is_finite() && (0.0..=64.0).contains(&v)) {
                return err(format!("{name}: expected a number in [0, 64], got {v}"));
            }
        }
        Ok(())
    }
}

/// Docs of the parameters both beam methods share, for `caustics list`.
pub const SHARED_PARAM_DOCS: &[(&str, &str)] = &[
    (
        "grid",
        "cells per side of the projected grid in the light's view (2 beam triangles per cell)",
    ),
    (
        "hull",
        "beam volume rasterized: prism (Ernst et al. 2005) or tight (6 triangles, Sect. 4.3)",
    ),
    (
        "light_resolution",
        "light G-buffer resolution (texels per side)",
    ),
    (
        "impostor_resolution",
        "distance impostor resolution (texels per cube-face side)",
    ),
    (
        "max_beams",
        "capacity of the beam and candidate buffers; excess is counted as overflow and warned about",
    ),
    (
        "reflections",
        "also trace the Fresnel-reflected beams of dielectrics",
    ),
    (
        "surface_filter_px",
        "sigma (px) of the low-pass filter on the surface caustic (Sect. 7), 0 = off",
    ),
    (
        "soft_depth_m",
        "soft-particle fade of volume caustics near surfaces (m), 0 = off (segments are clipped exactly)",
    ),
    (
        "max_focus",
        "A(y) is clamped to >= A(0)/max_focus (a point-sampled focus is singular)",
    ),
];
