//! The parameters of the beam pipeline, declared once: [`BeamParams`], the group both
//! `static-grid` and `adaptive-beams` compose (each with its own defaults), and
//! [`Refinement`], the split oracle that only `adaptive-beams` exposes. The pipeline
//! takes both as one [`BeamConfig`].

use caustics_method::method_params;
pub use caustics_method::params::Raster;
pub use caustics_method::params::Tracer;
use caustics_method::params::{above, closed};
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

caustics_method::param_enum!(HullKind, [HullKind::Prism, HullKind::Tight]);

/// Most refinement levels (the control buffer counts beams of levels 0..=4).
pub const MAX_LEVELS: u32 = 4;

/// Most further specular events [`BeamParams::bounces`] allows: the photon-hit methods'
/// bound, so one experiment sets every method alike. Each internal reflection is a
/// beam family of its own (one bit of a leaf's action word, one control counter, and
/// three more corner paths traced per leaf in `decide` and `emit_beams`).
pub const MAX_BOUNCES: u32 = 8;

method_params! {
    /// The settings both beam methods share, a parameter group of each (the defaults
    /// here are `static-grid`'s; `adaptive-beams` states its own grid and hull).
    pub struct BeamParams {
        /// cells per side of the projected grid in the light's view (2 beam triangles per cell)
        grid: u32 = 64 => closed(1.0, 256.0);
        /// beam volume rasterized: prism (Ernst et al. 2005) or tight (6 triangles, Sect. 4.3)
        hull: HullKind = HullKind::Prism;
        /// light G-buffer resolution (texels per side)
        light_resolution: u32 = 1024 => closed(16.0, 4096.0);
        /// distance impostor resolution (texels per cube-face side)
        impostor_resolution: u32 = 256 => closed(16.0, 2048.0);
        /// capacity of the beam and candidate buffers; excess is counted as overflow and warned about (bound: 4,194,240 = 65,535 x 64, the candidates and the beams are dispatched 64 to a workgroup and a dispatch of more than 65,535 workgroups a side is dropped whole; 1.1 GB of beams)
        max_beams: u32 = 1 << 16 => closed(1.0, 4194240.0);
        /// also trace the Fresnel-reflected beams of dielectrics
        reflections: bool = true;
        /// further specular events beyond the paper's path (two refractions, Sect. 6): internal reflections in a closed refractor (Fresnel and total; each count a beam family of its own), total internal reflection elsewhere, a generator met again (a ring's opposite wall, a concave mesh) (paper: 0; bound: one beam family and counter per internal reflection, each traced for every leaf)
        bounces: u32 = 0 => closed(0.0, MAX_BOUNCES as f64);
        /// how corner paths find their surfaces: impostor (distance impostors, the paper's Sect. 6) or bvh (exact: the scene's triangle BVH and analytic shapes, with the adjoint shading-normal factor; the light G-buffer and impostors are then not rendered)
        tracer: Tracer = Tracer::Impostor;
        /// also splat the light of the families a leaf drops (its corners part ways: a silhouette, different paths or receivers): each landed corner as a one-pixel point of a third of the triangle's flux, on the surface caustic (paper: false, that light is lost; bound: max_beams point records)
        splat_orphans: bool = false;
        /// emit the light of the families a leaf drops (its corners part ways) as clipped beams: each group of corners on one path keeps the part of the triangle around it, bounded on the edges to the other corners by the last point of its path that 6 bisections find (2 beams for a pair of corners, 1 for a corner alone; a leaf whose corners agree but whose exit points admit no beam space is one), and a clipped beam with no beam space at its exit points starts where its rays cross the plane across their mean direction, so silhouettes and folds keep their light in beams rather than losing it (paper: false, Sect. 4.1 omits triangles crossing silhouettes; bound: up to 3 beams per leaf and family, each clipped edge traced 6 more times; not with splat_orphans, which draws that light as points)
        clip_leaves: bool = false;
        /// with splat_orphans: sigma (camera pixels) of a Gaussian each orphan point is spread over instead of one pixel, before the surface filter (truncated at 2 sigma, normalised over the pixels it covers, so a flat receiver keeps its flux); 0 = one-pixel points (paper: no orphans; bound: a 33 x 33 pixel quad per point)
        orphan_kernel_px: f64 = 0.0 => closed(0.0, 8.0);
        /// how the hulls reach the image: hardware (rasterized, additively blended: the paper's) or compute (the workgroups of a beam shade the pixels of its clipped hull's projected polygon with the same per-pixel function and add the light into a fixed-point accumulator with integer atomics, then a full-screen pass resolves it: the same image on every run; bound: 48 bytes of accumulator per camera pixel)
        raster: Raster = Raster::Hardware;
        /// trace each vertex of the projected grid's main light path once per frame, into a cache that the split oracle and the beams read (the paper's geometry shader traces it again for every triangle that has it as a corner, as an edge midpoint the oracle tests and when its beam is written), and with reflections on a scene with a dielectric each corner's Fresnel reflection too (every leaf asks for it at its three corners); the same beams bit for bit (through the BVH on a mesh, the same WGSL compiled into another kernel may round a path's last bits differently: bumpy_glass, 8 bounces, 24,883 orphans against 24,877, the same beams), the time differs (bound: (grid x 2^levels + 1)^2 entries of 128 bytes per cached family; past 64 MiB the reflection is left out, then the cache)
        vertex_cache: bool = true;
        /// sigma (px) of the low-pass filter on the surface caustic (Sect. 7), 0 = off (bound: a (4 sigma + 1)^2 gather per pixel)
        surface_filter_px: f64 = 1.0 => closed(0.0, 16.0);
        /// soft-particle fade of volume caustics near surfaces (m), 0 = off (segments are clipped exactly; bound: longer than any scene)
        soft_depth_m: f64 = 0.0 => closed(0.0, 64.0);
        /// interpolate each beam's irradiance across it from its corners' (after Ernst et al. 2005's smooth interpolation, which Sect. 7 names): a corner's is the flux over the landing area of the beams of its light-path family that share its grid vertex, as a factor on the beam's own clamped by vertex_irradiance_max; off (the paper's): one area function per beam, so the irradiance steps at beam edges, which surface_filter_px blurs (bound: 36 bytes per vertex of the vertex cache's lattice and family, which it needs)
        vertex_irradiance: bool = false;
        /// with vertex_irradiance: a corner's irradiance is kept within this factor of its beam's own (where the beams around a vertex differ more, a focus or a fold lies between them and a mean would move light across it; 1 = the beam's own; bound: a millionfold)
        vertex_irradiance_max: f64 = 1.5 => closed(1.0, 1e6);
        /// A(y) is clamped to >= A(0)/max_focus (a point-sampled focus is singular; 1 = no focusing; bound: a millionfold concentration)
        max_focus: f64 = 1000.0 => closed(1.0, 1e6);
    }
    check = beam_params_agree;
}

/// The rules between parameters: the beam buffers must hold the 2·grid² triangles of
/// the base grid (refinement only adds to them), and a kernel for the orphans' points
/// needs the points.
fn beam_params_agree(p: &BeamParams) -> Result<(), String> {
    caustics_method::params::orphan_kernel_needs_orphans(p.orphan_kernel_px, p.splat_orphans)?;
    if p.clip_leaves && p.splat_orphans {
        return Err("clip_leaves: the light of torn leaves is either clipped into beams or drawn as points (splat_orphans), not both; set one of them to false".into());
    }
    let base = 2 * u64::from(p.grid).pow(2);
    if u64::from(p.max_beams) < base {
        return Err(format!(
            "max_beams: {} cannot hold the {base} triangles of a {g}x{g} base grid",
            p.max_beams,
            g = p.grid
        ));
    }
    Ok(())
}

method_params! {
    /// Refinement of the projected grid by the split oracle (Sect. 4.2): the parameters
    /// of `adaptive-beams` beyond [`BeamParams`]. The levels are the paper's (Sect. 8:
    /// three steps on a 16² grid); its oracle is "an empirically set-up heuristic" with
    /// no numbers given, so the thresholds ask for every split that misplaces a pixel
    /// of light and the beam budget, Table 1's largest count (5,300 at 1024×768), picks
    /// among them by priority (`bench/experiments/liktor-table1.json`).
    pub struct Refinement {
        /// refinement levels of the projected grid (bound: the counters of levels 0..=4)
        levels: u32 = 3 => closed(0.0, MAX_LEVELS as f64);
        /// split at silhouettes and surface discontinuities (Sect. 4.2)
        split_discontinuity: bool = true;
        /// also split where a light-path family beyond the main path (the Fresnel reflection, the internal reflections of bounces) parts ways at the corners while the main path does not, ranked by that family's light (paper: false, its oracle looks at the main path, and such a leaf loses that light or, with splat_orphans, draws it as three points of a third of its flux: bright dots where the leaf is coarse)
        split_families: bool = false;
        /// corner normals differing by more than this split (degrees)
        split_normal_deg: f64 = 30.0 => above(0.0, 180.0);
        /// corner depths changing faster than this (|Δdepth|/lateral) split (bound: a slope of 1e3 is 89.94°)
        split_depth_slope: f64 = 4.0 => above(0.0, 1e3);
        /// edge-midpoint photon hits off the linear prediction by more than this (camera px) split (Sect. 6; bound: an image side)
        split_hit_px: f64 = 1.0 => above(0.0, 16384.0);
        /// edge-midpoint photon hits split only when also off by more than this fraction of the edge's landing length (a beam spreads its flux evenly, while the true irradiance varies across it by about 8x this fraction); 0 = the pixel bound alone (the default: the beam budget keeps the count; bound: the whole edge)
        split_hit_rel: f64 = 0.0 => closed(0.0, 1.0);
        /// split where the leaf's even irradiance is off from its four children's (their landing areas, from the corners and the edge midpoints the hit test traces) by more than split_hit_px pixels' worth of light, ranked alike (the paper's energy criterion, "convergent beams ... are refined with higher priority", Sect. 4.2, measured as the error it causes; paper: its oracle gives no formula)
        split_irradiance: bool = true;
        /// split beams that carry much light or focus it (Sect. 4.2)
        split_energy: bool = true;
        /// split while the beam's flux relative to an unrefined beam's (path throughput x 4^-level) times A(0)/A(where seen) exceeds this (the receiver; the narrowest point in a medium; bound: relative flux <= 1 times the largest max_focus)
        split_energy_threshold: f64 = 2.0 => above(0.0, 1e6);
        /// split beams that look large from the camera (Sect. 4.2)
        split_camera: bool = true;
        /// split while the beam base spans more than this many pixels where its central ray passes closest to the eye (bound: an image side)
        split_camera_px: f64 = 16.0 => above(0.0, 16384.0);
        /// beams to aim for, counted over the paper's families, the main path and the Fresnel reflection (Table 1's largest count at 1024x768; the internal reflections of `bounces` come on top, one family per leaf the budget buys): each level, coarse first, takes the splits the oracle asks for by priority (pixels of misplaced light; a triangle whose light would be dropped first) while they fit the beams left, four children per beam at stake (the paper's "convergent beams ... are refined with higher priority", Sect. 4.2); a target, not a bound (children may emit more than estimated); 0 = every split asked (bound: max_beams)
        beam_budget: u32 = 5300 => closed(0.0, 4194240.0);
    }
}

impl Refinement {
    /// No refinement: the static grid (level 0 only, so the oracle is never asked).
    pub fn none() -> Self {
        Self {
            levels: 0,
            split_discontinuity: false,
            split_energy: false,
            split_camera: false,
            split_irradiance: false,
            beam_budget: 0,
            ..Self::default()
        }
    }

    /// The enabled criteria as `split_flags` of `BeamUniforms` (types.wgsl): 1
    /// discontinuity, 2 energy, 4 camera, 16 irradiance (generate.wgsl `SPLIT_*`; 8 is
    /// the reason `split_families` gives, a pipeline constant of generate.wgsl instead).
    pub fn flags(&self) -> u32 {
        (self.split_discontinuity as u32)
            | ((self.split_energy as u32) << 1)
            | ((self.split_camera as u32) << 2)
            | ((self.split_irradiance as u32) << 4)
    }
}

/// Everything the beam pipeline needs beyond the scene: the shared settings and the
/// refinement ([`Refinement::none`] for a static grid).
#[derive(Clone, Debug, PartialEq)]
pub struct BeamConfig {
    /// The shared settings.
    pub beams: BeamParams,
    /// The split oracle.
    pub refinement: Refinement,
}

impl BeamConfig {
    /// Every range and rule, the error naming the parameter.
    pub fn check(&self) -> Result<(), String> {
        use caustics_method::MethodParams;
        self.beams.check()?;
        self.refinement.check()?;
        if self.refinement.beam_budget > self.beams.max_beams {
            return Err(format!(
                "beam_budget: {} beams do not fit the beam buffers (max_beams {}); raise max_beams or lower the budget",
                self.refinement.beam_budget, self.beams.max_beams
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_method::MethodParams;

    #[test]
    fn the_base_grid_must_fit_the_beam_buffers() {
        let p = BeamParams {
            grid: 16,
            max_beams: 511,
            ..BeamParams::default()
        };
        let e = p.check().expect_err("511 < 2·16²");
        assert!(e.contains("max_beams") && e.contains("512"), "{e}");
        assert!(
            BeamParams {
                max_beams: 512,
                ..p
            }
            .check()
            .is_ok()
        );
    }

    #[test]
    fn bounces_default_to_the_papers_path_and_are_bounded() {
        assert_eq!(BeamParams::default().bounces, 0);
        let p = BeamParams {
            bounces: MAX_BOUNCES + 1,
            ..BeamParams::default()
        };
        let e = p.check().expect_err("one family and counter per bounce");
        assert!(e.contains("bounces"), "{e}");
        assert!(
            BeamParams {
                bounces: MAX_BOUNCES,
                ..p
            }
            .check()
            .is_ok()
        );
    }

    /// Candidates and beams are dispatched 64 to a workgroup, and wgpu drops an indirect
    /// dispatch of more than 65,535 workgroups a side whole (a no-op, no error): the
    /// buffers hold no more than that many.
    #[test]
    fn max_beams_fits_one_dispatch_of_64_wide_workgroups() {
        let fits = BeamParams {
            max_beams: 65_535 * 64,
            ..BeamParams::default()
        };
        fits.check().expect("65,535 workgroups of 64");
        let e = BeamParams {
            max_beams: 65_535 * 64 + 1,
            ..fits
        }
        .check()
        .expect_err("65,536 workgroups");
        assert!(e.contains("max_beams"), "{e}");
    }

    #[test]
    fn torn_light_is_clipped_or_splatted_not_both() {
        let p = BeamParams {
            clip_leaves: true,
            splat_orphans: true,
            ..BeamParams::default()
        };
        let e = p.check().expect_err("the same light twice");
        assert!(
            e.contains("clip_leaves") && e.contains("splat_orphans"),
            "{e}"
        );
        assert!(BeamParams::default().check().is_ok());
        assert!(
            !BeamParams::default().clip_leaves,
            "the paper omits torn triangles"
        );
        assert!(
            BeamParams {
                splat_orphans: false,
                ..p
            }
            .check()
            .is_ok()
        );
    }

    #[test]
    fn no_refinement_is_a_valid_configuration() {
        let c = BeamConfig {
            beams: BeamParams::default(),
            refinement: Refinement::none(),
        };
        c.check().expect("valid");
        assert_eq!((c.refinement.levels, c.refinement.flags()), (0, 0));
        assert_eq!(Refinement::default().flags(), 23);
    }
}
