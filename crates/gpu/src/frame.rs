//! One frame being recorded: the encoder, the profiler scopes and the frame's mode.
//! Every pass of the base renderer and of a method is opened through
//! [`Frame::render_pass`] or [`Frame::compute_pass`], which wrap it in timestamps
//! (timed frames) or pipeline statistics (count frames).

use std::ops::{Deref, DerefMut};
use std::time::Instant;

use crate::profiling::{FrameMode, PassProfiler, PassShape};
use crate::renderer::Renderer;
use crate::{GpuContext, GpuError};

/// A frame under construction.
pub struct Frame<'a> {
    /// The frame's command encoder (one submission per frame).
    pub encoder: wgpu::CommandEncoder,
    /// Timed or count frame.
    pub mode: FrameMode,
    /// The shared resources: scene, G-buffers, targets, group-0 bind group.
    pub renderer: &'a Renderer,
    reuses_light_side: bool,
    profiler: &'a mut PassProfiler,
    started: Instant,
}

/// A render pass that ends its pipeline-statistics query when dropped.
pub struct ProfiledRenderPass<'e> {
    pass: wgpu::RenderPass<'e>,
    statistics: bool,
}

impl<'e> Deref for ProfiledRenderPass<'e> {
    type Target = wgpu::RenderPass<'e>;
    fn deref(&self) -> &Self::Target {
        &self.pass
    }
}
impl DerefMut for ProfiledRenderPass<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.pass
    }
}
impl Drop for ProfiledRenderPass<'_> {
    fn drop(&mut self) {
        if self.statistics {
            self.pass.end_pipeline_statistics_query();
        }
    }
}

/// A compute pass that ends its pipeline-statistics query when dropped.
pub struct ProfiledComputePass<'e> {
    pass: wgpu::ComputePass<'e>,
    statistics: bool,
}

impl<'e> Deref for ProfiledComputePass<'e> {
    type Target = wgpu::ComputePass<'e>;
    fn deref(&self) -> &Self::Target {
        &self.pass
    }
}
impl DerefMut for ProfiledComputePass<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.pass
    }
}
impl Drop for ProfiledComputePass<'_> {
    fn drop(&mut self) {
        if self.statistics {
            self.pass.end_pipeline_statistics_query();
        }
    }
}

impl<'a> Frame<'a> {
    pub(crate) fn new(
        renderer: &'a Renderer,
        profiler: &'a mut PassProfiler,
        mode: FrameMode,
        reuses_light_side: bool,
    ) -> Result<Self, GpuError> {
        profiler.begin_frame(mode)?;
        let encoder =
            renderer
                .ctx_device()
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
        Ok(Self {
            encoder,
            mode,
            renderer,
            reuses_light_side,
            profiler,
            started: Instant::now(),
        })
    }

    /// Whether fill-rate counting pipelines should be used in this frame.
    pub fn counting(&self) -> bool {
        self.mode == FrameMode::Count
    }

    /// Whether this frame reuses the light-side work of the frame before it: a scoring
    /// sub-frame ([`Renderer::begin_scoring_subframe`]) after the scoring frame's whole
    /// frame at the pixel centre, where only the camera moved (by under a pixel). A
    /// method then records only its camera-side passes (those that read the camera
    /// G-buffer or write camera-resolution targets) and keeps the buffers and textures
    /// its light-side passes (photon tracing, beam generation, wavefront tracing,
    /// light-space splats) filled in the previous frame. Never true in timed or count
    /// frames: what is measured is always a whole frame.
    pub fn reuses_light_side(&self) -> bool {
        self.reuses_light_side
    }

    /// Opens a named, profiled render pass. `name` is `"<owner>/<pass>"`, e.g.
    /// "wavefront/splat". The descriptor's `timestamp_writes` is set here.
    pub fn render_pass(
        &mut self,
        name: &str,
        desc: wgpu::RenderPassDescriptor<'_>,
    ) -> Result<ProfiledRenderPass<'_>, GpuError> {
        open_render_pass(&mut self.encoder, self.profiler, name, desc, None)
    }

    /// [`Frame::render_pass`] for a pass whose pipeline's blending is known (the pass
    /// layer's [`crate::pass::RasterPass`]), so its roofline picks the right fill
    /// ceiling.
    pub(crate) fn render_pass_blending(
        &mut self,
        name: &str,
        desc: wgpu::RenderPassDescriptor<'_>,
        blended: bool,
    ) -> Result<ProfiledRenderPass<'_>, GpuError> {
        open_render_pass(&mut self.encoder, self.profiler, name, desc, Some(blended))
    }

    /// Opens a named, profiled compute pass.
    pub fn compute_pass(&mut self, name: &str) -> Result<ProfiledComputePass<'_>, GpuError> {
        open_compute_pass(&mut self.encoder, self.profiler, name)
    }

    /// Submits the frame, waits for it (frames do not overlap, so each is timed
    /// alone), then resolves its queries in a later submission.
    pub fn submit(self, ctx: &GpuContext) -> Result<(), GpuError> {
        submit_recorded(ctx, self.encoder, self.profiler, self.started)
    }
}

/// A frame with no scene: the profiled passes of [`Frame`] without a [`Renderer`], for
/// work that is measured like a method's pass but draws no scene (the adapter's
/// ceilings, `caustics-ceilings`). Its passes take the same timestamps and pipeline
/// statistics as a method's, so a pass and the ceiling it is read against are measured
/// with one ruler.
pub struct BareFrame<'a> {
    /// The frame's command encoder (one submission per frame).
    pub encoder: wgpu::CommandEncoder,
    /// Timed or count frame.
    pub mode: FrameMode,
    profiler: &'a mut PassProfiler,
    started: Instant,
}

impl<'a> BareFrame<'a> {
    /// Starts a frame measured by `profiler` (`Timed` or `Count`).
    pub fn begin(
        ctx: &GpuContext,
        profiler: &'a mut PassProfiler,
        mode: FrameMode,
    ) -> Result<Self, GpuError> {
        profiler.begin_frame(mode)?;
        let encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bare frame"),
            });
        Ok(Self {
            encoder,
            mode,
            profiler,
            started: Instant::now(),
        })
    }

    /// Opens a named, profiled render pass (see [`Frame::render_pass`]).
    pub fn render_pass(
        &mut self,
        name: &str,
        desc: wgpu::RenderPassDescriptor<'_>,
    ) -> Result<ProfiledRenderPass<'_>, GpuError> {
        open_render_pass(&mut self.encoder, self.profiler, name, desc, None)
    }

    /// [`BareFrame::render_pass`] whose pipelines write its first target with
    /// blending (`blended`) or without: the pass's [`crate::PassShape`] then says so,
    /// as a [`crate::pass::RasterPass`]'s does.
    pub fn render_pass_blending(
        &mut self,
        name: &str,
        desc: wgpu::RenderPassDescriptor<'_>,
        blended: bool,
    ) -> Result<ProfiledRenderPass<'_>, GpuError> {
        open_render_pass(&mut self.encoder, self.profiler, name, desc, Some(blended))
    }

    /// Opens a named, profiled compute pass (see [`Frame::compute_pass`]).
    pub fn compute_pass(&mut self, name: &str) -> Result<ProfiledComputePass<'_>, GpuError> {
        open_compute_pass(&mut self.encoder, self.profiler, name)
    }

    /// Submits the frame and waits for it, as [`Frame::submit`].
    pub fn submit(self, ctx: &GpuContext) -> Result<(), GpuError> {
        submit_recorded(ctx, self.encoder, self.profiler, self.started)
    }
}

fn open_render_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    profiler: &mut PassProfiler,
    name: &str,
    desc: wgpu::RenderPassDescriptor<'_>,
    blended: Option<bool>,
) -> Result<ProfiledRenderPass<'e>, GpuError> {
    let color_format = desc
        .color_attachments
        .iter()
        .flatten()
        .next()
        .map(|a| a.view.texture().format());
    let texture_bytes = |t: &wgpu::Texture, aspect: Option<wgpu::TextureAspect>| {
        let texel = t.format().block_copy_size(aspect).unwrap_or(4);
        u64::from(t.width()) * u64::from(t.height()) * u64::from(texel)
    };
    let colour_cleared = desc
        .color_attachments
        .iter()
        .flatten()
        .filter(|a| matches!(a.ops.load, wgpu::LoadOp::Clear(_)))
        .map(|a| texture_bytes(a.view.texture(), None))
        .sum::<u64>();
    let depth_cleared = desc.depth_stencil_attachment.as_ref().map_or(0, |d| {
        let cleared = d
            .depth_ops
            .is_some_and(|o| matches!(o.load, wgpu::LoadOp::Clear(_)));
        if cleared {
            texture_bytes(d.view.texture(), Some(wgpu::TextureAspect::DepthOnly))
        } else {
            0
        }
    });
    let shape = PassShape::Render {
        color_format,
        blended: color_format.and(blended),
        cleared_bytes: colour_cleared + depth_cleared,
    };
    let (index, mode) = profiler.open_pass(name, shape)?;
    let ts = profiler.timestamp_set(mode);
    let full = wgpu::RenderPassDescriptor {
        label: Some(name),
        color_attachments: desc.color_attachments,
        depth_stencil_attachment: desc.depth_stencil_attachment,
        timestamp_writes: ts.map(|query_set| wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: Some(2 * index),
            end_of_pass_write_index: Some(2 * index + 1),
        }),
        occlusion_query_set: desc.occlusion_query_set,
        multiview_mask: desc.multiview_mask,
    };
    let mut pass = encoder.begin_render_pass(&full);
    let stats = profiler.statistics_set(mode);
    if let Some(set) = stats {
        pass.begin_pipeline_statistics_query(set, index);
    }
    Ok(ProfiledRenderPass {
        pass,
        statistics: stats.is_some(),
    })
}

fn open_compute_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    profiler: &mut PassProfiler,
    name: &str,
) -> Result<ProfiledComputePass<'e>, GpuError> {
    let (index, mode) = profiler.open_pass(name, PassShape::Compute)?;
    let ts = profiler.timestamp_set(mode);
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(name),
        timestamp_writes: ts.map(|query_set| wgpu::ComputePassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: Some(2 * index),
            end_of_pass_write_index: Some(2 * index + 1),
        }),
    });
    let stats = profiler.statistics_set(mode);
    if let Some(set) = stats {
        pass.begin_pipeline_statistics_query(set, index);
    }
    // So that lavapipe takes the beginning before the first dispatch (profiling.rs).
    if let Some(set) = profiler.flush_timestamp_set(mode) {
        pass.write_timestamp(set, index);
    }
    Ok(ProfiledComputePass {
        pass,
        statistics: stats.is_some(),
    })
}

/// Submits a recorded frame, waits for it (frames do not overlap, so each is timed
/// alone), then resolves its queries in a later submission.
fn submit_recorded(
    ctx: &GpuContext,
    encoder: wgpu::CommandEncoder,
    profiler: &mut PassProfiler,
    started: Instant,
) -> Result<(), GpuError> {
    // Validation and out-of-memory errors of the frame's commands (reported when
    // the encoder is finished and submitted) become errors, not wgpu's panic.
    let oom = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let val = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    ctx.queue.submit([encoder.finish()]);
    let waited = ctx.wait_idle();
    let wall_ms = started.elapsed().as_secs_f64() * 1e3;
    let validation = pollster::block_on(val.pop());
    let memory = pollster::block_on(oom.pop());
    for (kind, err) in [("validation", validation), ("out of memory", memory)] {
        if let Some(e) = err {
            return Err(GpuError::Validation {
                kind,
                what: "frame submission".into(),
                message: e.to_string(),
            });
        }
    }
    ctx.check_device("frame")?;
    waited?;
    profiler.resolve_frame(ctx, wall_ms);
    Ok(())
}
