//! Headless wgpu layer of caustics-bench: adapter choice, one scene upload, the
//! camera and light G-buffers, direct lighting with shadows, the HDR radiance targets
//! and the instrumentation (timestamps and pipeline statistics per named pass, fill
//! counting per pixel) through which the harness measures every method alike, and the
//! scoring frames ([`scoring`]: sub-pixel camera offsets averaged on the GPU, so errors
//! are taken at the reference's pixel footprint).
//!
//! ```no_run
//! use caustics_gpu::{AdapterChoice, GpuContext, GpuScene, Renderer, RendererOptions, PassProfiler, FrameMode};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(None))?;
//! let scene = caustics_scene::Scene::load(&caustics_scene::resolve("sphere_on_plane")?)?;
//! let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default())?;
//! let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default())?;
//! let mut profiler = PassProfiler::new(&ctx, 1);
//! let frame = renderer.begin_frame(&mut profiler, FrameMode::Timed)?;
//! frame.submit(&ctx)?;
//! for f in profiler.collect(&ctx)? {
//!     for p in f.passes { println!("{}: {:?} ms", p.name, p.gpu_ms); }
//! }
//! # Ok(()) }
//! ```

pub mod buffers;
mod context;
mod error;
pub mod frame;
pub mod gbuffer;
pub mod impostor;
pub mod layout;
pub mod light_view;
pub mod limits;
pub mod pass;
pub mod pipeline_cache;
pub mod profiling;
pub mod readback;
pub mod renderer;
pub mod scene_upload;
pub mod scoring;
pub mod shader;
pub mod textures;
pub mod triangle_bvh;

pub use context::{
    ADAPTER_ENV, AdapterChoice, AdapterSummary, GpuContext, OPTIONAL_FEATURES, REQUIRED_FEATURES,
    adapter_summary, choose_adapter, enumerate_adapters,
};
pub use error::GpuError;
pub use frame::{BareFrame, Frame, ProfiledComputePass, ProfiledRenderPass};
pub use gbuffer::{GBuffer, GBufferPass, ShadowMap};
pub use impostor::{DistanceImpostor, ImpostorAtlas, ImpostorPass};
pub use light_view::{LightFace, LightProjection, LightView};
pub use pipeline_cache::PipelineStats;
pub use profiling::{FrameMode, FrameSample, PassProfiler, PassSample, PassShape, PassStatistics};
pub use renderer::{DIRECT_REPRESENTATIVE_LIGHTS, Renderer, RendererOptions};
pub use scene_upload::GpuScene;
pub use scoring::{ScoreAccumulator, ScoredImages, subpixel_offsets};
pub use wgpu;
