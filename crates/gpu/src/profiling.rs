//! Per-pass instrumentation owned by the harness, so every method is measured alike:
//! GPU timestamps around each named pass (timed frames) and pipeline statistics
//! (fragment-shader invocations, primitives, compute invocations) per pass (count
//! frames). Queries are resolved in a submission of their own after the frame's,
//! into one results buffer that is read back once after all frames.
//!
//! A compute pass also writes a timestamp of its own right after its beginning, into a
//! set that is never read ([`PassProfiler::flush_timestamp_set`]). On lavapipe a
//! timestamp takes its value when the next command that flushes runs (a timestamp
//! write, a barrier), not when it is written: a compute pass's beginning was otherwise
//! taken after its first dispatch had run, so the pass's time lacked that dispatch
//! (a pass of one dispatch read 0 ms; measured: one, two, three dispatches of 30 ms
//! read 0.0, 32.4, 59.7 ms). Render passes are not affected (their beginning is taken
//! as their draws start), nor GPUs that write timestamps in the pipeline.
//!
//! Why not `wgpu-profiler`: it covers timer queries only, and we need timestamps and
//! pipeline statistics behind the same per-pass scope so that the figures of a pass
//! line up by name; it also resolves inside the frame's own encoder.

use crate::{GpuContext, GpuError};

/// Most passes one frame may open: every light adds its shadow and direct passes and
/// the methods' per-light passes, and a scene may bring 64 representative lights per
/// extended light (caustic triangles under 64 point lights open over 1,024: six cube
/// faces each). Two timestamps each fill wgpu's 4,096 queries per set.
pub const MAX_PASSES_PER_FRAME: u32 = 2048;
/// Values of one pipeline-statistics query, in `STATISTICS` bit order.
const STATS_PER_QUERY: u64 = 5;
/// The statistics gathered (results come back in this bit order).
pub const STATISTICS: wgpu::PipelineStatisticsTypes =
    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_INVOCATIONS)
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_PRIMITIVES_OUT)
        .union(wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS)
        .union(wgpu::PipelineStatisticsTypes::COMPUTE_SHADER_INVOCATIONS);

/// Passes per frame the results buffers are first sized for; a frame with more grows
/// them (doubling, contents copied), so a 20,000-frame run of a one-light scene does
/// not hold [`MAX_PASSES_PER_FRAME`] passes' room per frame.
const INITIAL_PASSES_PER_FRAME: u64 = 64;
/// Bytes of a timestamp pair and of one statistics query.
const TS_BYTES_PER_PASS: u64 = 2 * 8;
const STATS_BYTES_PER_PASS: u64 = STATS_PER_QUERY * 8;
/// `resolve_query_set` writes at multiples of this offset.
const RESOLVE_ALIGNMENT: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

/// What a frame measures (DESIGN "Measuring honestly": time with counting off,
/// count with it on, in separate frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameMode {
    /// Timestamps on; pipeline statistics and fill counting off.
    Timed,
    /// Pipeline statistics and per-pixel fill counting on; no timestamps.
    Count,
    /// A scoring sub-frame (crates/gpu/src/scoring.rs): nothing measured, nothing
    /// counted; only its image is used.
    Score,
}

/// Pipeline statistics of one pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassStatistics {
    /// Vertex shader invocations.
    pub vertex_invocations: u64,
    /// Primitives that entered clipping.
    pub clipper_invocations: u64,
    /// Primitives that left clipping (rasterized).
    pub primitives_out: u64,
    /// Fragment shader invocations.
    pub fragment_invocations: u64,
    /// Compute shader invocations.
    pub compute_invocations: u64,
}

/// What a pass writes, as far as its roofline needs it (which fill ceiling applies).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassShape {
    /// A compute pass.
    Compute,
    /// A render pass.
    Render {
        /// Format of its first colour attachment; `None` for a depth-only pass.
        color_format: Option<wgpu::TextureFormat>,
        /// Whether that target is written with blending: known for passes built with
        /// the pass layer ([`crate::pass::RasterPass`]), `None` for a render pass opened
        /// directly (its pipelines are set afterwards, out of the profiler's sight).
        blended: Option<bool>,
        /// Bytes of the attachments the pass clears (every texel written however few
        /// fragments it draws).
        cleared_bytes: u64,
    },
}

/// One pass of one measured frame.
#[derive(Clone, Debug)]
pub struct PassSample {
    /// Pass name, `"<owner>/<pass>"`.
    pub name: String,
    /// Compute or render, and its target.
    pub shape: PassShape,
    /// GPU time (ms) from the pass's timestamps; `None` when the adapter has no
    /// timestamps, or the sample was rejected (zero or non-monotonic timestamps).
    pub gpu_ms: Option<f64>,
    /// Raw begin/end ticks, for the frame span.
    pub ticks: Option<(u64, u64)>,
    /// Pipeline statistics (count frames only, when supported).
    pub statistics: Option<PassStatistics>,
}

/// Everything measured in one frame.
#[derive(Clone, Debug)]
pub struct FrameSample {
    /// How the frame was run.
    pub mode: FrameMode,
    /// Its passes, in recording order.
    pub passes: Vec<PassSample>,
    /// CPU wall time from the start of recording to the end of the GPU work (ms).
    pub wall_ms: f64,
    /// Timestamps rejected in this frame (zero or end before begin).
    pub rejected_timestamps: u32,
}

struct FrameRecord {
    mode: FrameMode,
    passes: Vec<(String, PassShape)>,
    wall_ms: f64,
    /// Where its queries were resolved in the results buffer of its mode (bytes).
    results_offset: u64,
}

/// A results buffer that frames resolve into one after another, each at the next
/// aligned offset; it grows when a frame does not fit.
struct Results {
    label: &'static str,
    buffer: wgpu::Buffer,
    /// Bytes written so far (aligned).
    used: u64,
}

impl Results {
    fn new(device: &wgpu::Device, label: &'static str, size: u64) -> Self {
        Self {
            label,
            buffer: Self::buffer(device, label, size),
            used: 0,
        }
    }

    fn buffer(device: &wgpu::Device, label: &'static str, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size
                .max(RESOLVE_ALIGNMENT)
                .next_multiple_of(RESOLVE_ALIGNMENT),
            usage: wgpu::BufferUsages::QUERY_RESOLVE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Room for `bytes` more: the offset to resolve at. Grows the buffer (at least
    /// doubling, the results so far copied in `encoder`) when they do not fit.
    fn reserve(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        bytes: u64,
    ) -> u64 {
        let offset = self.used;
        let needed = offset + bytes;
        if needed > self.buffer.size() {
            let grown = Self::buffer(device, self.label, needed.max(2 * self.buffer.size()));
            if offset > 0 {
                encoder.copy_buffer_to_buffer(&self.buffer, 0, &grown, 0, offset);
            }
            self.buffer = grown;
        }
        self.used = needed.next_multiple_of(RESOLVE_ALIGNMENT);
        offset
    }
}

/// Query sets and result buffers for up to `max_frames` frames.
pub struct PassProfiler {
    timestamps: Option<wgpu::QuerySet>,
    statistics: Option<wgpu::QuerySet>,
    ts_results: Option<Results>,
    stats_results: Option<Results>,
    /// Timestamps written right after a compute pass begins and never read: writing
    /// one makes lavapipe take the pass's beginning before its first dispatch.
    flush_timestamps: Option<wgpu::QuerySet>,
    period_ns: f64,
    max_frames: u32,
    frames: Vec<FrameRecord>,
    open: Option<FrameRecord>,
}

impl PassProfiler {
    /// Allocates queries for up to `max_frames` frames (timed and count frames together).
    pub fn new(ctx: &GpuContext, max_frames: u32) -> Self {
        let device = &ctx.device;
        let timestamps = ctx.has_timestamps().then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_PASSES_PER_FRAME * 2,
            })
        });
        let flush_timestamps = ctx.has_timestamps_inside_passes().then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass beginning flushes"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_PASSES_PER_FRAME,
            })
        });
        let statistics = ctx.has_pipeline_statistics().then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass statistics"),
                ty: wgpu::QueryType::PipelineStatistics(STATISTICS),
                count: MAX_PASSES_PER_FRAME,
            })
        });
        let results = |label: &'static str, per_pass: u64| {
            let per_frame =
                (INITIAL_PASSES_PER_FRAME * per_pass).next_multiple_of(RESOLVE_ALIGNMENT);
            Results::new(device, label, per_frame * u64::from(max_frames.max(1)))
        };
        let ts_results = timestamps
            .as_ref()
            .map(|_| results("timestamp results", TS_BYTES_PER_PASS));
        let stats_results = statistics
            .as_ref()
            .map(|_| results("statistics results", STATS_BYTES_PER_PASS));
        Self {
            timestamps,
            statistics,
            ts_results,
            stats_results,
            flush_timestamps,
            period_ns: ctx.queue.get_timestamp_period() as f64,
            max_frames,
            frames: Vec::new(),
            open: None,
        }
    }

    /// A profiler that takes no queries at all, for [`FrameMode::Score`] frames: passes
    /// are still opened by name (so methods record exactly as in measured frames), but
    /// no query set or results buffer is allocated.
    pub fn unmeasured(max_frames: u32) -> Self {
        Self {
            timestamps: None,
            statistics: None,
            ts_results: None,
            stats_results: None,
            flush_timestamps: None,
            period_ns: 1.0,
            max_frames,
            frames: Vec::new(),
            open: None,
        }
    }

    /// Whether timestamps are taken at all.
    pub fn has_timestamps(&self) -> bool {
        self.timestamps.is_some()
    }

    pub(crate) fn begin_frame(&mut self, mode: FrameMode) -> Result<(), GpuError> {
        if self.frames.len() as u32 >= self.max_frames {
            return Err(GpuError::ProfilerCapacity(format!(
                "more than {} frames",
                self.max_frames
            )));
        }
        self.open = Some(FrameRecord {
            mode,
            passes: Vec::new(),
            wall_ms: 0.0,
            results_offset: 0,
        });
        Ok(())
    }

    /// Registers a pass; returns its index in the frame.
    pub(crate) fn open_pass(
        &mut self,
        name: &str,
        shape: PassShape,
    ) -> Result<(u32, FrameMode), GpuError> {
        let rec = self
            .open
            .as_mut()
            .ok_or_else(|| GpuError::ProfilerCapacity("pass opened outside a frame".into()))?;
        if rec.passes.len() as u32 >= MAX_PASSES_PER_FRAME {
            return Err(GpuError::ProfilerCapacity(format!(
                "more than {MAX_PASSES_PER_FRAME} passes in a frame"
            )));
        }
        rec.passes.push((name.to_owned(), shape));
        Ok((rec.passes.len() as u32 - 1, rec.mode))
    }

    pub(crate) fn timestamp_set(&self, mode: FrameMode) -> Option<&wgpu::QuerySet> {
        (mode == FrameMode::Timed)
            .then_some(self.timestamps.as_ref())
            .flatten()
    }

    /// Where a timed compute pass writes its flushing timestamp (index: the pass's).
    pub(crate) fn flush_timestamp_set(&self, mode: FrameMode) -> Option<&wgpu::QuerySet> {
        (mode == FrameMode::Timed)
            .then_some(self.flush_timestamps.as_ref())
            .flatten()
    }

    pub(crate) fn statistics_set(&self, mode: FrameMode) -> Option<&wgpu::QuerySet> {
        (mode == FrameMode::Count)
            .then_some(self.statistics.as_ref())
            .flatten()
    }

    /// Resolves the open frame's queries into the results buffers, in an encoder of its
    /// own (submitted after the frame's), and closes the frame.
    pub(crate) fn resolve_frame(&mut self, ctx: &GpuContext, wall_ms: f64) {
        let Some(mut rec) = self.open.take() else {
            return;
        };
        rec.wall_ms = wall_ms;
        let n = rec.passes.len() as u32;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("resolve queries"),
            });
        if n > 0 {
            if let (Some(set), Some(results), FrameMode::Timed) =
                (&self.timestamps, &mut self.ts_results, rec.mode)
            {
                let offset =
                    results.reserve(&ctx.device, &mut encoder, u64::from(n) * TS_BYTES_PER_PASS);
                encoder.resolve_query_set(set, 0..2 * n, &results.buffer, offset);
                rec.results_offset = offset;
            }
            if let (Some(set), Some(results), FrameMode::Count) =
                (&self.statistics, &mut self.stats_results, rec.mode)
            {
                let offset = results.reserve(
                    &ctx.device,
                    &mut encoder,
                    u64::from(n) * STATS_BYTES_PER_PASS,
                );
                encoder.resolve_query_set(set, 0..n, &results.buffer, offset);
                rec.results_offset = offset;
            }
        }
        ctx.queue.submit([encoder.finish()]);
        self.frames.push(rec);
    }

    /// Reads all results back (once, after the measured frames) and clears the profiler.
    pub fn collect(&mut self, ctx: &GpuContext) -> Result<Vec<FrameSample>, GpuError> {
        let frames = std::mem::take(&mut self.frames);
        let read = |results: &mut Option<Results>, what: &str| match results {
            Some(r) if r.used > 0 => {
                let values = crate::readback::read_buffer_u64(ctx, &r.buffer, r.used, what);
                r.used = 0;
                values.map(Some)
            }
            _ => Ok(None),
        };
        let ts = read(&mut self.ts_results, "timestamps")?;
        let st = read(&mut self.stats_results, "pipeline statistics")?;
        let mut out = Vec::with_capacity(frames.len());
        for rec in frames {
            let first = (rec.results_offset / 8) as usize;
            let mut rejected = 0;
            let passes = rec
                .passes
                .into_iter()
                .enumerate()
                .map(|(p, (name, shape))| {
                    let mut sample = PassSample {
                        name,
                        shape,
                        gpu_ms: None,
                        ticks: None,
                        statistics: None,
                    };
                    if let (Some(ts), FrameMode::Timed) = (&ts, rec.mode) {
                        let begin = ts[first + 2 * p];
                        let end = ts[first + 2 * p + 1];
                        // Zero means "never written"; end < begin happens on some drivers
                        // across power-state changes. Both are rejected, never reported as 0.
                        // end == begin is a pass shorter than one tick, and is kept.
                        if begin != 0 && end >= begin {
                            sample.gpu_ms = Some((end - begin) as f64 * self.period_ns * 1e-6);
                            sample.ticks = Some((begin, end));
                        } else {
                            rejected += 1;
                        }
                    }
                    if let (Some(st), FrameMode::Count) = (&st, rec.mode) {
                        let b = first + p * STATS_PER_QUERY as usize;
                        sample.statistics = Some(PassStatistics {
                            vertex_invocations: st[b],
                            clipper_invocations: st[b + 1],
                            primitives_out: st[b + 2],
                            fragment_invocations: st[b + 3],
                            compute_invocations: st[b + 4],
                        });
                    }
                    sample
                })
                .collect();
            out.push(FrameSample {
                mode: rec.mode,
                passes,
                wall_ms: rec.wall_ms,
                rejected_timestamps: rejected,
            });
        }
        Ok(out)
    }

    /// Ticks → milliseconds.
    pub fn ticks_to_ms(&self, ticks: u64) -> f64 {
        ticks as f64 * self.period_ns * 1e-6
    }
}
