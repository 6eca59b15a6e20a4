//! GPU → CPU readback (never on the hot path: after measured frames, or for images).

use crate::{GpuContext, GpuError};

fn map_and_copy(ctx: &GpuContext, staging: &wgpu::Buffer, what: &str) -> Result<Vec<u8>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait_idle()?;
    rx.recv()
        .map_err(|e| GpuError::Readback {
            what: what.into(),
            message: e.to_string(),
        })?
        .map_err(|e| GpuError::Readback {
            what: what.into(),
            message: e.to_string(),
        })?;
    let bytes = staging
        .get_mapped_range(..)
        .map_err(|e| GpuError::Readback {
            what: what.into(),
            message: format!("{e:?}"),
        })?
        .to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Copies the first `size` bytes of `buffer` (which needs `COPY_SRC`) to the CPU.
pub fn read_buffer_bytes(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    what: &str,
) -> Result<Vec<u8>, GpuError> {
    // A size past the buffer's end is an error naming `what`, not wgpu's panic.
    let staging = ctx.checked(&format!("readback of {what}"), || {
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback staging"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        ctx.queue.submit([encoder.finish()]);
        staging
    })?;
    map_and_copy(ctx, &staging, what)
}

/// Reads `size` bytes of `buffer` as little-endian u32s.
pub fn read_buffer_u32(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    what: &str,
) -> Result<Vec<u32>, GpuError> {
    Ok(bytemuck::pod_collect_to_vec(&read_buffer_bytes(
        ctx, buffer, size, what,
    )?))
}

/// Reads `size` bytes of `buffer` as little-endian u64s.
pub fn read_buffer_u64(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    what: &str,
) -> Result<Vec<u64>, GpuError> {
    Ok(bytemuck::pod_collect_to_vec(&read_buffer_bytes(
        ctx, buffer, size, what,
    )?))
}

/// Reads layer `layer` of a 2D texture with 4-byte-aligned texels, row 0 at the top,
/// rows tightly packed. Returns the raw texel bytes.
pub fn read_texture_bytes(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    layer: u32,
    what: &str,
) -> Result<Vec<u8>, GpuError> {
    let (w, h) = (texture.width(), texture.height());
    let bpp = texture.format().block_copy_size(None).unwrap_or(4);
    let row = w * bpp;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: padded as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("texture readback"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_and_copy(ctx, &staging, what)?;
    let mut out = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        out.extend_from_slice(&bytes[y * padded as usize..y * padded as usize + row as usize]);
    }
    Ok(out)
}

/// Reads an `Rgba32Float` texture as RGBA f32, row 0 at the top.
pub fn read_rgba32f(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    what: &str,
) -> Result<Vec<f32>, GpuError> {
    Ok(bytemuck::pod_collect_to_vec(&read_texture_bytes(
        ctx, texture, 0, what,
    )?))
}
