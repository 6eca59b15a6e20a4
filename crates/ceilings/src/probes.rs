//! The probes: their pipelines, what one trial records, and its work.

use caustics_gpu::{BareFrame, FrameMode, GpuContext, GpuError, PassProfiler, wgpu};

use crate::{
    COMPUTE_WGSL, CeilingsError, FILL_WGSL, OVERHEAD_PASSES, ProbeOptions, SMALL_CELL_PX, run_frame,
};

/// How a probe's figure reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeKind {
    /// Work per second: higher is better (fill, FLOPs, bytes, atomics).
    Throughput,
    /// Time per item (µs): lower is better (pass and draw overhead).
    PerItem,
}

/// One probe's measurements.
#[derive(Clone, Debug)]
pub struct ProbeResult {
    /// Stable name, e.g. `fill_blend_rgba32f_fullscreen`.
    pub name: &'static str,
    /// What it measures, in a sentence.
    pub what: &'static str,
    /// Throughput or time per item.
    pub kind: ProbeKind,
    /// Unit of the figure: e.g. `Gfragments/s`, `us/pass`.
    pub unit: &'static str,
    /// Unit of `work` (e.g. `fragments`, `FLOP`, `bytes`, `passes`).
    pub work_unit: &'static str,
    /// Work of one trial, in closed form from the probe's geometry and dispatches.
    pub work: f64,
    /// The same work counted by pipeline statistics (fragment or compute-shader
    /// invocations, times the work per invocation), where the adapter has them and
    /// the work is counted per invocation; `None` otherwise.
    pub counted_work: Option<f64>,
    /// The scale the probe was calibrated to (layers, loop trips, dispatches, draws).
    pub scale: u32,
    /// GPU time of each timed trial (ms), in order.
    pub trial_ms: Vec<f64>,
}

impl ProbeResult {
    /// The figure of one trial time: work per second in the unit's prefix
    /// (1e9 for G-units), or µs per item. The work is the counted one where there is
    /// one: fill is then in fragment-shader invocations as pipeline statistics count
    /// them (helper lanes of partly covered 2x2 quads included: twice the covered
    /// pixels for 8-pixel triangles on lavapipe), the figure every pass's
    /// `fragment_shader_invocations` is given in, so a pass reads against its
    /// ceiling in one unit.
    pub fn figure(&self, trial_ms: f64) -> f64 {
        match self.kind {
            ProbeKind::Throughput => {
                self.counted_work.unwrap_or(self.work) / (trial_ms * 1e-3) / 1e9
            }
            ProbeKind::PerItem => trial_ms * 1e3 / self.work,
        }
    }
}

type Record<'a> = Box<dyn Fn(&mut BareFrame<'_>, u32) -> Result<(), GpuError> + 'a>;

/// A probe before it runs.
struct Probe<'a> {
    name: &'static str,
    what: &'static str,
    kind: ProbeKind,
    unit: &'static str,
    work_unit: &'static str,
    /// Records one trial at a scale.
    record: Record<'a>,
    /// Work at a scale.
    work: Box<dyn Fn(u32) -> f64 + 'a>,
    /// Work per counted invocation (fragment or compute), when statistics count it.
    per_invocation: Option<(Invocations, f64)>,
    /// Largest scale (1: no calibration).
    max_scale: u32,
}

#[derive(Clone, Copy)]
enum Invocations {
    Fragment,
    Compute,
}

/// Runs the probes `options` selects on `ctx`'s adapter; `progress` hears each probe's
/// name as it starts.
pub fn measure(
    ctx: &GpuContext,
    options: &ProbeOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<ProbeResult>, CeilingsError> {
    options.validate()?;
    if !ctx.has_timestamps() {
        return Err(CeilingsError::NoTimestamps {
            adapter: ctx.summary.name.clone(),
        });
    }
    let fill = FillProbes::new(ctx, options)?;
    let compute = ComputeProbes::new(ctx, options)?;
    // Compute first, as before the cause was known: on lavapipe (Mesa 22.3.6) a
    // timestamp took its value at the next flushing command, so once a render pass had
    // run, a compute pass's beginning was taken after its first dispatch, and the FP32
    // probe (one dispatch) read a few microseconds for any loop length, the repeated-
    // dispatch probes one dispatch short. The profiler now flushes right after a
    // compute pass begins (caustics_gpu::profiling), so the order no longer matters.
    let mut probes = compute.probes();
    probes.extend(fill.probes());
    // Calibration frames, one warm-up, the trials and one count frame share a profiler.
    let mut profiler = PassProfiler::new(ctx, 2);
    let mut results = Vec::new();
    for probe in probes.iter().filter(|p| options.selects(p.name)) {
        progress(probe.name);
        results.push(run_probe(ctx, &mut profiler, options, probe)?);
    }
    Ok(results)
}

fn span_ms(profiler: &PassProfiler, sample: &caustics_gpu::FrameSample) -> Option<f64> {
    let first = sample.passes.first()?.ticks?;
    let last = sample.passes.last()?.ticks?;
    (last.1 >= first.0).then(|| profiler.ticks_to_ms(last.1 - first.0))
}

fn run_probe(
    ctx: &GpuContext,
    profiler: &mut PassProfiler,
    options: &ProbeOptions,
    probe: &Probe<'_>,
) -> Result<ProbeResult, CeilingsError> {
    let no_timings = || CeilingsError::NoTimings {
        probe: probe.name.to_owned(),
    };
    let timed = |profiler: &mut PassProfiler, scale: u32| -> Result<Option<f64>, CeilingsError> {
        let sample = run_frame(ctx, profiler, FrameMode::Timed, &|f| {
            (probe.record)(f, scale)
        })?;
        Ok(span_ms(profiler, &sample))
    };
    // Warm-up (pipeline compilation, first touch of the buffers), then scale up until
    // a trial takes target_ms: at least doubling, at most 16x per step.
    let mut scale = 1u32;
    timed(profiler, scale)?;
    while scale < probe.max_scale {
        let ms = timed(profiler, scale)?.ok_or_else(no_timings)?;
        if ms >= options.target_ms {
            break;
        }
        let factor = (options.target_ms / ms.max(1e-6)).ceil().clamp(2.0, 16.0) as u32;
        scale = scale.saturating_mul(factor).min(probe.max_scale);
    }
    timed(profiler, scale)?;
    let mut trial_ms = Vec::with_capacity(options.trials as usize);
    for _ in 0..options.trials {
        if let Some(ms) = timed(profiler, scale)? {
            trial_ms.push(ms);
        }
    }
    if trial_ms.is_empty() {
        return Err(no_timings());
    }
    let counted_work = match probe.per_invocation {
        Some((which, per)) if ctx.has_pipeline_statistics() => {
            let sample = run_frame(ctx, profiler, FrameMode::Count, &|f| {
                (probe.record)(f, scale)
            })?;
            let invocations: u64 = sample
                .passes
                .iter()
                .filter_map(|p| p.statistics)
                .map(|s| match which {
                    Invocations::Fragment => s.fragment_invocations,
                    Invocations::Compute => s.compute_invocations,
                })
                .sum();
            Some(invocations as f64 * per)
        }
        _ => None,
    };
    Ok(ProbeResult {
        name: probe.name,
        what: probe.what,
        kind: probe.kind,
        unit: probe.unit,
        work_unit: probe.work_unit,
        work: (probe.work)(scale),
        counted_work,
        scale,
        trial_ms,
    })
}

/// The fill probes' targets and pipelines.
struct FillProbes<'c> {
    width: u32,
    height: u32,
    params: wgpu::Buffer,
    rgba32f: wgpu::TextureView,
    rgba16f: wgpu::TextureView,
    // Kept alive beside the views: the ledger's hold on their bytes.
    _reservations: Vec<caustics_gpu::limits::Reservation>,
    module: wgpu::ShaderModule,
    ctx: &'c GpuContext,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FillParams {
    target_px: [f32; 2],
    cell_px: f32,
    cells_x: u32,
}

const ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

impl<'c> FillProbes<'c> {
    fn new(ctx: &'c GpuContext, options: &ProbeOptions) -> Result<Self, CeilingsError> {
        let (width, height) = (options.width, options.height);
        let mut reservations = Vec::new();
        let mut target = |format: wgpu::TextureFormat, bytes_per_px: u64| {
            let bytes = u64::from(width) * u64::from(height) * bytes_per_px;
            reservations.push(ctx.memory.reserve(
                "ceilings fill target",
                bytes,
                "lower --width/--height",
            )?);
            ctx.limits.texture(
                "ceilings fill target",
                width,
                height,
                "lower --width/--height",
            )?;
            Ok::<_, GpuError>(
                ctx.device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some("ceilings fill target"),
                        size: wgpu::Extent3d {
                            width,
                            height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                        view_formats: &[],
                    })
                    .create_view(&wgpu::TextureViewDescriptor::default()),
            )
        };
        let rgba32f = target(wgpu::TextureFormat::Rgba32Float, 16)?;
        let rgba16f = target(wgpu::TextureFormat::Rgba16Float, 8)?;
        let params = caustics_gpu::buffers::uniform_buffer(
            &ctx.device,
            "ceilings fill params",
            &FillParams {
                target_px: [width as f32, height as f32],
                cell_px: SMALL_CELL_PX as f32,
                cells_x: width / SMALL_CELL_PX,
            },
        );
        let module = ctx.checked("ceilings fill.wgsl", || {
            caustics_gpu::shader::module(&ctx.device, "ceilings fill.wgsl", FILL_WGSL)
        })?;
        Ok(Self {
            width,
            height,
            params,
            rgba32f,
            rgba16f,
            _reservations: reservations,
            module,
            ctx,
        })
    }

    fn pipeline(
        &self,
        vertex: &str,
        format: wgpu::TextureFormat,
        blend: Option<wgpu::BlendState>,
    ) -> Result<(wgpu::RenderPipeline, Option<wgpu::BindGroup>), GpuError> {
        let ctx = self.ctx;
        let pipeline = ctx.checked("ceilings fill pipeline", || {
            ctx.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(vertex),
                    layout: None,
                    vertex: wgpu::VertexState {
                        module: &self.module,
                        entry_point: Some(vertex),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &self.module,
                        entry_point: Some("fs_fill"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format,
                            blend,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })?;
        // vs_small reads the tiling's parameters; the others bind nothing.
        let group = (vertex == "vs_small").then(|| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ceilings fill params"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                }],
            })
        });
        Ok((pipeline, group))
    }

    fn probes(&self) -> Vec<Probe<'_>> {
        let pixels = f64::from(self.width) * f64::from(self.height);
        let small_vertices = 6 * (self.width / SMALL_CELL_PX) * (self.height / SMALL_CELL_PX);
        let mut out = Vec::new();
        type Variant = (&'static str, &'static str, wgpu::TextureFormat, bool, bool);
        let variants: [Variant; 5] = [
            (
                "fill_blend_rgba32f_fullscreen",
                "full-screen triangles additively blended into RGBA32F (the method targets' format)",
                wgpu::TextureFormat::Rgba32Float,
                true,
                false,
            ),
            (
                "fill_blend_rgba16f_fullscreen",
                "full-screen triangles additively blended into RGBA16F",
                wgpu::TextureFormat::Rgba16Float,
                true,
                false,
            ),
            (
                "fill_blend_rgba32f_small",
                "8-pixel triangles tiling the target, additively blended into RGBA32F (caustic triangles, small hulls)",
                wgpu::TextureFormat::Rgba32Float,
                true,
                true,
            ),
            (
                "fill_blend_rgba16f_small",
                "8-pixel triangles tiling the target, additively blended into RGBA16F",
                wgpu::TextureFormat::Rgba16Float,
                true,
                true,
            ),
            (
                "fill_unblended_rgba32f_fullscreen",
                "full-screen triangles written to RGBA32F without blending",
                wgpu::TextureFormat::Rgba32Float,
                false,
                false,
            ),
        ];
        for (name, what, format, blended, small) in variants {
            let vertex = if small { "vs_small" } else { "vs_fullscreen" };
            let view = if format == wgpu::TextureFormat::Rgba32Float {
                &self.rgba32f
            } else {
                &self.rgba16f
            };
            let built = self.pipeline(vertex, format, blended.then_some(ADDITIVE));
            let vertices = if small { small_vertices } else { 3 };
            out.push(Probe {
                name,
                what,
                kind: ProbeKind::Throughput,
                unit: "Gfragments/s",
                work_unit: "fragments",
                record: Box::new(move |frame: &mut BareFrame<'_>, layers: u32| {
                    let (pipeline, group) = built.as_ref().map_err(clone_error)?;
                    let mut pass = color_pass(frame, name, view, wgpu::LoadOp::Load)?;
                    pass.set_pipeline(pipeline);
                    if let Some(group) = group {
                        pass.set_bind_group(0, group, &[]);
                    }
                    pass.draw(0..vertices, 0..layers);
                    Ok(())
                }),
                work: Box::new(move |layers| pixels * f64::from(layers)),
                per_invocation: Some((Invocations::Fragment, 1.0)),
                // Small triangles start at one layer (a full tiling); full-screen
                // layers are cheap to record, so more of them are allowed.
                max_scale: if small { 1 << 12 } else { 1 << 16 },
            });
        }
        let empty = self.pipeline("vs_empty", wgpu::TextureFormat::Rgba32Float, None);
        let view = &self.rgba32f;
        out.push(Probe {
            name: "overhead_draw",
            what: "draws of one zero-area triangle in one render pass: what a draw costs by itself",
            kind: ProbeKind::PerItem,
            unit: "us/draw",
            work_unit: "draws",
            record: Box::new(move |frame: &mut BareFrame<'_>, scale: u32| {
                let (pipeline, _) = empty.as_ref().map_err(clone_error)?;
                let mut pass = color_pass(frame, "overhead_draw", view, wgpu::LoadOp::Load)?;
                pass.set_pipeline(pipeline);
                for d in 0..64 * scale {
                    pass.draw(3 * d..3 * d + 3, 0..1);
                }
                Ok(())
            }),
            work: Box::new(|scale| 64.0 * f64::from(scale)),
            per_invocation: None,
            max_scale: 1 << 10,
        });
        let view = &self.rgba32f;
        out.push(Probe {
            name: "bandwidth_clear",
            what: "render passes that clear the RGBA32F target and draw nothing, first start to last end: bytes written per second (what a pass's cleared attachments cost)",
            kind: ProbeKind::Throughput,
            unit: "GB/s",
            work_unit: "bytes",
            record: Box::new(move |frame: &mut BareFrame<'_>, passes: u32| {
                for _ in 0..passes {
                    let clear = wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT);
                    color_pass(frame, "bandwidth_clear", view, clear)?;
                }
                Ok(())
            }),
            work: Box::new(move |passes| pixels * 16.0 * f64::from(passes)),
            per_invocation: None,
            // One profiled pass per clear: at most a frame's passes.
            max_scale: OVERHEAD_PASSES,
        });
        out
    }
}

/// A pipeline error is built once and reported by every trial that needs it.
fn clone_error(e: &GpuError) -> GpuError {
    GpuError::Validation {
        kind: "validation",
        what: "ceilings pipeline".into(),
        message: e.to_string(),
    }
}

/// Opens a probe's render pass on `view`. The fill probes load the target, keeping
/// what earlier trials blended, so a trial's time is its draws alone (the layer values
/// are small enough that thousands of trials stay finite in half floats); the clear
/// probe clears it.
fn color_pass<'f>(
    frame: &'f mut BareFrame<'_>,
    name: &str,
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> Result<caustics_gpu::ProfiledRenderPass<'f>, GpuError> {
    let attachments = [Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        },
    })];
    frame.render_pass(
        name,
        wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &attachments,
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        },
    )
}

/// The compute probes' buffers and pipelines.
struct ComputeProbes<'c> {
    ctx: &'c GpuContext,
    elements: u32,
    params: wgpu::Buffer,
    source: wgpu::Buffer,
    destination: wgpu::Buffer,
    counters: wgpu::Buffer,
    _reservations: Vec<caustics_gpu::limits::Reservation>,
    module: wgpu::ShaderModule,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ComputeParams {
    elements: u32,
    iterations: u32,
    stride: u32,
    counter_mask: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

/// Invocations of the FP32 and atomics probes per dispatch (1,024 workgroups of 256).
const COMPUTE_INVOCATIONS: u32 = 1024 * 256;
/// FMA loop trips of the FP32 probe at scale 1.
const FP32_ITERATIONS: u32 = 16;
/// FLOPs per loop trip: 4 vec4 FMAs.
const FLOPS_PER_ITERATION: f64 = 32.0;
const ATOMIC_COUNTERS: u32 = 1 << 16;
const ATOMICS_PER_INVOCATION: f64 = 8.0;
const GATHER_STRIDE: u32 = 33;
const WORKGROUP: u32 = 256;

impl<'c> ComputeProbes<'c> {
    fn new(ctx: &'c GpuContext, options: &ProbeOptions) -> Result<Self, CeilingsError> {
        // A power of two of 16-byte elements within the device's largest binding.
        let largest = ctx
            .limits
            .storage_elements(16)
            .min(options.bandwidth_bytes / 16);
        let elements = 1u32 << (63 - largest.max(1).leading_zeros()).min(31);
        let bytes = u64::from(elements) * 16;
        let raise = "lower --bandwidth-mib";
        let mut reservations = vec![
            ctx.reserve_storage("ceilings bandwidth source", bytes, raise)?,
            ctx.reserve_storage("ceilings bandwidth destination", bytes, raise)?,
        ];
        let counter_bytes = u64::from(ATOMIC_COUNTERS) * 4;
        reservations.push(ctx.reserve_storage("ceilings atomic counters", counter_bytes, raise)?);
        let storage =
            |label, size| caustics_gpu::buffers::storage_buffer(&ctx.device, label, size, false);
        // Writable: the FP32 probe writes its loop trips before each trial.
        let params = wgpu::util::DeviceExt::create_buffer_init(
            &ctx.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("ceilings compute params"),
                contents: bytemuck::bytes_of(&ComputeParams {
                    elements,
                    iterations: FP32_ITERATIONS,
                    stride: GATHER_STRIDE,
                    counter_mask: ATOMIC_COUNTERS - 1,
                    _pad0: 0,
                    _pad1: 0,
                    _pad2: 0,
                    _pad3: 0,
                }),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            },
        );
        let module = ctx.checked("ceilings compute.wgsl", || {
            caustics_gpu::shader::module(&ctx.device, "ceilings compute.wgsl", COMPUTE_WGSL)
        })?;
        Ok(Self {
            ctx,
            elements,
            params,
            source: storage("ceilings bandwidth source", bytes),
            destination: storage("ceilings bandwidth destination", bytes),
            counters: storage("ceilings atomic counters", counter_bytes),
            _reservations: reservations,
            module,
        })
    }

    /// A kernel's pipeline (layout from the shader: only the bindings it uses) and its
    /// bind group.
    fn kernel(
        &self,
        entry: &str,
        bindings: &[u32],
    ) -> Result<(wgpu::ComputePipeline, Option<wgpu::BindGroup>), GpuError> {
        let ctx = self.ctx;
        let pipeline = ctx.checked("ceilings compute pipeline", || {
            ctx.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: None,
                    module: &self.module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
        })?;
        let buffer = |b: u32| match b {
            0 => &self.params,
            1 => &self.source,
            2 => &self.destination,
            _ => &self.counters,
        };
        let entries: Vec<_> = bindings
            .iter()
            .map(|&b| wgpu::BindGroupEntry {
                binding: b,
                resource: buffer(b).as_entire_binding(),
            })
            .collect();
        let group = (!entries.is_empty()).then(|| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        });
        Ok((pipeline, group))
    }

    fn probes(&self) -> Vec<Probe<'_>> {
        let mut out = Vec::new();
        let element_groups = groups_2d(self.elements / WORKGROUP);
        let invocation_groups = groups_2d(COMPUTE_INVOCATIONS / WORKGROUP);
        let elements = f64::from(self.elements);
        let invocations = f64::from(COMPUTE_INVOCATIONS);

        // FP32: the scale multiplies the loop trips (one dispatch), written into the
        // uniform before each frame.
        let fp32 = self.kernel("fp32", &[0, 2]);
        let params = &self.params;
        let queue = &self.ctx.queue;
        out.push(Probe {
            name: "compute_fp32",
            what: "independent vec4 FMA chains, 32 FLOPs per loop trip",
            kind: ProbeKind::Throughput,
            unit: "GFLOP/s",
            work_unit: "FLOP",
            record: Box::new(move |frame: &mut BareFrame<'_>, scale: u32| {
                let (pipeline, group) = fp32.as_ref().map_err(clone_error)?;
                queue.write_buffer(params, 4, bytemuck::bytes_of(&(FP32_ITERATIONS * scale)));
                let mut pass = frame.compute_pass("compute_fp32")?;
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group.as_ref(), &[]);
                pass.dispatch_workgroups(invocation_groups[0], invocation_groups[1], 1);
                Ok(())
            }),
            work: Box::new(move |scale| {
                invocations * f64::from(FP32_ITERATIONS * scale) * FLOPS_PER_ITERATION
            }),
            per_invocation: None,
            max_scale: 1 << 14,
        });
        for (name, what, entry) in [
            (
                "bandwidth_copy",
                "sequential vec4 copy between two storage buffers (bytes read + written)",
                "copy",
            ),
            (
                "bandwidth_strided",
                "vec4 gather 528 bytes apart into sequential writes (useful bytes read + written)",
                "strided",
            ),
        ] {
            let kernel = self.kernel(entry, &[0, 1, 2]);
            out.push(Probe {
                name,
                what,
                kind: ProbeKind::Throughput,
                unit: "GB/s",
                work_unit: "bytes",
                record: Box::new(move |frame: &mut BareFrame<'_>, scale: u32| {
                    let (pipeline, group) = kernel.as_ref().map_err(clone_error)?;
                    let mut pass = frame.compute_pass(name)?;
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, group.as_ref(), &[]);
                    for _ in 0..scale {
                        pass.dispatch_workgroups(element_groups[0], element_groups[1], 1);
                    }
                    Ok(())
                }),
                work: Box::new(move |scale| elements * 32.0 * f64::from(scale)),
                per_invocation: Some((Invocations::Compute, 32.0)),
                max_scale: 1 << 10,
            });
        }
        let atomics = self.kernel("atomics", &[0, 3]);
        out.push(Probe {
            name: "atomics_storage",
            what: "atomicAdd on 65,536 u32 storage counters at hashed addresses, 8 per invocation",
            kind: ProbeKind::Throughput,
            unit: "Gatomics/s",
            work_unit: "atomics",
            record: Box::new(move |frame: &mut BareFrame<'_>, scale: u32| {
                let (pipeline, group) = atomics.as_ref().map_err(clone_error)?;
                let mut pass = frame.compute_pass("atomics_storage")?;
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group.as_ref(), &[]);
                for _ in 0..scale {
                    pass.dispatch_workgroups(invocation_groups[0], invocation_groups[1], 1);
                }
                Ok(())
            }),
            work: Box::new(move |scale| invocations * ATOMICS_PER_INVOCATION * f64::from(scale)),
            per_invocation: Some((Invocations::Compute, ATOMICS_PER_INVOCATION)),
            max_scale: 1 << 10,
        });
        let empty = self.kernel("empty", &[]);
        out.push(Probe {
            name: "overhead_pass",
            what: "compute passes of one empty one-invocation dispatch each, first start to last end: what a pass costs by itself",
            kind: ProbeKind::PerItem,
            unit: "us/pass",
            work_unit: "passes",
            record: Box::new(move |frame: &mut BareFrame<'_>, _scale: u32| {
                let (pipeline, _) = empty.as_ref().map_err(clone_error)?;
                for _ in 0..OVERHEAD_PASSES {
                    let mut pass = frame.compute_pass("overhead_pass")?;
                    pass.set_pipeline(pipeline);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                Ok(())
            }),
            work: Box::new(|_| f64::from(OVERHEAD_PASSES)),
            per_invocation: None,
            max_scale: 1,
        });
        out
    }
}

/// Workgroups of a 1D dispatch as (x, y), x at most 32,768 (both powers of two here).
fn groups_2d(groups: u32) -> [u32; 2] {
    let x = groups.clamp(1, 1 << 15);
    [x, groups.div_ceil(x).max(1)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_gpu::assert_wgsl_layout;

    #[test]
    fn probe_uniforms_match_their_wgsl() {
        assert_wgsl_layout!(
            FILL_WGSL,
            FillParams {
                target_px,
                cell_px,
                cells_x
            }
        );
        assert_wgsl_layout!(
            COMPUTE_WGSL,
            ComputeParams {
                elements,
                iterations,
                stride,
                counter_mask,
                _pad0,
                _pad1,
                _pad2,
                _pad3
            }
        );
    }
}
