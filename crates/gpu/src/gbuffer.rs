//! Camera and light-space G-buffers: world position, smooth normal, object and
//! material ids and depth, rasterized from any view. A light's view is general:
//! orthographic for a directional light, one perspective face for a spot light,
//! six perspective faces (a cube) for a point light.

use bytemuck::{Pod, Zeroable};
use caustics_scene::Camera;
use wgpu::util::DeviceExt;

use crate::frame::Frame;
pub use crate::light_view::{LightFace, LightProjection, LightView};
use crate::pass::{BindGroupSchema, RasterPass, Shader};
use crate::scene_upload::{GpuScene, SceneVertex};
use crate::shader;
use crate::textures::{
    DEPTH_FORMAT, IDS_FORMAT, NORMAL_FORMAT, POSITION_FORMAT, Target, depth_test_state,
    opaque_target,
};
use crate::{GpuContext, GpuError};

/// Uniforms of one rasterized view (matches `View` in gbuffer.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewUniform {
    /// World to clip.
    pub view_proj: [[f32; 4]; 4],
    /// Eye position (perspective) or the view's centre (orthographic).
    pub eye: [f32; 4],
}

/// The targets of a G-buffer (one layer per view face).
pub struct GBuffer {
    /// World position and hit flag.
    pub position: Target,
    /// Normal and side seen.
    pub normal: Target,
    /// Object and material ids.
    pub ids: Target,
    /// Depth (for a light: the shadow map).
    pub depth: Target,
    /// View uniforms, one per layer.
    views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    /// Width, height.
    pub size: (u32, u32),
}

impl GBuffer {
    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.position.bytes + self.normal.bytes + self.ids.bytes + self.depth.bytes
    }

    /// Number of layers (faces).
    pub fn layers(&self) -> u32 {
        self.views.len() as u32
    }

    /// Replaces the view uniform of `layer` (staged: takes effect at the next submit).
    pub(crate) fn write_view(&self, queue: &wgpu::Queue, layer: usize, view: &ViewUniform) {
        if let Some((buffer, _)) = self.views.get(layer) {
            queue.write_buffer(buffer, 0, bytemuck::bytes_of(view));
        }
    }
}

/// Depth only, from a light's view (one layer per face): the base renderer's shadow
/// map. Methods that need positions, normals and ids from the light allocate a full
/// [`GBuffer`] with [`GBufferPass::light_gbuffer`] at their own resolution.
pub struct ShadowMap {
    /// Depth, one layer per face.
    pub depth: Target,
    /// View uniforms, one per layer.
    views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    /// Width, height.
    pub size: (u32, u32),
}

impl ShadowMap {
    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.depth.bytes
    }
}

/// The G-buffer rasterization passes (full and depth-only), shared by camera and
/// light views; each view's uniform is the pass's group 0, set per layer.
pub struct GBufferPass {
    full: RasterPass,
    depth_only: RasterPass,
}

impl GBufferPass {
    /// Builds both passes.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let shader = Shader::new(ctx, "gbuffer.wgsl", shader::compose(shader::GBUFFER_WGSL))?;
        let target = opaque_target;
        // Open cylinders, quads and heightfields are seen from both sides: no culling.
        let vertex_buffers = [Some(SceneVertex::LAYOUT)];
        let full = RasterPass::builder(ctx, "gbuffer", &shader, "vs_main")
            .caller_group(0)
            .vertex_buffers(&vertex_buffers)
            .depth_stencil(depth_test_state())
            .fragment(
                "fs_main",
                &[
                    target(POSITION_FORMAT),
                    target(NORMAL_FORMAT),
                    target(IDS_FORMAT),
                ],
            )
            .build()?;
        let depth_only = RasterPass::builder(ctx, "shadow map", &shader, "vs_main")
            .caller_group(0)
            .vertex_buffers(&vertex_buffers)
            .depth_stencil(depth_test_state())
            .build()?;
        Ok(Self { full, depth_only })
    }

    fn view_schema(&self) -> Result<&BindGroupSchema, GpuError> {
        // Both passes share the shader, so either's group 0 layout serves.
        self.full
            .schema(0)
            .ok_or_else(|| GpuError::Invalid("gbuffer.wgsl declares no group 0".into()))
    }

    fn view_binds(
        &self,
        device: &wgpu::Device,
        label: &str,
        views: &[ViewUniform],
    ) -> Result<Vec<(wgpu::Buffer, wgpu::BindGroup)>, GpuError> {
        views
            .iter()
            .map(|v| {
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::bytes_of(v),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                });
                let bind = self.view_schema()?.bind(device, &[("view", &buffer)])?;
                Ok((buffer, bind))
            })
            .collect()
    }

    /// Allocates a depth-only view of the light (the shadow map), one layer per face.
    pub fn shadow_map(&self, ctx: &GpuContext, view: &LightView) -> Result<ShadowMap, GpuError> {
        let layers = view.faces.len() as u32;
        let res = view.resolution;
        Ok(ShadowMap {
            depth: Target::new(
                ctx,
                "shadow map",
                DEPTH_FORMAT,
                res,
                res,
                layers,
                wgpu::TextureUsages::empty(),
            )?,
            views: self.view_binds(&ctx.device, "shadow map", &light_view_uniforms(view))?,
            size: (res, res),
        })
    }

    /// Records the depth of every object into each layer of `shadow`.
    pub fn record_shadow_map(
        &self,
        frame: &mut Frame<'_>,
        name: &str,
        scene: &GpuScene,
        shadow: &ShadowMap,
    ) -> Result<(), GpuError> {
        for (layer, (_, bind)) in shadow.views.iter().enumerate() {
            let depth = clear_depth(&shadow.depth.layer_views[layer]);
            let mut pass = self.depth_only.begin_as(frame, name, &[], Some(depth))?;
            draw_scene(&mut pass, bind, scene);
        }
        Ok(())
    }

    fn allocate(
        &self,
        ctx: &GpuContext,
        label: &str,
        width: u32,
        height: u32,
        views: &[ViewUniform],
    ) -> Result<GBuffer, GpuError> {
        let layers = views.len() as u32;
        let none = wgpu::TextureUsages::empty();
        let views = self.view_binds(&ctx.device, label, views)?;
        Ok(GBuffer {
            position: Target::new(
                ctx,
                &format!("{label} position"),
                POSITION_FORMAT,
                width,
                height,
                layers,
                none,
            )?,
            normal: Target::new(
                ctx,
                &format!("{label} normal"),
                NORMAL_FORMAT,
                width,
                height,
                layers,
                none,
            )?,
            ids: Target::new(
                ctx,
                &format!("{label} ids"),
                IDS_FORMAT,
                width,
                height,
                layers,
                none,
            )?,
            depth: Target::new(
                ctx,
                &format!("{label} depth"),
                DEPTH_FORMAT,
                width,
                height,
                layers,
                none,
            )?,
            views,
            size: (width, height),
        })
    }

    /// Allocates the camera G-buffer at the camera's resolution.
    pub fn camera_gbuffer(
        &self,
        ctx: &GpuContext,
        camera: &Camera,
        near: f32,
        far: f32,
    ) -> Result<GBuffer, GpuError> {
        let vp = camera.projection(near, far) * camera.view();
        let u = ViewUniform {
            view_proj: vp.to_cols_array_2d(),
            eye: camera.eye.extend(1.0).to_array(),
        };
        self.allocate(ctx, "camera gbuffer", camera.width, camera.height, &[u])
    }

    /// Allocates a light G-buffer, one layer per face of `view`.
    pub fn light_gbuffer(&self, ctx: &GpuContext, view: &LightView) -> Result<GBuffer, GpuError> {
        self.allocate(
            ctx,
            "light gbuffer",
            view.resolution,
            view.resolution,
            &light_view_uniforms(view),
        )
    }

    /// Records the rasterization of every object into each layer of `gbuffer`, one
    /// profiled render pass per layer named `name`.
    pub fn record(
        &self,
        frame: &mut Frame<'_>,
        name: &str,
        scene: &GpuScene,
        gbuffer: &GBuffer,
    ) -> Result<(), GpuError> {
        for (layer, (_, bind)) in gbuffer.views.iter().enumerate() {
            fn color(
                view: &wgpu::TextureView,
                clear: wgpu::Color,
            ) -> Option<wgpu::RenderPassColorAttachment<'_>> {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })
            }
            let none_id = f64::from(u32::MAX);
            let attachments = [
                color(
                    &gbuffer.position.layer_views[layer],
                    wgpu::Color::TRANSPARENT,
                ),
                color(&gbuffer.normal.layer_views[layer], wgpu::Color::TRANSPARENT),
                color(
                    &gbuffer.ids.layer_views[layer],
                    wgpu::Color {
                        r: none_id,
                        g: none_id,
                        b: 0.0,
                        a: 0.0,
                    },
                ),
            ];
            let depth = clear_depth(&gbuffer.depth.layer_views[layer]);
            let mut pass = self.full.begin_as(frame, name, &attachments, Some(depth))?;
            draw_scene(&mut pass, bind, scene);
        }
        Ok(())
    }
}

fn draw_scene(pass: &mut wgpu::RenderPass<'_>, view: &wgpu::BindGroup, scene: &GpuScene) {
    pass.set_bind_group(0, view, &[]);
    pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
    pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..scene.index_count, 0, 0..1);
}

fn clear_depth(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

fn light_view_uniforms(view: &LightView) -> Vec<ViewUniform> {
    view.faces
        .iter()
        .map(|f| ViewUniform {
            view_proj: f.view_proj.to_cols_array_2d(),
            eye: view.origin.extend(1.0).to_array(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_uniform_matches_its_wgsl() {
        crate::assert_wgsl_layout!(crate::shader::compose(crate::shader::GBUFFER_WGSL), ViewUniform as "View" { view_proj, eye });
    }
}
