//! Render targets shared by the base passes and the methods.

use crate::limits::Reservation;
use crate::{GpuContext, GpuError};

/// Format of every HDR radiance target (direct, surface caustic, volume caustic).
/// 32-bit float with additive blending (`FLOAT32_BLENDABLE`), linear W·m⁻²·sr⁻¹.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// G-buffer world position (xyz) and hit flag (w).
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// G-buffer normal (xyz) and the side seen (w = ±1).
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// G-buffer object and material ids.
pub const IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;
/// Depth of the camera and light G-buffers (the light's is the shadow map).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// An HDR radiance target that passes add into (`One + One` blending), as every
/// light-accumulating pass (direct light, caustic splats, beams) needs.
pub fn additive_hdr_target() -> wgpu::ColorTargetState {
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    wgpu::ColorTargetState {
        format: HDR_FORMAT,
        blend: Some(wgpu::BlendState {
            color: add,
            alpha: add,
        }),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// A colour target written without blending (G-buffers, impostors).
pub fn opaque_target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// Depth test and write, nearest surface wins ([`DEPTH_FORMAT`]).
pub fn depth_test_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// A colour attachment that keeps what the target holds (passes that add light).
pub fn load_attachment(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A texture with its default view and byte size.
pub struct Target {
    /// The texture.
    pub texture: wgpu::Texture,
    /// A view of all layers (D2 for one layer, D2Array for several).
    pub view: wgpu::TextureView,
    /// Per-layer D2 views (for rendering into one layer).
    pub layer_views: Vec<wgpu::TextureView>,
    /// Bytes of GPU memory.
    pub bytes: u64,
    /// Those bytes, held in the device's memory ledger while the texture lives.
    _memory: Reservation,
}

impl Target {
    /// Bytes of a `width` × `height` × `layers` texture of `format`.
    pub fn bytes_of(format: wgpu::TextureFormat, width: u32, height: u32, layers: u32) -> u64 {
        let bpp = format.block_copy_size(None).unwrap_or(4) as u64;
        u64::from(width) * u64::from(height) * u64::from(layers) * bpp
    }

    /// Creates a 2D (array) texture usable as attachment, binding and copy source,
    /// after checking its side against the device and reserving its bytes in the
    /// memory ledger (what sizes it from a user's request checks first, with the
    /// parameter to lower; this is the backstop every texture passes).
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
        layers: u32,
        extra_usage: wgpu::TextureUsages,
    ) -> Result<Self, GpuError> {
        let raise = "lower the resolution or parameter that sizes it";
        ctx.limits.texture(label, width, height, raise)?;
        if layers > ctx.device.limits().max_texture_array_layers {
            return Err(GpuError::OverLimit {
                what: label.to_owned(),
                needed: format!("{layers} layers"),
                limit: format!(
                    "this device's largest texture array, {} layers (max_texture_array_layers)",
                    ctx.device.limits().max_texture_array_layers
                ),
                raise: raise.to_owned(),
            });
        }
        let bytes = Self::bytes_of(format, width, height, layers);
        let memory = ctx.memory.reserve(
            &format!("{label} ({width}x{height}x{layers})"),
            bytes,
            raise,
        )?;
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | extra_usage,
            view_formats: &[],
        });
        let dimension = if layers > 1 {
            wgpu::TextureViewDimension::D2Array
        } else {
            wgpu::TextureViewDimension::D2
        };
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(dimension),
            ..Default::default()
        });
        let layer_views = (0..layers)
            .map(|l| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some(label),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Ok(Self {
            texture,
            view,
            layer_views,
            bytes,
            _memory: memory,
        })
    }

    /// View of the texture as a D2 array (for shadow-map sampling), whatever its layer count.
    pub fn array_view(&self) -> wgpu::TextureView {
        self.texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    }
}

/// The three HDR images of a frame (DESIGN "Units and what an image means").
pub struct RadianceTargets {
    /// L D E with shadows, written by the base renderer.
    pub direct: Target,
    /// L S+ D E, written by the method.
    pub surface: Target,
    /// L S+ M E, written by the method (stays zero for surface-only methods).
    pub volume: Target,
}

impl RadianceTargets {
    /// Allocates the three targets at the camera resolution.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self, GpuError> {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        Ok(Self {
            direct: Target::new(
                ctx,
                "direct radiance",
                HDR_FORMAT,
                width,
                height,
                1,
                storage,
            )?,
            surface: Target::new(
                ctx,
                "surface caustic radiance",
                HDR_FORMAT,
                width,
                height,
                1,
                storage,
            )?,
            volume: Target::new(
                ctx,
                "volume caustic radiance",
                HDR_FORMAT,
                width,
                height,
                1,
                storage,
            )?,
        })
    }

    /// Bytes of GPU memory the targets own.
    pub fn bytes(&self) -> u64 {
        self.direct.bytes + self.surface.bytes + self.volume.bytes
    }
}
