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
//! The paper gives no size; the default (`kernel_px = 0`) is four hit-image texels
//! wide, 4 × cube_size / resolution cube-map texels, the best kernel of the
//! `splatting-kernel` sweep at every hit resolution ([`KERNEL_PER_HIT_TEXEL`]).
//!
//! Passes (names `splatting/<pass>`): `light_gbuffer`, `distance_maps`,
//! `trace_photons`, `splat` (raster, all six faces in one pass), `camera_lookup`.
//!
//! `raster=compute` (issue 17) replaces the raster `splat` by a compute pass of the same
//! name (`splat_compute.wgsl`): one invocation per (hit, kernel row) adds the very
//! texel values of the raster path (`splat_texel`) into a fixed-point accumulator with
//! integer atomics, and a second dispatch resolves it into the atlas. The image is the
//! same on every run (integer sums do not depend on order) and within a stated bound of
//! the hardware path's (`tests/accuracy.rs`).
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
use caustics_gpu::pass::{ComputePass, RasterPass, Shader, groups_2d};
use caustics_gpu::textures::additive_hdr_target;
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GpuContext, Renderer};
use caustics_method::params::{Raster, closed};
use caustics_method::{
    Capabilities, CausticsMethod, CounterDoc, Counters, Method, MethodError, Unsupported,
    method_params,
};
use caustics_scene::Scene;
use photon_hits::{AtlasAccumulator, CausticMap, PhotonHitConfig, PhotonHits};

const SPLAT_WGSL: &str = include_str!("splat.wgsl");
const SPLAT_COMPUTE_WGSL: &str = include_str!("splat_compute.wgsl");

/// Registry name.
pub const NAME: &str = "splatting";

method_params! {
    /// Parameters of `splatting`: the photon-hit settings of `caustic-triangles` and
    /// the kernel size.
    pub struct SplattingParams {
        group
        /// The photon hit image, distance maps and cube map, as `caustic-triangles`.
        hits: PhotonHitConfig;
        /// splat kernel side in cube-map texels; 0 = chosen from the hit image: 4 x cube_size / resolution (the splatting-kernel experiment's best at every hit resolution)
        kernel_px: u32 = 0 => closed(0.0, 64.0);
        /// how the kernels reach the cube map: hardware (rasterized quads, additive blending: the paper's) or compute (a compute pass adding each kernel texel into a fixed-point accumulator with integer atomics, then resolved: the same image on every run)
        raster: Raster = Raster::Hardware;
    }
    check = |p: &SplattingParams| {
        if p.kernel_px > p.hits.cube_size {
            Err(format!(
                "kernel_px: expected at most cube_size ({}), got {}",
                p.hits.cube_size, p.kernel_px
            ))
        } else {
            Ok(())
        }
    };
}

// The kernel rule lives with the photon hits: caustic-triangles' orphan splats use it too.
pub use photon_hits::{KERNEL_PER_HIT_TEXEL, auto_kernel_px};

/// The kernel `params` ask for, `kernel_px = 0` resolved.
pub fn kernel_px(params: &SplattingParams) -> u32 {
    match params.kernel_px {
        0 => auto_kernel_px(&params.hits),
        k => k,
    }
}

/// What splatting's own counter says; [`Method::COUNTERS`] adds it to the photon
/// tracing ones of [`photon_hits::COUNTER_DOCS`].
pub const SPLAT_COUNTER_DOCS: &[CounterDoc] = &[CounterDoc {
    name: "kernel_px",
    doc: "side of the square kernel each valid photon hit is splatted with, in cube-map texels: the kernel_px parameter, or 4 x cube_size / resolution (rounded, within 1..=64) where it is 0 (a setting, not a count)",
}];

impl Method for Splatting {
    type Params = SplattingParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str = "the caustic-mapping baseline: the photon hits of caustic-triangles splatted as fixed kernels into the same cube map";
    const SOURCE: &'static str = "photon splatting as compared in Umenhoffer, Patow & Szirmay-Kalos, Caustic Triangles on the GPU, Fig. 1";
    const CAPABILITIES: Capabilities = photon_hits::CAPABILITIES;
    const COUNTERS: &'static [CounterDoc] = &CounterDoc::concat::<
        { photon_hits::COUNTER_DOCS.len() + SPLAT_COUNTER_DOCS.len() },
    >(photon_hits::COUNTER_DOCS, SPLAT_COUNTER_DOCS);

    fn check_scene(scene: &Scene, _params: &SplattingParams) -> Result<(), Unsupported> {
        photon_hits::check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &SplattingParams,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        Ok(Box::new(Splatting::new(ctx, renderer, params)?))
    }
}

/// Matches `SplatUniform` in splat.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatUniform {
    kernel_px: u32,
    _pad: [u32; 3],
}

/// The splat pass of one (light, generator) pair, on either path.
enum SplatPass {
    /// Rasterized quads, additively blended into the atlas.
    Hardware(RasterPass),
    /// The compute splat and resolve, and the fixed-point accumulator they share.
    Compute {
        pass: ComputePass,
        _accumulator: AtlasAccumulator,
    },
}

/// `splatting` bound to one scene.
pub struct Splatting {
    /// One photon hit image and cube map per (light, caustic generator) pair,
    /// light-major ([`PhotonHits::for_scene`]).
    pairs: Vec<(PhotonHits, CausticMap)>,
    /// The splat pass of each pair (its bind group holds the pair's buffers).
    splat_passes: Vec<SplatPass>,
    kernel_px: u32,
    bytes: u64,
}

impl Splatting {
    /// Builds the photon hit images (one per light and caustic generator), their
    /// caustic cube maps and splat passes.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &SplattingParams,
    ) -> Result<Self, MethodError> {
        let kernel_px = kernel_px(params);
        let splat_uniform = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("splat params"),
                contents: bytemuck::bytes_of(&SplatUniform {
                    kernel_px,
                    _pad: [0; 3],
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let shader = match params.raster {
            Raster::Hardware => Shader::new(ctx, "splatting splat.wgsl", splat_source())?,
            Raster::Compute => {
                Shader::new(ctx, "splatting splat_compute.wgsl", splat_compute_source())?
            }
        };
        let mut pairs = Vec::new();
        let mut splat_passes = Vec::new();
        let mut bytes = splat_uniform.size();
        for hits in PhotonHits::for_scene(ctx, renderer, NAME, &params.hits)? {
            let (map, splat_pass) = match params.raster {
                Raster::Hardware => {
                    let map = CausticMap::new(
                        ctx,
                        renderer,
                        NAME,
                        hits.center,
                        hits.reach,
                        &params.hits,
                    )?;
                    // All six faces in one pass: each hit is drawn once per face,
                    // clipped to it.
                    let pass = RasterPass::builder(ctx, "splatting/splat", &shader, "vs_splat")
                        .frame(renderer)
                        .bind(
                            1,
                            &[
                                ("cm", map.uniform()),
                                ("su", &splat_uniform),
                                ("hits", &hits.hits),
                            ],
                        )
                        .fragment("fs_splat", &[Some(additive_hdr_target())])
                        .build()?;
                    (map, SplatPass::Hardware(pass))
                }
                Raster::Compute => {
                    let map = CausticMap::for_raster(
                        ctx,
                        renderer,
                        NAME,
                        &hits,
                        &params.hits,
                        params.raster,
                    )?;
                    let accumulator = AtlasAccumulator::new(ctx, NAME, &map)?;
                    let pass = ComputePass::builder(ctx, "splatting/splat", &shader)
                        .frame(renderer)
                        .bind(
                            1,
                            &[
                                ("cm", map.uniform()),
                                ("su", &splat_uniform),
                                ("hits", &hits.hits),
                                ("accum", &accumulator.buffer),
                                ("atlas_out", &map.atlas.view),
                            ],
                        )
                        .kernels(&["splat", "resolve"])
                        .build()?;
                    bytes += accumulator.bytes();
                    (
                        map,
                        SplatPass::Compute {
                            pass,
                            _accumulator: accumulator,
                        },
                    )
                }
            };
            bytes += hits.bytes() + map.bytes();
            pairs.push((hits, map));
            splat_passes.push(splat_pass);
        }
        Ok(Self {
            pairs,
            splat_passes,
            kernel_px,
            bytes,
        })
    }

    /// The first (light, generator) pair's photon hit image.
    pub fn photon_hits(&self) -> &PhotonHits {
        &self.pairs[0].0
    }

    /// The first pair's caustic cube map.
    pub fn caustic_map(&self) -> &CausticMap {
        &self.pairs[0].1
    }

    /// Every (light, generator) pair's hit image and cube map.
    pub fn pairs(&self) -> &[(PhotonHits, CausticMap)] {
        &self.pairs
    }
}

impl CausticsMethod for Splatting {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        for ((hits, map), splat_pass) in self.pairs.iter().zip(&self.splat_passes) {
            // Light side: the hits and their splats into the light-space cube map do not
            // depend on the camera; a reused scoring sub-frame only looks them up.
            if !frame.reuses_light_side() {
                hits.record(frame)?;
                match splat_pass {
                    SplatPass::Hardware(raster) => {
                        let target = map.reconstruction_attachment();
                        let mut pass = raster.begin(frame, &target, None)?;
                        for face in 0..6 {
                            map.set_face(&mut pass, face);
                            pass.draw(0..6 * hits.texels(), face..face + 1);
                        }
                    }
                    SplatPass::Compute { pass, .. } => {
                        let rows = u64::from(hits.texels()) * u64::from(self.kernel_px);
                        let mut recorder = pass.begin(frame)?;
                        recorder.dispatch("splat", groups_2d(rows.div_ceil(64)))?;
                        recorder.dispatch("resolve", AtlasAccumulator::resolve_groups(map))?;
                    }
                }
            }
            map.record_lookup(frame)?;
        }
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let mut out = Counters::new();
        for (hits, _) in &self.pairs {
            photon_hits::add_counters(&mut out, hits.counters(ctx)?);
        }
        out.insert("kernel_px".into(), self.kernel_px as u64);
        Ok(out)
    }

    fn gpu_memory_bytes(&self) -> u64 {
        self.bytes
    }
}

fn splat_source() -> String {
    photon_hits::compose(&format!("{}\n{SPLAT_WGSL}", photon_hits::SPLAT_KERNEL_WGSL))
}

fn splat_compute_source() -> String {
    photon_hits::compose(&format!(
        "{}\n{}\n{SPLAT_COMPUTE_WGSL}",
        photon_hits::SPLAT_KERNEL_WGSL,
        photon_hits::accumulator_wgsl()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_gpu::shader;
    use caustics_method::params::parse;

    #[test]
    fn shader_validates() -> Result<(), String> {
        shader::validate_wgsl("splat.wgsl", &splat_source())
    }

    #[test]
    fn compute_shader_validates() -> Result<(), String> {
        shader::validate_wgsl("splat_compute.wgsl", &splat_compute_source())
    }

    #[test]
    fn splat_uniform_matches_its_wgsl() {
        caustics_gpu::assert_wgsl_layout!(splat_source(), SplatUniform { kernel_px });
        caustics_gpu::assert_wgsl_layout!(splat_compute_source(), SplatUniform { kernel_px });
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"kernel_px": -1}), "kernel_px"),
            (serde_json::json!({"kernel_px": 65}), "kernel_px"),
            (
                serde_json::json!({"kernel_px": 32, "cube_size": 16}),
                "kernel_px",
            ),
            (serde_json::json!({"resolution": 5000}), "resolution"),
            (serde_json::json!({"max_stretch": 4}), "known parameters"),
        ] {
            let msg = parse::<SplattingParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        assert!(parse::<SplattingParams>(NAME, &serde_json::Value::Null).is_ok());
    }

    #[test]
    fn the_default_kernel_is_four_hit_texels_wide() {
        let at = |resolution, cube_size| {
            kernel_px(&SplattingParams {
                hits: PhotonHitConfig {
                    resolution,
                    cube_size,
                    ..Default::default()
                },
                ..Default::default()
            })
        };
        // The sweep's best kernels at 512² cube faces.
        assert_eq!((at(64, 512), at(128, 512), at(256, 512)), (32, 16, 8));
        // Bounded by the parameter's range and the face; an explicit kernel is kept.
        assert_eq!((at(2, 2048), at(1024, 16)), (64, 1));
        let explicit = SplattingParams {
            kernel_px: 3,
            ..Default::default()
        };
        assert_eq!(kernel_px(&explicit), 3);
    }
}
