//! What crosses to the GPU: the `#[repr(C)]` mirrors of types.wgsl and filter.wgsl
//! (each checked field by field against naga's layout in the tests below), the
//! caustic generators' slots, and how the uniforms are filled from the scene.

use bytemuck::{Pod, Zeroable};
use caustics_gpu::impostor::ImpostorAtlas;
use caustics_gpu::scene_upload::material_kind;
use caustics_gpu::{GpuScene, LightView};
use caustics_scene::{Light, Material, Scene, Shape, Vec3};

use crate::{BeamConfig, HullKind, MAX_SPECULAR, Tracer};

/// Bytes of one `Candidate` (types.wgsl).
pub(crate) const CANDIDATE_BYTES: u64 = 32;
/// Bytes of one `Beam`.
pub(crate) const BEAM_BYTES: u64 = std::mem::size_of::<BeamRecord>() as u64;
/// Bytes of one `Orphan` (types.wgsl): three corners' points, directions and flux
/// shares, and their receivers.
pub(crate) const ORPHAN_BYTES: u64 = 160;

/// Bytes of one `CachedPath` (generate.wgsl): a vertex's main light path in the vertex
/// cache.
pub(crate) const VERTEX_PATH_BYTES: u64 = 128;

/// Mirrors `SpecularSlot` in types.wgsl: one caustic generator.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(crate) struct SpecularSlot {
    center_reach: [f32; 4],
    color: [f32; 4],
    object: u32,
    kind: u32,
    closed: u32,
    ior: f32,
}

/// Mirrors `BeamUniforms` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct BeamUniforms {
    light_inv_view_proj: [[f32; 4]; 4],
    light_dir_kind: [f32; 4],
    light_pos_start: [f32; 4],
    light_power: [f32; 4],
    sigma_t: [f32; 4],
    sigma_s_g: [f32; 4],
    receivers: [f32; 4],
    specular: [SpecularSlot; MAX_SPECULAR],
    specular_count: u32,
    grid: u32,
    levels: u32,
    max_beams: u32,
    split_flags: u32,
    split_cos_normal: f32,
    split_depth_slope: f32,
    split_energy: f32,
    split_camera_px: f32,
    pixel_angle: f32,
    reflections: u32,
    tight_hulls: u32,
    max_focus: f32,
    soft_depth: f32,
    impostor_tolerance: f32,
    scene_reach: f32,
    split_hit_px: f32,
    bounces: u32,
    exact_trace: u32,
    split_hit_rel: f32,
    beam_budget: u32,
    splat_orphans: u32,
    light_index: u32,
    vertex_cache_side: u32,
}

/// Mirrors `FilterUniforms` in filter.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct FilterUniforms {
    sigma_px: f32,
    radius_px: i32,
    _pad: [u32; 2],
}

impl FilterUniforms {
    /// A Gaussian of `sigma_px` cut at 2σ; 0 = off (the raw surface caustic is copied).
    pub(crate) fn new(sigma_px: f64) -> Self {
        let sigma = sigma_px as f32;
        Self {
            sigma_px: sigma.max(1e-3),
            radius_px: if sigma > 0.0 {
                (2.0 * sigma).ceil() as i32
            } else {
                0
            },
            _pad: [0; 2],
        }
    }
}

/// One beam as stored on the GPU (mirrors `Beam` in types.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BeamRecord {
    /// xyz: base vertex v_i; w: coefficient a_i of A(y) = a0 + a1·y + a2·y².
    pub v: [[f32; 4]; 3],
    /// xyz: edge direction scaled to unit height; w: height where edge i meets a receiver.
    pub d: [[f32; 4]; 3],
    /// rgb: flux (W) if every ray carried vertex i's weight; w of `flux[0]`: the
    /// light-path family (0 main, 1 Fresnel reflection, 1 + j: j internal reflections),
    /// of `flux[1]`: generators met again, of `flux[2]`: total internal reflections
    /// (both summed over the three corner paths).
    pub flux: [[f32; 4]; 3],
    /// xyz: unit base normal; w: extrusion height y_max.
    pub n: [f32; 4],
    /// Hull points: base 3, top 3.
    pub hull: [[f32; 4]; 6],
    /// 24 packed 4-bit hull indices; w: 1 tight, 0 prism.
    pub tris: [u32; 4],
}

impl BeamRecord {
    /// The beam's light-path family: 0 the main path, 1 the Fresnel reflection at the
    /// first interface, 1 + j the light reflected j times inside the first object.
    pub fn family(&self) -> u32 {
        self.flux[0][3] as u32
    }

    /// Further specular events on its corner paths (summed over the three): generators
    /// met again, and total internal reflections.
    pub fn further_events(&self) -> (u32, u32) {
        (self.flux[1][3] as u32, self.flux[2][3] as u32)
    }
}

/// One specular object's role in the pipeline.
pub(crate) struct Slot {
    /// Its object index.
    pub(crate) object: usize,
    uniform: SpecularSlot,
    /// Impostor centre; None = the centre of its bounds (closed objects).
    pub(crate) center: Option<Vec3>,
}

impl Slot {
    /// A dielectric: the Fresnel reflection off it is a beam family of its own.
    pub(crate) fn is_dielectric(&self) -> bool {
        self.uniform.kind == material_kind::DIELECTRIC
    }
}

/// The scene's caustic generators in object order.
pub(crate) fn slots(scene: &Scene, gpu_scene: &GpuScene) -> Vec<Slot> {
    let mut out = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (kind, ior, color) = match scene.material(o) {
            Material::Dielectric { ior } => (material_kind::DIELECTRIC, *ior, Vec3::ONE),
            Material::Mirror { reflectance } => (material_kind::MIRROR, 1.0, *reflectance),
            Material::Diffuse { .. } => continue,
        };
        let bounds = caustics_gpu::impostor::objects_bounds(gpu_scene, &[i]);
        let extent = bounds.map_or(1.0, |b| (b.max - b.min).max_element());
        // Closed generators are star-shaped around their centre; an open surface
        // (water, a mirror quad) is seen from a point behind it, a ring from its axis.
        let (closed, center) = match &o.shape {
            Shape::Sphere { .. } | Shape::Mesh(_) => (true, None),
            Shape::Heightfield(_) => (
                false,
                bounds.map(|b| b.center() - Vec3::Y * (0.5 * extent + 0.5 * (b.max.y - b.min.y))),
            ),
            Shape::Quad { normal, .. } => (
                false,
                bounds.map(|b| b.center() - normal.normalize() * (0.5 * extent)),
            ),
            Shape::Cylinder { .. } => (false, None),
        };
        out.push(Slot {
            object: i,
            uniform: SpecularSlot {
                center_reach: [0.0; 4],
                color: color.extend(1.0).to_array(),
                object: i as u32,
                kind,
                closed: closed as u32,
                ior,
            },
            center,
        });
    }
    out
}

impl BeamUniforms {
    /// The uniforms of `config` for the scene's light `light_index` and its `view`, the
    /// generators `slots` and their impostors in `atlas` (the slots in order, then
    /// the receivers), with the vertex cache's lattice of `vertex_cache_side` vertices a
    /// side (0: none).
    pub(crate) fn new(
        scene: &Scene,
        config: &BeamConfig,
        light_index: usize,
        view: &LightView,
        slots: &[Slot],
        atlas: &ImpostorAtlas,
        vertex_cache_side: u32,
    ) -> Self {
        let center_reach = |k: usize| {
            let e = &atlas.entries[k];
            e.center.extend(e.reach).to_array()
        };
        let mut specular = [SpecularSlot::default(); MAX_SPECULAR];
        for (k, s) in slots.iter().enumerate() {
            specular[k] = SpecularSlot {
                center_reach: center_reach(k),
                ..s.uniform
            };
        }
        let bounds = scene.bounds();
        let (light_dir_kind, light_pos_start, power) = match scene.lights[light_index] {
            Light::Directional {
                direction,
                irradiance,
            } => {
                let dir = direction.normalize();
                // Extinction is counted from the plane the reference starts its
                // directional photons on.
                let start = bounds.directional_start(dir);
                let side = view.texel_size * view.resolution as f32;
                (
                    dir.extend(0.0),
                    [0.0, 0.0, 0.0, start],
                    irradiance.extend(side * side),
                )
            }
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => (
                Vec3::ZERO.extend(1.0),
                position.extend(0.0).to_array(),
                intensity.extend(0.0),
            ),
            // Declined by the capability check and refused by GpuScene::upload: no
            // power, so nothing could ever be drawn from them.
            Light::Sphere { position, .. } => (
                Vec3::ZERO.extend(1.0),
                position.extend(0.0).to_array(),
                Vec3::ZERO.extend(0.0),
            ),
            Light::Environment { .. } => {
                (Vec3::NEG_Y.extend(0.0), [0.0; 4], Vec3::ZERO.extend(0.0))
            }
        };
        let (sigma_t, sigma_s_g) = match &scene.medium {
            Some(m) => (
                m.sigma_t().extend(1.0).to_array(),
                m.sigma_s.extend(m.g).to_array(),
            ),
            None => ([0.0; 4], [0.0; 4]),
        };
        let cam = &scene.camera;
        let (b, r) = (&config.beams, &config.refinement);
        Self {
            light_inv_view_proj: view.faces[0].view_proj.inverse().to_cols_array_2d(),
            light_dir_kind: light_dir_kind.to_array(),
            light_pos_start,
            light_power: power.to_array(),
            sigma_t,
            sigma_s_g,
            receivers: center_reach(slots.len()),
            specular,
            specular_count: slots.len() as u32,
            grid: b.grid,
            levels: r.levels,
            max_beams: b.max_beams,
            split_flags: r.flags(),
            split_cos_normal: (r.split_normal_deg.to_radians().cos()) as f32,
            split_depth_slope: r.split_depth_slope as f32,
            split_energy: r.split_energy_threshold as f32,
            split_camera_px: r.split_camera_px as f32,
            pixel_angle: cam.fov_y_rad() / cam.height as f32,
            reflections: b.reflections as u32,
            tight_hulls: (b.hull == HullKind::Tight) as u32,
            max_focus: b.max_focus as f32,
            soft_depth: b.soft_depth_m as f32,
            impostor_tolerance: 0.01,
            scene_reach: 2.0 * bounds.bounding_sphere_radius().max(1e-3),
            split_hit_px: r.split_hit_px as f32,
            bounces: b.bounces,
            exact_trace: u32::from(b.tracer == Tracer::Bvh),
            split_hit_rel: r.split_hit_rel as f32,
            beam_budget: if r.levels > 0 { r.beam_budget } else { 0 },
            splat_orphans: u32::from(b.splat_orphans),
            light_index: light_index as u32,
            vertex_cache_side,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{filter_source, generate_source, rasterize_source};
    use caustics_gpu::assert_wgsl_layout;

    #[test]
    fn structs_match_their_wgsl() {
        assert_wgsl_layout!(
            generate_source(),
            SpecularSlot {
                center_reach,
                color,
                object,
                kind,
                closed,
                ior
            }
        );
        assert_wgsl_layout!(
            generate_source(),
            BeamUniforms {
                light_inv_view_proj,
                light_dir_kind,
                light_pos_start,
                light_power,
                sigma_t,
                sigma_s_g,
                receivers,
                specular,
                specular_count,
                grid,
                levels,
                max_beams,
                split_flags,
                split_cos_normal,
                split_depth_slope,
                split_energy,
                split_camera_px,
                pixel_angle,
                reflections,
                tight_hulls,
                max_focus,
                soft_depth,
                impostor_tolerance,
                scene_reach,
                split_hit_px,
                bounces,
                exact_trace,
                split_hit_rel,
                beam_budget,
                splat_orphans,
                light_index,
                vertex_cache_side,
            }
        );
        assert_wgsl_layout!(
            filter_source(),
            FilterUniforms {
                sigma_px,
                radius_px
            }
        );
        assert_wgsl_layout!(
            rasterize_source(false),
            BeamRecord as "Beam" {
                v,
                d,
                flux,
                n,
                hull,
                tris
            }
        );
    }

    #[test]
    fn candidate_orphan_and_vertex_path_sizes_match_their_wgsl() {
        let (_, span) = caustics_gpu::layout::wgsl_struct_layout(&generate_source(), "Candidate")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(u64::from(span), CANDIDATE_BYTES);
        let (_, span) = caustics_gpu::layout::wgsl_struct_layout(&generate_source(), "Orphan")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(u64::from(span), ORPHAN_BYTES);
        let (_, span) = caustics_gpu::layout::wgsl_struct_layout(&generate_source(), "CachedPath")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(u64::from(span), VERTEX_PATH_BYTES);
    }
}
