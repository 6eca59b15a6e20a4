//! The caustic cube map's fixed-point accumulator of the compute-raster paths
//! (`raster=compute`, issue 17), shared by splatting and caustic-triangles: the buffer
//! their reconstruction kernels add into with integer atomics and `resolve` empties into
//! the atlas (`atlas_accumulator.wgsl`).

use caustics_gpu::limits::Reservation;
use caustics_gpu::wgpu;
use caustics_gpu::{GpuContext, GpuError, shader};
use caustics_method::MethodError;

use crate::CausticMap;

/// The accumulator's WGSL (`add_atlas`, the `resolve` kernel) after caustics-gpu's
/// fixed-point functions; the including pass binds `cm`, `accum` and `atlas_out`.
pub fn accumulator_wgsl() -> String {
    format!("{}\n{ATLAS_ACCUMULATOR_WGSL}", shader::FIXED_POINT_WGSL)
}

const ATLAS_ACCUMULATOR_WGSL: &str = include_str!("atlas_accumulator.wgsl");

/// u32 words per atlas texel (`ATLAS_WORDS` in atlas_accumulator.wgsl): a fixed-point
/// channel for each of r, g, b and alpha.
pub const ATLAS_WORDS_PER_TEXEL: u64 = 4 * shader::FIXED_POINT_WORDS;

/// A fixed-point sum for every texel of a [`CausticMap`]'s atlas.
pub struct AtlasAccumulator {
    /// Bound as `accum` by the reconstruction kernels and `resolve`.
    pub buffer: wgpu::Buffer,
    /// Its hold on the memory ledger, given back with it.
    _reservation: Reservation,
}

impl AtlasAccumulator {
    /// Allocates the accumulator of `map` (zero at creation; each resolve zeroes what
    /// it read), refused naming `cube_size` where the adapter's limits or the memory
    /// budget cannot hold it.
    pub fn new(
        ctx: &GpuContext,
        method: &'static str,
        map: &CausticMap,
    ) -> Result<Self, MethodError> {
        let texels = 6 * u64::from(map.size) * u64::from(map.size);
        let bytes = texels * ATLAS_WORDS_PER_TEXEL * 4;
        let what = format!(
            "cube_size: the compute path's fixed-point accumulator ({texels} texels x {} bytes)",
            ATLAS_WORDS_PER_TEXEL * 4
        );
        let param = |e: GpuError| MethodError::Param {
            method,
            message: e.to_string(),
        };
        let reservation = ctx
            .reserve_storage(&what, bytes, "lower cube_size")
            .map_err(param)?;
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("caustic cube map accumulator"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Ok(Self {
            buffer,
            _reservation: reservation,
        })
    }

    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.buffer.size()
    }

    /// Workgroups of the `resolve` kernel over `map`'s 3 × 2 atlas.
    pub fn resolve_groups(map: &CausticMap) -> [u32; 3] {
        [(3 * map.size).div_ceil(8), (2 * map.size).div_ceil(8), 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_gpu::layout::wgsl_u32_constant;

    /// The snippet with the bindings it asks its includer for: valid WGSL, and its
    /// words per texel are the ones the buffer is sized by.
    #[test]
    fn accumulator_validates_and_its_words_match() -> Result<(), String> {
        let source = crate::compose(&format!(
            "@group(1) @binding(0) var<uniform> cm: CausticMapUniform;\n\
             @group(1) @binding(1) var<storage, read_write> accum: array<atomic<u32>>;\n\
             @group(1) @binding(2) var atlas_out: texture_storage_2d<rgba32float, write>;\n{}",
            accumulator_wgsl()
        ));
        shader::validate_wgsl("atlas_accumulator.wgsl", &source)?;
        assert_eq!(
            wgsl_u32_constant(&source, "ATLAS_WORDS")?,
            ATLAS_WORDS_PER_TEXEL as u32
        );
        Ok(())
    }
}
