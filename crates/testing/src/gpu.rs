//! The headless device, one uploaded scene, and a method's frames on it.

use std::sync::Arc;

use caustics_gpu::readback::read_rgba32f;
use caustics_gpu::{
    AdapterChoice, FrameMode, FrameSample, GpuContext, GpuScene, PassProfiler, Renderer,
    RendererOptions, ScoreAccumulator,
};
use caustics_method::{CausticsMethod, Counters, LightSide, MethodError, MethodInfo};
use caustics_metrics::HdrImage;
use caustics_scene::Scene;

/// Opens the adapter the harness would pick (`CAUSTICS_ADAPTER`, else the first hardware
/// adapter, else lavapipe).
///
/// # Panics
/// Without a usable adapter, with the GPU layer's message, which says to
/// `apt-get install -y mesa-vulkan-drivers` (lavapipe): a GPU test fails there, it is
/// never skipped.
pub fn context() -> GpuContext {
    GpuContext::new(&AdapterChoice::from_flag_or_env(None))
        .unwrap_or_else(|e| panic!("no GPU to test on: {e}"))
}

/// A device with one scene uploaded and its base renderer (G-buffers, shadows, the
/// radiance targets), on which methods are built and run.
pub struct Gpu {
    /// The device.
    pub ctx: GpuContext,
    /// The base renderer of the scene.
    pub renderer: Renderer,
}

/// What [`Gpu::measure`] recorded.
pub struct Measured {
    /// The timed frames after the warm-up, in order.
    pub frames: Vec<FrameSample>,
    /// The count frame after them (pipeline statistics, fill counting on).
    pub count: FrameSample,
    /// Fragments per camera pixel of the count frame's method passes (row-major).
    pub fill: Vec<u32>,
    /// The method's counters after the count frame.
    pub counters: Counters,
    /// Whether the adapter gave timestamps.
    pub timestamps: bool,
}

/// The scoring frame's images ([`Gpu::scoring_frame`]).
pub struct Scored {
    /// The direct image (L D E).
    pub direct: HdrImage,
    /// The surface caustic image.
    pub surface: HdrImage,
    /// The volume caustic image.
    pub volume: HdrImage,
    /// Sub-pixel offsets averaged (grid²).
    pub samples: u32,
}

impl Gpu {
    /// Opens the device ([`context`]) and uploads `scene` with the default renderer.
    pub fn new(scene: Scene) -> Self {
        Self::with_options(scene, RendererOptions::default())
    }

    /// [`Gpu::new`] with other renderer options (e.g. smaller shadow maps).
    ///
    /// # Panics
    /// Without an adapter (see [`context`]), or if the upload fails.
    pub fn with_options(scene: Scene, options: RendererOptions) -> Self {
        let ctx = context();
        let name = scene.name.clone();
        let gpu_scene = GpuScene::upload(&ctx, Arc::new(scene), Default::default())
            .unwrap_or_else(|e| panic!("uploading scene {name}: {e}"));
        let renderer = Renderer::new(&ctx, gpu_scene, options)
            .unwrap_or_else(|e| panic!("base renderer of scene {name}: {e}"));
        Self { ctx, renderer }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.renderer.scene().scene
    }

    /// Builds the method of registry entry `info` from JSON parameters (missing keys take
    /// the paper's defaults), as the harness does: parameters validated, the scene
    /// checked against what the method supports, then `info.create`.
    ///
    /// # Panics
    /// If the parameters are refused, the method declines the scene, or creation fails.
    pub fn method(&self, info: &MethodInfo, params: serde_json::Value) -> Box<dyn CausticsMethod> {
        self.try_method(info, params)
            .unwrap_or_else(|e| panic!("building {}: {e}", info.name))
    }

    /// [`Gpu::method`] returning the error, for tests of refusals.
    pub fn try_method(
        &self,
        info: &MethodInfo,
        params: serde_json::Value,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        let params = (info.parse)(&params)?;
        info.supports(self.scene(), &params)
            .map_err(|reason| MethodError::Unsupported {
                method: info.name,
                scene: self.scene().name.clone(),
                reason,
            })?;
        (info.create)(&self.ctx, &self.renderer, &params)
    }

    /// One timed frame of `method` (nothing collected).
    pub fn frame(&self, method: &mut dyn CausticsMethod) {
        let mut profiler = PassProfiler::new(&self.ctx, 1);
        self.record(method, &mut profiler, FrameMode::Timed);
    }

    fn record(
        &self,
        method: &mut dyn CausticsMethod,
        profiler: &mut PassProfiler,
        mode: FrameMode,
    ) {
        let mut frame = self
            .renderer
            .begin_frame(profiler, mode)
            .unwrap_or_else(|e| panic!("begin frame: {e}"));
        method
            .record(&mut frame)
            .unwrap_or_else(|e| panic!("recording the method's passes: {e}"));
        frame
            .submit(&self.ctx)
            .unwrap_or_else(|e| panic!("submitting the frame: {e}"));
    }

    /// As `caustics run` measures: `warmup` + `frames` timed frames, then one count frame
    /// (pipeline statistics and fill counting on, the same image), then the counters.
    /// A frame's image never depends on what came before (the harness's `gpu_scoring`
    /// test checks it), so accuracy tests take `(0, 1)`.
    pub fn measure(&self, method: &mut dyn CausticsMethod, warmup: u32, frames: u32) -> Measured {
        let total = warmup + frames + 1;
        let mut profiler = PassProfiler::new(&self.ctx, total);
        for i in 0..total {
            let mode = if i + 1 < total {
                FrameMode::Timed
            } else {
                FrameMode::Count
            };
            self.record(method, &mut profiler, mode);
        }
        let mut samples = profiler
            .collect(&self.ctx)
            .unwrap_or_else(|e| panic!("collecting the profiler: {e}"));
        let count = samples.pop().expect("the count frame was recorded");
        let frames = samples.split_off(warmup as usize);
        Measured {
            frames,
            count,
            fill: self
                .renderer
                .read_fill_counts(&self.ctx)
                .unwrap_or_else(|e| panic!("reading fill counts: {e}")),
            counters: method
                .counters(&self.ctx)
                .unwrap_or_else(|e| panic!("reading counters: {e}")),
            timestamps: profiler.has_timestamps(),
        }
    }

    /// The scoring frame (DESIGN "Measuring honestly"): the frame at `grid × grid`
    /// stratified sub-pixel offsets averaged on the GPU, the reference's pixel footprint,
    /// with the light side rendered once and reused, as `caustics run` scores.
    pub fn scoring_frame(&self, method: &mut dyn CausticsMethod, grid: u32) -> Scored {
        self.scoring_frame_with(method, grid, LightSide::Reuse)
    }

    /// [`Harness::scoring_frame`] with the light side rendered as `light_side` says.
    pub fn scoring_frame_with(
        &self,
        method: &mut dyn CausticsMethod,
        grid: u32,
        light_side: LightSide,
    ) -> Scored {
        let mut accumulator = ScoreAccumulator::new(&self.ctx, &self.renderer)
            .unwrap_or_else(|e| panic!("score accumulator: {e}"));
        let scored = caustics_method::render_scoring_frame(
            &self.ctx,
            &self.renderer,
            method,
            &mut accumulator,
            grid,
            light_side,
        )
        .unwrap_or_else(|e| panic!("scoring frame: {e}"));
        let image = |rgba: &[f32], what: &str| self.image(rgba, what);
        Scored {
            direct: image(&scored.direct, "direct image (scoring frame)"),
            surface: image(&scored.surface, "surface caustic image (scoring frame)"),
            volume: image(&scored.volume, "volume caustic image (scoring frame)"),
            samples: scored.frames,
        }
    }

    /// Checks a method's split into light-side and camera-side passes
    /// ([`caustics_gpu::Frame::reuses_light_side`]): its `grid × grid` scoring frame with
    /// the light side reused must equal the one where every sub-frame is a whole frame,
    /// pixel for pixel (surface, volume and direct). A camera-dependent pass skipped in
    /// reused sub-frames would leave the centre camera's result in every sub-frame and
    /// fail this. Returns the reused frame.
    pub fn assert_light_side_reuse_is_exact(
        &self,
        method: &mut dyn CausticsMethod,
        grid: u32,
    ) -> Scored {
        let each = self.scoring_frame_with(method, grid, LightSide::RenderEach);
        let reused = self.scoring_frame_with(method, grid, LightSide::Reuse);
        for (what, a, b) in [
            ("surface", &reused.surface, &each.surface),
            ("volume", &reused.volume, &each.volume),
            ("direct", &reused.direct, &each.direct),
        ] {
            let differing = a
                .pixels
                .iter()
                .zip(&b.pixels)
                .filter(|(x, y)| x != y)
                .count();
            assert_eq!(
                differing,
                0,
                "{what}: {differing} of {} pixels differ between the {grid}x{grid} scoring frame with the light side reused and with it rendered in every sub-frame",
                a.pixels.len()
            );
        }
        reused
    }

    fn image(&self, rgba: &[f32], what: &str) -> HdrImage {
        let camera = &self.scene().camera;
        let img = HdrImage::from_rgba_f32(camera.width, camera.height, rgba)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        img.check_finite(what).unwrap_or_else(|e| panic!("{e}"));
        img
    }

    fn read(&self, texture: &caustics_gpu::wgpu::Texture, what: &str) -> Vec<f32> {
        read_rgba32f(&self.ctx, texture, what).unwrap_or_else(|e| panic!("reading {what}: {e}"))
    }

    /// The surface caustic target of the last frame (checked finite).
    pub fn surface(&self) -> HdrImage {
        let t = &self.renderer.targets().surface.texture;
        self.image(
            &self.read(t, "surface caustic image"),
            "surface caustic image",
        )
    }

    /// The volume caustic target of the last frame (checked finite).
    pub fn volume(&self) -> HdrImage {
        let t = &self.renderer.targets().volume.texture;
        self.image(
            &self.read(t, "volume caustic image"),
            "volume caustic image",
        )
    }

    /// The direct image (L D E) of the last frame (checked finite).
    pub fn direct(&self) -> HdrImage {
        let t = &self.renderer.targets().direct.texture;
        self.image(&self.read(t, "direct image"), "direct image")
    }

    /// The camera G-buffer's world positions, RGBA per pixel (row-major, row 0 at the
    /// top); alpha > 0.5 where a surface is hit.
    pub fn positions(&self) -> Vec<f32> {
        let t = &self.renderer.camera_gbuffer().position.texture;
        self.read(t, "camera G-buffer positions")
    }
}

impl Measured {
    /// The pass names of the count frame, in recording order (a pass recorded more than
    /// once per frame is listed each time).
    pub fn pass_names(&self) -> Vec<&str> {
        self.count.passes.iter().map(|p| p.name.as_str()).collect()
    }

    /// Fragment-shader invocations of pass `name` in the count frame (pipeline
    /// statistics, summed over its recordings); `None` without statistics or pass.
    pub fn fragment_invocations(&self, name: &str) -> Option<u64> {
        self.pass_statistic(name, |s| s.fragment_invocations)
    }

    /// Vertex-shader invocations of pass `name` in the count frame (pipeline
    /// statistics, summed over its recordings): one per vertex a non-indexed draw
    /// issues; `None` without statistics or pass.
    pub fn vertex_invocations(&self, name: &str) -> Option<u64> {
        self.pass_statistic(name, |s| s.vertex_invocations)
    }

    fn pass_statistic(
        &self,
        name: &str,
        statistic: impl Fn(&caustics_gpu::profiling::PassStatistics) -> u64,
    ) -> Option<u64> {
        let mut passes = self
            .count
            .passes
            .iter()
            .filter(|p| p.name == name)
            .peekable();
        passes.peek()?;
        passes.map(|p| p.statistics.as_ref().map(&statistic)).sum()
    }

    /// Fragment-shader invocations of the passes of `method` (named `<method>/...`) in
    /// the count frame; `None` without pipeline statistics.
    pub fn method_fragments(&self, method: &str) -> Option<u64> {
        self.count
            .passes
            .iter()
            .filter(|p| p.name.split('/').next() == Some(method))
            .map(|p| p.statistics.map(|s| s.fragment_invocations))
            .sum()
    }

    /// The sum of the fill counts: fragments the method shaded, as the heatmap counts them.
    pub fn fill_total(&self) -> u64 {
        self.fill.iter().map(|&c| u64::from(c)).sum()
    }

    /// Counter `name`.
    ///
    /// # Panics
    /// If the method has no such counter (the message lists those it has).
    pub fn counter(&self, name: &str) -> u64 {
        *self
            .counters
            .get(name)
            .unwrap_or_else(|| panic!("no counter {name}; counters: {:?}", self.counters))
    }
}

/// Asserts that every counter in `counters` (as `info`'s method reported them) has a
/// doc in the method's `Method::COUNTERS`, the glossary of `caustics list` and the
/// report.
///
/// # Panics
/// Naming each undocumented counter.
pub fn assert_counters_documented(info: &MethodInfo, counters: &Counters) {
    let missing: Vec<&str> = counters
        .keys()
        .map(String::as_str)
        .filter(|name| info.counter_doc(name).is_none())
        .collect();
    assert!(
        missing.is_empty(),
        "{} reports counters with no doc in its Method::COUNTERS: {}",
        info.name,
        missing.join(", ")
    );
}
