//! The caustic ("light") cube map of §4.2 and the camera pass of §4.3.
//!
//! The six faces live side by side in one 3×2 atlas texture (face f at column f % 3,
//! row f / 3), so that a method reconstructs all of them in one render pass, one
//! viewport per face, instead of six passes; the face order, orientation and texel
//! convention are those of the distance impostors (`impostor_face_uv`,
//! [`caustics_gpu::impostor::face_view_proj`]), so lookups and rasterization agree.

use bytemuck::{Pod, Zeroable};
use caustics_gpu::binding::{texture_entry, uniform_entry};
use caustics_gpu::impostor::face_view_proj;
use caustics_gpu::textures::{HDR_FORMAT, Target, additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{
    CountedPipeline, Frame, GpuContext, ProfiledRenderPass, Renderer, pass_desc, shader,
};
use caustics_method::MethodError;
use caustics_scene::{Mat4, Vec3};

use crate::{LOOKUP_WGSL, PhotonHitConfig, compose};

/// Matches `CausticMapUniform` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MapUniform {
    face_view_proj: [[[f32; 4]; 4]; 6],
    center: [f32; 4],
    params: [f32; 4],
}

/// Top-left texel of face `face` in the atlas of `size`² faces.
pub fn face_origin(face: u32, size: u32) -> (u32, u32) {
    ((face % 3) * size, (face / 3) * size)
}

/// The caustic cube map around the generator's centre, and its camera pass.
pub struct CausticMap {
    /// Irradiance on the receiver (rgb, W/m²) and luminance × distance (alpha), six
    /// `size`² faces in a 3×2 atlas ([`HDR_FORMAT`]).
    pub atlas: Target,
    /// Texels per side of a face.
    pub size: u32,
    /// The centre (m): the distance maps' reference point.
    pub center: Vec3,
    /// World → clip of each face (the rasterization of the reconstruction passes).
    pub faces: [Mat4; 6],
    uniform: wgpu::Buffer,
    lookup_pipeline: CountedPipeline<wgpu::RenderPipeline>,
    lookup_bind: wgpu::BindGroup,
    lookup_name: String,
    bytes: u64,
}

impl CausticMap {
    /// Allocates the atlas and the camera pass; `reach` (m) is the farthest receiver
    /// distance from `center` (the far plane of the faces).
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        method: &'static str,
        center: Vec3,
        reach: f32,
        config: &PhotonHitConfig,
    ) -> Result<Self, MethodError> {
        let device = &ctx.device;
        let size = config.cube_size;
        let far = reach * 1.01 + 1e-3;
        let near = (far * 1e-5).max(1e-5);
        let faces: [Mat4; 6] = std::array::from_fn(|f| face_view_proj(f, center, near, far));
        Ok(ctx.checked("caustic cube map setup", || {
            let atlas = Target::new(
                device,
                "caustic cube map",
                HDR_FORMAT,
                3 * size,
                2 * size,
                1,
                wgpu::TextureUsages::empty(),
            );
            let u = MapUniform {
                face_view_proj: faces.map(|m| m.to_cols_array_2d()),
                center: center.extend(0.0).to_array(),
                params: [
                    size as f32,
                    if config.distance_test { 1.0 } else { 0.0 },
                    config.distance_tolerance as f32,
                    0.0,
                ],
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("caustic cube map"),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let fs = wgpu::ShaderStages::FRAGMENT;
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("caustic lookup"),
                entries: &[
                    uniform_entry(0, fs),
                    texture_entry(
                        1,
                        fs,
                        wgpu::TextureSampleType::Float { filterable: false },
                        wgpu::TextureViewDimension::D2,
                    ),
                ],
            });
            let lookup_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("caustic lookup"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&atlas.view),
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("caustic lookup"),
                bind_group_layouts: &[Some(renderer.frame_layout()), Some(&layout)],
                immediate_size: 0,
            });
            let module = shader::module(device, "photon-hits lookup.wgsl", compose(LOOKUP_WGSL));
            let lookup_pipeline = CountedPipeline::new(|constants| {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("caustic lookup"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_fullscreen"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: None,
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_lookup"),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants,
                            ..Default::default()
                        },
                        targets: &[Some(additive_hdr_target())],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            });
            let bytes = atlas.bytes + uniform.size();
            Self {
                atlas,
                size,
                center,
                faces,
                uniform,
                lookup_pipeline,
                lookup_bind,
                lookup_name: format!("{method}/camera_lookup"),
                bytes,
            }
        })?)
    }

    /// The `CausticMapUniform` buffer, for the reconstruction passes' bind groups.
    pub fn uniform(&self) -> &wgpu::Buffer {
        &self.uniform
    }

    /// Opens the reconstruction pass `name`, which clears the whole atlas first.
    pub fn begin_reconstruction<'f>(
        &self,
        frame: &'f mut Frame<'_>,
        name: &str,
    ) -> Result<ProfiledRenderPass<'f>, MethodError> {
        let attachments = [Some(wgpu::RenderPassColorAttachment {
            view: &self.atlas.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })];
        Ok(frame.render_pass(name, pass_desc(&attachments))?)
    }

    /// The atlas as the colour attachment of a reconstruction pass, cleared first.
    pub fn reconstruction_attachment(&self) -> [Option<wgpu::RenderPassColorAttachment<'_>>; 1] {
        [Some(wgpu::RenderPassColorAttachment {
            view: &self.atlas.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })]
    }

    /// Restricts drawing to face `face` of the atlas: clip space of that face's
    /// projection maps onto its square, and nothing spills onto a neighbour.
    pub fn set_face(&self, pass: &mut wgpu::RenderPass<'_>, face: u32) {
        let (x, y) = face_origin(face, self.size);
        pass.set_viewport(
            x as f32,
            y as f32,
            self.size as f32,
            self.size as f32,
            0.0,
            1.0,
        );
        pass.set_scissor_rect(x, y, self.size, self.size);
    }

    /// The camera pass: adds ρ/π · E into the surface caustic target.
    pub fn record_lookup(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        let pipeline = self.lookup_pipeline.get(frame);
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        let mut pass = frame.render_pass(&self.lookup_name, pass_desc(&attachments))?;
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
        pass.set_bind_group(1, &self.lookup_bind, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Reads the atlas back as RGBA f32, row 0 at the top (tests and figures).
    pub fn read_atlas(&self, ctx: &GpuContext) -> Result<Vec<f32>, MethodError> {
        Ok(caustics_gpu::readback::read_rgba32f(
            ctx,
            &self.atlas.texture,
            "caustic cube map",
        )?)
    }

    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}
