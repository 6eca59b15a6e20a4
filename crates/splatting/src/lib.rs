//! `splatting`: the caustic-mapping baseline that Umenhoffer, Patow & Szirmay-Kalos
//! compare caustic triangles against (their §2 and Fig. 1), as a caustics-bench method.
//!
//! The photon hit location image is the same as `caustic-triangles'` (the
//! [`photon_hits`] crate: light G-buffer, distance maps, photon tracing), and so are the
//! caustic cube map and the camera pass with its distance test; only the
//! reconstruction differs: every valid hit is drawn as a fixed box kernel of
//! `kernel_px` × `kernel_px` cube-map texels carrying the hit's flux over the receiver
//! area the kernel covers (`splat.wgsl`), so the energy is conserved whatever the
//! kernel. A small kernel leaves the dots of individual photons, a large one blurs the
//! caustic: the paper's argument that no single splat size fits an uneven photon
//! density, which the `umenhoffer-fig1` experiment of `caustics reproduce` sweeps.
//!
//! Passes (names `splatting/<pass>`): `light_gbuffer`, `distance_maps`,
//! `trace_photons`, `splat` (raster, all six faces in one pass), `camera_lookup`.
//!
//! ```no_run
//! use caustics_gpu::{AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer};
//! use caustics_method::CausticsMethod;
//! use splatting::{Splatting, SplattingParams};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(None))?;
//! let scene = caustics_scene::Scene::load(&caustics_scene::resolve("sphere_on_plane")?)?;
//! let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default())?;
//! let renderer = Renderer::new(&ctx, gpu_scene, Default::default())?;
//! let mut method = Splatting::new(&ctx, &renderer, &SplattingParams::default())?;
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

const SPLAT_WGSL: &str = include_str!("splat.wgsl");

/// Registry name.
pub const NAME: &str = "splatting";

/// Parameters of `splatting` (the photon-hit settings match `caustic-triangles'`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct SplattingParams {
    /// Photon hit location image, texels per side.
    pub resolution: u32,
    /// Caustic cube map, texels per face side.
    pub cube_size: u32,
    /// Distance maps (generator and receivers), texels per face side.
    pub distance_map_size: u32,
    /// Accept caustic light only where the stored distance matches.
    pub distance_test: bool,
    /// Relative tolerance of the distance test.
    pub distance_tolerance: f64,
    /// Kernel side in cube-map texels.
    pub kernel_px: u32,
}

impl Default for SplattingParams {
    fn default() -> Self {
        Self {
            resolution: 128,
            cube_size: 512,
            distance_map_size: 256,
            distance_test: true,
            distance_tolerance: 0.05,
            kernel_px: 4,
        }
    }
}

impl SplattingParams {
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
        if !(1..=64).contains(&self.kernel_px) || self.kernel_px > self.cube_size {
            return Err(MethodError::Param {
                method: NAME,
                message: format!(
                    "kernel_px: expected an integer in 1..=64 and at most cube_size ({}), got {}",
                    self.cube_size, self.kernel_px
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
        summary: "the caustic-mapping baseline: the photon hits of caustic-triangles splatted as fixed kernels into the same cube map",
        source: "photon splatting as compared in Umenhoffer, Patow & Szirmay-Kalos, Caustic Triangles on the GPU, Fig. 1",
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
            param_specs::<SplattingParams>(&[
                ("resolution", "photon hit location image, texels per side"),
                ("cube_size", "caustic cube map, texels per face side"),
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
                ("kernel_px", "splat kernel side in cube-map texels"),
            ])
        },
        validate_params: |v| parse_params::<SplattingParams>(NAME, v)?.validate(),
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
    let p: SplattingParams = parse_params(NAME, params)?;
    p.validate()?;
    Ok(Box::new(Splatting::new(ctx, renderer, &p)?))
}

/// Matches `SplatUniform` in splat.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatUniform {
    kernel_px: u32,
    _pad: [u32; 3],
}

/// `splatting` bound to one scene.
pub struct Splatting {
    hits: PhotonHits,
    map: CausticMap,
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    kernel_px: u32,
    bytes: u64,
}

impl Splatting {
    /// Builds the photon hit image, the caustic cube map and the splat pass.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &SplattingParams,
    ) -> Result<Self, MethodError> {
        let config = params.config();
        let hits = PhotonHits::new(ctx, renderer, NAME, &config)?;
        let map = CausticMap::new(ctx, renderer, NAME, hits.center, hits.reach, &config)?;
        let device = &ctx.device;
        let (pipeline, bind, own_bytes) = ctx.checked("splatting setup", || {
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("splat params"),
                contents: bytemuck::bytes_of(&SplatUniform {
                    kernel_px: params.kernel_px,
                    _pad: [0; 3],
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("splat"),
                entries: &[
                    uniform_entry(0, vf),
                    uniform_entry(1, vf),
                    storage_entry(2, true, vf),
                ],
            });
            let bind = buffers_bind_group(
                device,
                "splat",
                &layout,
                &[map.uniform(), &uniform, &hits.hits],
            );
            let module = shader::module(
                device,
                "splatting splat.wgsl",
                photon_hits::compose(SPLAT_WGSL),
            );
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("splat"),
                bind_group_layouts: &[Some(renderer.frame_layout()), Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("splat"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_splat"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_splat"),
                    compilation_options: Default::default(),
                    targets: &[Some(additive_hdr_target())],
                }),
                multiview_mask: None,
                cache: None,
            });
            (pipeline, bind, uniform.size())
        })?;
        let bytes = own_bytes + hits.bytes() + map.bytes();
        Ok(Self {
            hits,
            map,
            pipeline,
            bind,
            kernel_px: params.kernel_px,
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
}

impl CausticsMethod for Splatting {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        self.hits.record(frame)?;
        {
            let mut pass = self.map.begin_reconstruction(frame, "splatting/splat")?;
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.bind, &[]);
            for face in 0..6 {
                self.map.set_face(&mut pass, face);
                pass.draw(0..6 * self.hits.texels(), face..face + 1);
            }
        }
        self.map.record_lookup(frame)
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let mut out = self.hits.counters(ctx)?;
        out.insert("kernel_px".into(), self.kernel_px as u64);
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
    fn shader_validates() -> Result<(), String> {
        shader::validate_wgsl("splat.wgsl", &photon_hits::compose(SPLAT_WGSL))
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"kernel_px": 0}), "kernel_px"),
            (serde_json::json!({"kernel_px": 65}), "kernel_px"),
            (
                serde_json::json!({"kernel_px": 32, "cube_size": 16}),
                "kernel_px",
            ),
            (serde_json::json!({"resolution": 5000}), "resolution"),
            (serde_json::json!({"max_stretch": 4}), "known parameters"),
        ] {
            let e =
                parse_params::<SplattingParams>(NAME, &json).and_then(|p| p.validate().map(|_| p));
            let msg = e.expect_err("must fail").to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        assert!(SplattingParams::default().validate().is_ok());
    }
}
