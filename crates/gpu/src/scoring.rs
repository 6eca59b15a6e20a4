//! Scoring frames at the reference's footprint (DESIGN "Measuring honestly").
//!
//! The reference image is a pixel-area average (a box filter over each pixel); a timed
//! frame samples each pixel once, at its centre. A focus narrower than a pixel is then
//! hit or missed, never averaged, and the error measures camera aliasing as much as the
//! method. A scoring frame renders the same frame `N×N` times with the camera shifted
//! by stratified sub-pixel offsets ([`subpixel_offsets`], applied to the projection by
//! [`Renderer::set_subpixel_offset`], so the G-buffer, the base passes and every
//! camera-side method pass see the same shifted camera) and averages them on the GPU
//! ([`ScoreAccumulator`]): the mean converges to the box filter as `N` grows. The
//! light-side passes, which do not depend on the camera, may run once before the
//! sub-frames ([`Renderer::begin_scoring_subframe`], `caustics_method::LightSide`). The
//! scoring frames come after the timed frames and are never timed.

use crate::frame::Frame;
use crate::pass::{ComputePass, Shader};
use crate::renderer::Renderer;
use crate::{GpuContext, GpuError};

/// The score-accumulation pass.
pub const SCORE_ACCUMULATE_WGSL: &str = include_str!("shaders/score_accumulate.wgsl");

/// Name of the accumulation pass in scoring frames (not a method pass).
pub const ACCUMULATE_PASS: &str = "score/accumulate";

/// Largest `N` of an `N×N` scoring grid (256 sub-frames per scored image).
pub const MAX_SCORE_GRID: u32 = 16;

/// The `grid × grid` sub-pixel offsets of a scoring frame, in pixels from the pixel
/// centre (x right, y down), row by row: the centres of the strata, so `grid = 1` gives
/// `[0, 0]` (today's pixel-centre sample) and every run uses the same offsets. Regular
/// stratum centres are the midpoint rule of the box filter: deterministic (counts and
/// errors are gated exactly) and with an error that falls as `1/grid²` for smooth images.
pub fn subpixel_offsets(grid: u32) -> Vec<[f32; 2]> {
    let n = grid.max(1);
    let step = 1.0 / n as f32;
    (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            [(i as f32 + 0.5) * step - 0.5, (j as f32 + 0.5) * step - 0.5]
        })
        .collect()
}

/// The pixel-averaged images of a scoring frame: RGBA32F, row 0 at the top, rows
/// tightly packed (the layout of [`crate::readback::read_rgba32f`]).
pub struct ScoredImages {
    /// Direct light (L D E).
    pub direct: Vec<f32>,
    /// Surface caustic radiance (L S+ D E).
    pub surface: Vec<f32>,
    /// Volume caustic radiance (L S+ M E).
    pub volume: Vec<f32>,
    /// Sub-frames averaged.
    pub frames: u32,
}

/// Running sums of the three radiance targets over the sub-frames of a scoring frame,
/// allocated once per run (three `width × height` RGBA32F storage buffers).
pub struct ScoreAccumulator {
    pass: ComputePass,
    sums: [wgpu::Buffer; 3],
    size: (u32, u32),
    frames: u32,
}

impl ScoreAccumulator {
    /// Allocates the sums for the renderer's targets (zero-initialized).
    pub fn new(ctx: &GpuContext, renderer: &Renderer) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let targets = renderer.targets();
        let (w, h) = (
            targets.surface.texture.width(),
            targets.surface.texture.height(),
        );
        let sum = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (w as u64 * h as u64 * 16).max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let sums = [
            sum("score sum: direct"),
            sum("score sum: surface"),
            sum("score sum: volume"),
        ];
        let shader = Shader::new(
            ctx,
            "score_accumulate.wgsl",
            SCORE_ACCUMULATE_WGSL.to_owned(),
        )?;
        let pass = ComputePass::builder(ctx, ACCUMULATE_PASS, &shader)
            .bind(
                0,
                &[
                    ("direct_in", &targets.direct.view),
                    ("surface_in", &targets.surface.view),
                    ("volume_in", &targets.volume.view),
                    ("direct_sum", &sums[0]),
                    ("surface_sum", &sums[1]),
                    ("volume_sum", &sums[2]),
                ],
            )
            .kernels(&["accumulate"])
            .build()?;
        Ok(Self {
            pass,
            sums,
            size: (w, h),
            frames: 0,
        })
    }

    /// Bytes of GPU memory the sums own.
    pub fn bytes(&self) -> u64 {
        self.sums.iter().map(|b| b.size()).sum()
    }

    /// Records, at the end of `frame` (after the method's passes), the addition of the
    /// frame's three targets into the sums.
    pub fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), GpuError> {
        let (w, h) = self.size;
        let mut pass = self.pass.begin(frame)?;
        pass.dispatch("accumulate", [w.div_ceil(8), h.div_ceil(8), 1])?;
        drop(pass);
        self.frames += 1;
        Ok(())
    }

    /// Reads the sums back (once per scoring frame) and divides by the sub-frames
    /// recorded, then zeroes the sums for the next scoring frame.
    pub fn read_mean(&mut self, ctx: &GpuContext) -> Result<ScoredImages, GpuError> {
        if self.frames == 0 {
            return Err(GpuError::Readback {
                what: "scored images".into(),
                message: "no scoring sub-frame was recorded".into(),
            });
        }
        let inv = 1.0 / self.frames as f32;
        let read = |b: &wgpu::Buffer, what: &str| -> Result<Vec<f32>, GpuError> {
            let bytes = crate::readback::read_buffer_bytes(ctx, b, b.size(), what)?;
            let mut v: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
            v.truncate(self.size.0 as usize * self.size.1 as usize * 4);
            v.iter_mut().for_each(|x| *x *= inv);
            Ok(v)
        };
        let images = ScoredImages {
            direct: read(&self.sums[0], "scored direct image")?,
            surface: read(&self.sums[1], "scored surface caustic image")?,
            volume: read(&self.sums[2], "scored volume caustic image")?,
            frames: self.frames,
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("score reset"),
            });
        for b in &self.sums {
            encoder.clear_buffer(b, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
        self.frames = 0;
        Ok(images)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulate_shader_validates() -> Result<(), String> {
        crate::shader::validate_wgsl("score_accumulate.wgsl", SCORE_ACCUMULATE_WGSL)
    }

    #[test]
    fn offsets_are_stratum_centres_symmetric_about_the_pixel_centre() {
        assert_eq!(subpixel_offsets(1), vec![[0.0, 0.0]]);
        let o = subpixel_offsets(4);
        assert_eq!(o.len(), 16);
        assert_eq!(o[0], [-0.375, -0.375]);
        assert_eq!(o[15], [0.375, 0.375]);
        let mean = o
            .iter()
            .fold([0.0f32; 2], |a, p| [a[0] + p[0], a[1] + p[1]]);
        assert!(mean[0].abs() < 1e-6 && mean[1].abs() < 1e-6);
        // Every stratum holds exactly one offset.
        for (k, p) in o.iter().enumerate() {
            let (i, j) = (((p[0] + 0.5) * 4.0) as usize, ((p[1] + 0.5) * 4.0) as usize);
            assert_eq!(j * 4 + i, k);
        }
    }
}
