//! `caustic-triangles`: Umenhoffer, Patow & Szirmay-Kalos, "Caustic Triangles on the
//! GPU", as a caustics-bench method.
//!
//! Splatting photon hits needs a kernel size, and no single size suits the uneven
//! density of a caustic (the paper's Fig. 1). The paper instead joins neighbouring
//! photon hits into triangles, which adapt to the local density by construction: a
//! vertex carries the irradiance ΔΦ/ΔA of its photon's flux over the receiver area its
//! triangles cover, and Gouraud shading spreads it. The triangles are drawn into a
//! cube map around the caustic generator, which also knows distances, so that the
//! camera pass can refuse light reconstructed on a surface nearer to the generator
//! than the one being shaded (no light leaks).
//!
//! Passes (names `caustic-triangles/<pass>`), every frame:
//! 1. `light_gbuffer`, `distance_maps`, `trace_photons`: the photon hit location
//!    image (shared with `splatting`, see the [`photon_hits`] crate; §3, §4.1);
//! 2. `triangle_areas` (compute): the discard rule and each triangle's receiver area
//!    (`areas.wgsl` states the rule);
//! 3. `vertex_irradiance` (compute, the §5 per-vertex pass): ΔΦ/ΔA per vertex, with
//!    ΔA = (2/n) × the area of its n kept triangles (one cell's worth);
//! 4. `triangles` (raster, §4.2): all triangles into the six faces of the caustic
//!    cube map, additive, irradiance and luminance × distance;
//! 5. `camera_lookup` (§4.3): ρ/π · E at each camera pixel whose distance from the
//!    centre matches the map's (`distance_test`).
//!
//! The photon hit image is one light view fitted to the generator (a cube for a light
//! inside it); triangles do not cross between the faces of a cube view.
//!
//! ```no_run
//! use caustics_gpu::{AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer};
//! use caustics_method::CausticsMethod;
//! use caustic_triangles::{CausticTriangles, CausticTrianglesParams};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(None))?;
//! let scene = caustics_scene::Scene::load(&caustics_scene::resolve("sphere_on_plane")?)?;
//! let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default())?;
//! let renderer = Renderer::new(&ctx, gpu_scene, Default::default())?;
//! let mut method = CausticTriangles::new(&ctx, &renderer, &CausticTrianglesParams::default())?;
//! let mut profiler = PassProfiler::new(&ctx, 1);
//! let mut frame = renderer.begin_frame(&mut profiler, FrameMode::Timed)?;
//! method.record(&mut frame)?; // adds ρ/π · E into renderer.targets().surface
//! frame.submit(&ctx)?;
//! println!("{:?}", method.counters(&ctx)?);
//! # Ok(())
//! # }
//! ```

use bytemuck::{Pod, Zeroable};
use caustics_gpu::binding::{buffers_bind_group, storage_entry, uniform_entry};
use caustics_gpu::textures::additive_hdr_target;
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GpuContext, Renderer, shader};
use caustics_method::{
    Capabilities, CausticsMethod, Counters, MethodError, MethodInfo, Unsupported, param_specs,
    parse_params,
};
use caustics_scene::Scene;
use photon_hits::{CausticMap, PhotonHitConfig, PhotonHits};
use serde::{Deserialize, Serialize};

/// The shared photon-hit crate, for callers that read hits or the cube map back.
pub use photon_hits;

const GRID_WGSL: &str = include_str!("grid.wgsl");
const AREAS_WGSL: &str = include_str!("areas.wgsl");
const TRIANGLES_WGSL: &str = include_str!("triangles.wgsl");

fn pass_source(pass: &str) -> String {
    photon_hits::compose(&format!("{GRID_WGSL}\n{pass}"))
}

/// Registry name.
pub const NAME: &str = "caustic-triangles";

/// Parameters of `caustic-triangles` (defaults: the paper's §6 where it gives them).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct CausticTrianglesParams {
    /// Photon hit location image, texels per side (the paper: 128).
    pub resolution: u32,
    /// Caustic cube map, texels per face side (the paper: 512).
    pub cube_size: u32,
    /// Distance maps (generator and receivers), texels per face side.
    pub distance_map_size: u32,
    /// Accept caustic light only where the stored distance matches (§4.3).
    pub distance_test: bool,
    /// Relative tolerance of the distance test.
    pub distance_tolerance: f64,
    /// Discard a triangle whose receiver area exceeds this × its area at the generator.
    pub max_stretch: f64,
}

impl Default for CausticTrianglesParams {
    fn default() -> Self {
        Self {
            resolution: 128,
            cube_size: 512,
            distance_map_size: 256,
            distance_test: true,
            distance_tolerance: 0.05,
            max_stretch: 1000.0,
        }
    }
}

impl CausticTrianglesParams {
    /// The shared photon-hit settings.
    pub fn config(&self) -> PhotonHitConfig {
        PhotonHitConfig {
            resolution: self.resolution,
            distance_map_size: self.distance_map_size,
            cube_size: self.cube_size,
            distance_test: self.distance_test,
            distance_tolerance: self.distance_tolerance as f32,
        }
    }

    /// Range checks, with errors naming the parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.config().validate(NAME)?;
        if !(self.max_stretch.is_finite() && self.max_stretch >= 1.0) {
            return Err(MethodError::Param {
                method: NAME,
                message: format!(
                    "max_stretch: expected a number >= 1, got {}",
                    self.max_stretch
                ),
            });
        }
        Ok(())
    }
}

/// The registry entry.
pub fn info() -> MethodInfo {
    MethodInfo {
        name: NAME,
        summary: "photon hit image from the light, neighbouring hits as triangles with per-vertex irradiance in a cube map with distance (no light leaks), camera lookup",
        source: "Umenhoffer, Patow & Szirmay-Kalos, Caustic Triangles on the GPU (umenhoffer-patow-szirmay-kalos-caustic-triangles.txt)",
        capabilities: Capabilities {
            surface: true,
            volume: false,
            reflection: true,
            refraction: true,
            multiple_bounces: false,
            directional_light: true,
            point_light: true,
            spot_light: true,
        },
        params: || {
            param_specs::<CausticTrianglesParams>(&[
                (
                    "resolution",
                    "photon hit location image, texels per side (paper: 128)",
                ),
                (
                    "cube_size",
                    "caustic cube map, texels per face side (paper: 512)",
                ),
                (
                    "distance_map_size",
                    "distance maps of the generator and the receivers, texels per face side",
                ),
                (
                    "distance_test",
                    "accept caustic light only where the stored distance matches (false shows light leaks)",
                ),
                (
                    "distance_tolerance",
                    "distance test: |stored - actual| <= tolerance x actual",
                ),
                (
                    "max_stretch",
                    "discard triangles whose receiver area exceeds this x their area at the generator",
                ),
            ])
        },
        validate_params: |v| parse_params::<CausticTrianglesParams>(NAME, v)?.validate(),
        check_scene,
        create,
    }
}

fn check_scene(scene: &Scene, _params: &serde_json::Value) -> Result<(), Unsupported> {
    photon_hits::check_scene(scene)
}

fn create(
    ctx: &GpuContext,
    renderer: &Renderer,
    params: &serde_json::Value,
) -> Result<Box<dyn CausticsMethod>, MethodError> {
    let p: CausticTrianglesParams = parse_params(NAME, params)?;
    p.validate()?;
    Ok(Box::new(CausticTriangles::new(ctx, renderer, &p)?))
}

/// Matches `TriUniform` in grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TriUniform {
    layers: u32,
    resolution: u32,
    max_stretch: f32,
    _pad: u32,
}

/// Names of the triangle counters, in the order of `TRI_*` in grid.wgsl.
const TRI_REASONS: [&str; 6] = [
    "triangles_kept",
    "triangles_dropped_invalid_vertex",
    "triangles_dropped_receiver_mismatch",
    "triangles_dropped_path_mismatch",
    "triangles_dropped_stretched",
    "triangles_dropped_degenerate",
];

/// `caustic-triangles` bound to one scene.
pub struct CausticTriangles {
    hits: PhotonHits,
    map: CausticMap,
    areas_pipeline: wgpu::ComputePipeline,
    irradiance_pipeline: wgpu::ComputePipeline,
    raster_pipeline: wgpu::RenderPipeline,
    compute_bind: wgpu::BindGroup,
    raster_bind: wgpu::BindGroup,
    vertex_irradiance: wgpu::Buffer,
    tri_counters: wgpu::Buffer,
    triangle_count: u32,
    bytes: u64,
}

impl CausticTriangles {
    /// Builds the photon hit image, the caustic cube map and the reconstruction passes.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &CausticTrianglesParams,
    ) -> Result<Self, MethodError> {
        let config = params.config();
        let hits = PhotonHits::new(ctx, renderer, NAME, &config)?;
        let map = CausticMap::new(ctx, renderer, NAME, hits.center, hits.reach, &config)?;
        let device = &ctx.device;
        let n = hits.resolution;
        let triangle_count = hits.layers * (n - 1) * (n - 1) * 2;
        let built = ctx.checked("caustic-triangles setup", || {
            let tri_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("caustic triangles params"),
                contents: bytemuck::bytes_of(&TriUniform {
                    layers: hits.layers,
                    resolution: n,
                    max_stretch: params.max_stretch as f32,
                    _pad: 0,
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
            let tri_area = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("caustic triangle areas"),
                size: triangle_count.max(1) as u64 * 4,
                usage: storage,
                mapped_at_creation: false,
            });
            let vertex_irradiance = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("caustic vertex irradiance"),
                size: hits.texels() as u64 * 16,
                usage: storage,
                mapped_at_creation: false,
            });
            let tri_counters = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("caustic triangle counters"),
                size: 4 * 8,
                usage: storage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let cs = wgpu::ShaderStages::COMPUTE;
            let compute_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("caustic triangles compute"),
                    entries: &[
                        uniform_entry(0, cs),
                        storage_entry(1, true, cs),
                        storage_entry(2, false, cs),
                        storage_entry(3, false, cs),
                        storage_entry(4, false, cs),
                    ],
                });
            let compute_bind = buffers_bind_group(
                device,
                "caustic triangles compute",
                &compute_layout,
                &[
                    &tri_uniform,
                    &hits.hits,
                    &tri_area,
                    &vertex_irradiance,
                    &tri_counters,
                ],
            );
            let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
            let raster_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("caustic triangles raster"),
                entries: &[
                    uniform_entry(0, vf),
                    uniform_entry(1, vf),
                    storage_entry(2, true, vf),
                    storage_entry(3, true, vf),
                    storage_entry(4, true, vf),
                ],
            });
            let raster_bind = buffers_bind_group(
                device,
                "caustic triangles raster",
                &raster_layout,
                &[
                    map.uniform(),
                    &tri_uniform,
                    &hits.hits,
                    &tri_area,
                    &vertex_irradiance,
                ],
            );
            let layout = |label: &str, own: &wgpu::BindGroupLayout| {
                device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(label),
                    bind_group_layouts: &[Some(renderer.frame_layout()), Some(own)],
                    immediate_size: 0,
                })
            };
            let areas_module = shader::module(
                device,
                "caustic-triangles areas.wgsl",
                pass_source(AREAS_WGSL),
            );
            let compute_pipeline_layout = layout("caustic triangles compute", &compute_layout);
            let compute = |entry: &str| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&compute_pipeline_layout),
                    module: &areas_module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            };
            let areas_pipeline = compute("triangle_areas");
            let irradiance_pipeline = compute("vertex_irradiance_pass");
            let raster_module = shader::module(
                device,
                "caustic-triangles triangles.wgsl",
                pass_source(TRIANGLES_WGSL),
            );
            let raster_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("caustic triangles"),
                layout: Some(&layout("caustic triangles raster", &raster_layout)),
                vertex: wgpu::VertexState {
                    module: &raster_module,
                    entry_point: Some("vs_triangle"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                // Triangles folded over a caustic curve face the other way: both count.
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &raster_module,
                    entry_point: Some("fs_triangle"),
                    compilation_options: Default::default(),
                    targets: &[Some(additive_hdr_target())],
                }),
                multiview_mask: None,
                cache: None,
            });
            let bytes = tri_uniform.size()
                + tri_area.size()
                + vertex_irradiance.size()
                + tri_counters.size();
            (
                areas_pipeline,
                irradiance_pipeline,
                raster_pipeline,
                compute_bind,
                raster_bind,
                vertex_irradiance,
                tri_counters,
                bytes,
            )
        })?;
        let (
            areas_pipeline,
            irradiance_pipeline,
            raster_pipeline,
            compute_bind,
            raster_bind,
            vertex_irradiance,
            tri_counters,
            own_bytes,
        ) = built;
        let bytes = own_bytes + hits.bytes() + map.bytes();
        Ok(Self {
            hits,
            map,
            areas_pipeline,
            irradiance_pipeline,
            raster_pipeline,
            compute_bind,
            raster_bind,
            vertex_irradiance,
            tri_counters,
            triangle_count,
            bytes,
        })
    }

    /// The photon hit image.
    pub fn photon_hits(&self) -> &PhotonHits {
        &self.hits
    }

    /// The caustic cube map.
    pub fn caustic_map(&self) -> &CausticMap {
        &self.map
    }

    /// Per-vertex irradiance (W/m², rgb + unused w), one per photon-image texel,
    /// read back for tests and figures.
    pub fn read_vertex_irradiance(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>, MethodError> {
        let bytes = caustics_gpu::readback::read_buffer_bytes(
            ctx,
            &self.vertex_irradiance,
            self.vertex_irradiance.size(),
            "caustic vertex irradiance",
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

impl CausticsMethod for CausticTriangles {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        self.hits.record(frame)?;
        frame.encoder.clear_buffer(&self.tri_counters, 0, None);
        {
            let mut pass = frame.compute_pass("caustic-triangles/triangle_areas")?;
            pass.set_pipeline(&self.areas_pipeline);
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.compute_bind, &[]);
            pass.dispatch_workgroups(self.triangle_count.div_ceil(64), 1, 1);
        }
        {
            let mut pass = frame.compute_pass("caustic-triangles/vertex_irradiance")?;
            pass.set_pipeline(&self.irradiance_pipeline);
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.compute_bind, &[]);
            pass.dispatch_workgroups(self.hits.texels().div_ceil(64), 1, 1);
        }
        {
            let mut pass = self
                .map
                .begin_reconstruction(frame, "caustic-triangles/triangles")?;
            pass.set_pipeline(&self.raster_pipeline);
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.raster_bind, &[]);
            for face in 0..6 {
                self.map.set_face(&mut pass, face);
                pass.draw(0..3 * self.triangle_count, face..face + 1);
            }
        }
        self.map.record_lookup(frame)
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let mut out = self.hits.counters(ctx)?;
        let c = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.tri_counters,
            self.tri_counters.size(),
            "caustic triangle counters",
        )?;
        out.insert("triangles".into(), self.triangle_count as u64);
        for (name, v) in TRI_REASONS.iter().zip(&c) {
            out.insert((*name).into(), *v as u64);
        }
        Ok(out)
    }

    fn gpu_memory_bytes(&self) -> u64 {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shaders_validate() -> Result<(), String> {
        shader::validate_wgsl("areas.wgsl", &pass_source(AREAS_WGSL))?;
        shader::validate_wgsl("triangles.wgsl", &pass_source(TRIANGLES_WGSL))
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"resolution": 1}), "resolution"),
            (serde_json::json!({"cube_size": 8}), "cube_size"),
            (
                serde_json::json!({"distance_map_size": 9000}),
                "distance_map_size",
            ),
            (
                serde_json::json!({"distance_tolerance": 2.0}),
                "distance_tolerance",
            ),
            (serde_json::json!({"max_stretch": 0.5}), "max_stretch"),
            (serde_json::json!({"distance_test": "yes"}), "invalid type"),
            (serde_json::json!({"kernel_px": 4}), "known parameters"),
        ] {
            let e = parse_params::<CausticTrianglesParams>(NAME, &json)
                .and_then(|p| p.validate().map(|_| p));
            let msg = e.expect_err("must fail").to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        assert!(CausticTrianglesParams::default().validate().is_ok());
    }
}
