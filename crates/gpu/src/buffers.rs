//! The buffers passes bind, made one way: a uniform from a `Pod` value, a storage
//! buffer that can be read back (and cleared each frame).

use bytemuck::Pod;
use wgpu::util::DeviceExt;

/// A uniform buffer holding `value`.
pub fn uniform_buffer<T: Pod>(device: &wgpu::Device, label: &str, value: &T) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A storage buffer of `size` bytes that can be read back (and cleared, if `clear`).
pub fn storage_buffer(device: &wgpu::Device, label: &str, size: u64, clear: bool) -> wgpu::Buffer {
    let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    if clear {
        usage |= wgpu::BufferUsages::COPY_DST;
    }
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}
