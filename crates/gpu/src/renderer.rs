//! The base renderer every method runs on top of: the camera G-buffer, the light
//! G-buffers (whose depth is the shadow map), direct lighting, the HDR targets, the
//! fill-rate counter and the group-0 bind group that method passes share.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::frame::Frame;
use crate::gbuffer::{GBuffer, GBufferPass, LightProjection, LightView, ShadowMap, ViewUniform};
use crate::limits::Reservation;
use crate::pass::{BindGroupSchema, RasterPass, Shader};
use crate::profiling::{FrameMode, PassProfiler};
use crate::scene_upload::{GpuLight, GpuScene, gpu_light};
use crate::shader;
use crate::textures::{RadianceTargets, additive_hdr_target, load_attachment};
use crate::{GpuContext, GpuError};

/// Matches `FrameUniforms` in frame.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Camera world → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Eye (xyz), vertical field of view in radians (w).
    pub eye: [f32; 4],
    /// Unit forward axis (xyz).
    pub forward: [f32; 4],
    /// Width, height, 1/width, 1/height.
    pub resolution: [f32; 4],
    /// Object, material, light and wave counts.
    pub counts: [u32; 4],
}

/// Matches `DirectLight` in direct.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DirectUniform {
    light: GpuLight,
    face_view_proj: [[[f32; 4]; 4]; 6],
    params: [f32; 4],
}

/// Lights each extended light (sphere, environment) becomes in the direct image
/// ([`caustics_scene::Light::representative`]: point lights in the sphere, median-cut
/// directional lights of the map); each costs a shadow map and a full-screen draw.
pub const DIRECT_REPRESENTATIVE_LIGHTS: u32 = 16;

/// Settings of the base renderer.
#[derive(Clone, Copy, Debug)]
pub struct RendererOptions {
    /// Shadow-map resolution per face for directional and spot lights (texels).
    pub shadow_resolution: u32,
    /// Shadow-map resolution per cube face for point lights (texels).
    pub cube_shadow_resolution: u32,
}

impl Default for RendererOptions {
    fn default() -> Self {
        Self {
            shadow_resolution: 2048,
            cube_shadow_resolution: 1024,
        }
    }
}

struct LightShadow {
    view: LightView,
    shadow: ShadowMap,
    direct_bind: wgpu::BindGroup,
}

/// Constant values for the `FILL_COUNT` override of frame.wgsl.
pub(crate) fn fill_constants(counting: bool) -> [(&'static str, f64); 1] {
    [("FILL_COUNT", if counting { 1.0 } else { 0.0 })]
}

/// Base renderer and shared per-scene GPU state.
pub struct Renderer {
    device: wgpu::Device,
    scene: GpuScene,
    gbuffer_pass: GBufferPass,
    camera_gbuffer: GBuffer,
    direct: DirectLighting,
    targets: RadianceTargets,
    frame_uniforms: FrameUniforms,
    frame_buffer: wgpu::Buffer,
    /// Camera world → view and view → clip, unshifted (see [`Renderer::set_subpixel_offset`]).
    camera_view: Mat4,
    camera_projection: Mat4,
    frame_schema: BindGroupSchema,
    frame_bind: wgpu::BindGroup,
    fill_counts: wgpu::Buffer,
    /// The fill counts' bytes in the memory ledger (textures hold their own).
    _fill_counts_memory: Reservation,
    bytes: u64,
}

/// Direct lighting: per light a shadow map (the light G-buffer's depth) and one
/// full-screen draw adding its shadowed direct radiance.
struct DirectLighting {
    pass: RasterPass,
    lights: Vec<LightShadow>,
}

impl DirectLighting {
    fn new(
        ctx: &GpuContext,
        gbuffer_pass: &GBufferPass,
        camera_gbuffer: &GBuffer,
        scene: &GpuScene,
        options: RendererOptions,
    ) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let shader = Shader::new(ctx, "direct.wgsl", shader::compose(shader::DIRECT_WGSL))?;
        let pass = RasterPass::fullscreen(
            ctx,
            "base/direct",
            &shader,
            "fs_main",
            &[Some(additive_hdr_target())],
        )
        .caller_group(0)
        .build()?;
        let schema = pass
            .schema(0)
            .ok_or_else(|| GpuError::Invalid("direct.wgsl declares no group 0".into()))?;
        let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let bounds = scene.scene.bounds();
        // An extended light (only a method that renders it natively, pinhole, gets one:
        // the harness gives the others representative lights) lights the direct image
        // as its representative lights, as the methods' caustics would: soft shadows
        // from a sphere light, the sky's light at all (the light buffer's black
        // directional stand-in draws none).
        let direct_lights: Vec<caustics_scene::Light> = scene
            .scene
            .lights
            .iter()
            .flat_map(|l| l.representative(DIRECT_REPRESENTATIVE_LIGHTS))
            .collect();
        let lights = direct_lights
            .iter()
            .map(|light| {
                let res = match light {
                    caustics_scene::Light::Point { .. } | caustics_scene::Light::Sphere { .. } => {
                        options.cube_shadow_resolution
                    }
                    _ => options.shadow_resolution,
                };
                let view = LightView::fit(light, &bounds, res);
                let shadow = gbuffer_pass.shadow_map(ctx, &view)?;
                let uniform = direct_uniform(light, &view);
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("direct light"),
                    contents: bytemuck::bytes_of(&uniform),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let shadow_view = shadow.depth.array_view();
                let direct_bind = schema.bind(
                    device,
                    &[
                        ("gbuf_position", &camera_gbuffer.position.view),
                        ("gbuf_normal", &camera_gbuffer.normal.view),
                        ("gbuf_ids", &camera_gbuffer.ids.view),
                        ("materials", &scene.materials_buffer),
                        ("dl", &buffer),
                        ("shadow_map", &shadow_view),
                        ("shadow_sampler", &shadow_sampler),
                    ],
                )?;
                Ok(LightShadow {
                    view,
                    shadow,
                    direct_bind,
                })
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        Ok(Self { pass, lights })
    }

    fn bytes(&self) -> u64 {
        self.lights.iter().map(|l| l.shadow.bytes()).sum()
    }

    /// Shadow maps (kept from the previous frame when it [reuses the light
    /// side](Frame::reuses_light_side)), then one draw per light into the direct target.
    fn record(
        &self,
        frame: &mut Frame<'_>,
        gbuffer_pass: &GBufferPass,
        scene: &GpuScene,
        targets: &RadianceTargets,
    ) -> Result<(), GpuError> {
        if !frame.reuses_light_side() {
            for light in &self.lights {
                gbuffer_pass.record_shadow_map(frame, "base/shadow_map", scene, &light.shadow)?;
            }
        }
        for light in &self.lights {
            let attachments = [load_attachment(&targets.direct.view)];
            let mut pass = self.pass.begin(frame, &attachments, None)?;
            pass.set_bind_group(0, &light.direct_bind, &[]);
            pass.draw_fullscreen();
        }
        Ok(())
    }
}

fn direct_uniform(light: &caustics_scene::Light, view: &LightView) -> DirectUniform {
    let mut faces = [[[0.0f32; 4]; 4]; 6];
    for (i, f) in view.faces.iter().enumerate() {
        faces[i] = f.view_proj.to_cols_array_2d();
    }
    let orthographic = view.projection == LightProjection::Orthographic;
    DirectUniform {
        light: gpu_light(light),
        face_view_proj: faces,
        params: [
            view.faces.len() as f32,
            view.resolution as f32,
            view.texel_size,
            if orthographic { 1.0 } else { 0.0 },
        ],
    }
}

impl Renderer {
    /// Allocates every shared target and pipeline for `scene`.
    pub fn new(
        ctx: &GpuContext,
        scene: GpuScene,
        options: RendererOptions,
    ) -> Result<Self, GpuError> {
        ctx.checked("base renderer setup", || Self::build(ctx, scene, options))?
    }

    fn build(
        ctx: &GpuContext,
        scene: GpuScene,
        options: RendererOptions,
    ) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let sc = &scene.scene;
        let cam = &sc.camera;
        let (w, h) = (cam.width, cam.height);
        let bounds = sc.bounds();
        let far = bounds
            .corners()
            .iter()
            .map(|c| (*c - cam.eye).length())
            .fold(0.0, f32::max);
        let far = far * 1.05 + 1e-2;
        let near = (far * 1e-4).max(1e-3);

        // Refused before anything camera-sized is made.
        let raise = "lower camera.width and camera.height in the scene file";
        ctx.limits.texture(
            "the camera image (camera.width x camera.height)",
            w,
            h,
            raise,
        )?;
        // Summed with what is held already (the scene's buffers); each target reserves
        // its own bytes as it is made.
        ctx.memory.check(
            &format!(
                "the camera-sized targets of {w}x{h} (radiance, G-buffer, depth, fill counts)"
            ),
            u64::from(w) * u64::from(h) * camera_bytes_per_pixel(),
            raise,
        )?;
        let gbuffer_pass = GBufferPass::new(ctx)?;
        let camera_gbuffer = gbuffer_pass.camera_gbuffer(ctx, cam, near, far)?;
        let (camera_view, camera_projection) = (cam.view(), cam.projection(near, far));
        let targets = RadianceTargets::new(ctx, w, h)?;

        // Group 0 of method passes, reflected from frame.wgsl; visible to every stage
        // of every method pass (vertex stages may not write storage).
        let frame_shader = Shader::new(ctx, "frame.wgsl", shader::compose_method(""))?;
        let frame_schema = BindGroupSchema::with_visibility(device, &frame_shader, 0, |b| {
            let writable = matches!(
                b.ty,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    ..
                }
            );
            if writable {
                wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE
            } else {
                wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE
            }
        });
        let frame_uniforms = FrameUniforms {
            view_proj: (camera_projection * camera_view).to_cols_array_2d(),
            eye: cam.eye.extend(cam.fov_y_deg.to_radians()).to_array(),
            forward: cam.forward().extend(0.0).to_array(),
            resolution: [w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32],
            counts: [
                sc.objects.len() as u32,
                sc.materials.len() as u32,
                sc.lights.len() as u32,
                (scene.waves_buffer.size() / 16) as u32,
            ],
        };
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame uniforms"),
            contents: bytemuck::bytes_of(&frame_uniforms),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let fill_counts_bytes = (w as u64 * h as u64 * 4).max(4);
        let fill_counts_memory = ctx
            .memory
            .reserve("fill counts", fill_counts_bytes, raise)?;
        let fill_counts = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fill counts"),
            size: fill_counts_bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind = frame_schema.bind(
            device,
            &[
                ("frame", &frame_buffer),
                ("gbuf_position", &camera_gbuffer.position.view),
                ("gbuf_normal", &camera_gbuffer.normal.view),
                ("gbuf_ids", &camera_gbuffer.ids.view),
                ("objects", &scene.objects_buffer),
                ("materials", &scene.materials_buffer),
                ("lights", &scene.lights_buffer),
                ("waves", &scene.waves_buffer),
                ("fill_counts", &fill_counts),
            ],
        )?;

        let direct = DirectLighting::new(ctx, &gbuffer_pass, &camera_gbuffer, &scene, options)?;
        let bytes = scene.bytes
            + camera_gbuffer.bytes()
            + targets.bytes()
            + fill_counts.size()
            + direct.bytes();
        Ok(Self {
            device: device.clone(),
            scene,
            gbuffer_pass,
            camera_gbuffer,
            direct,
            targets,
            frame_uniforms,
            frame_buffer,
            _fill_counts_memory: fill_counts_memory,
            camera_view,
            camera_projection,
            frame_schema,
            frame_bind,
            fill_counts,
            bytes,
        })
    }

    pub(crate) fn ctx_device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The uploaded scene.
    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// The camera G-buffer.
    pub fn camera_gbuffer(&self) -> &GBuffer {
        &self.camera_gbuffer
    }

    /// The view and shadow map of direct light `i` (fitted to the whole scene): the
    /// scene's lights in order, each extended light as its
    /// [`DIRECT_REPRESENTATIVE_LIGHTS`] representative lights in its place. Methods that
    /// need a light G-buffer fit their own [`LightView`] and allocate one with
    /// [`GBufferPass::light_gbuffer`].
    pub fn light(&self, i: usize) -> Option<(&LightView, &ShadowMap)> {
        self.direct.lights.get(i).map(|l| (&l.view, &l.shadow))
    }

    /// The HDR targets.
    pub fn targets(&self) -> &RadianceTargets {
        &self.targets
    }

    /// Camera, resolution and counts as uploaded (the unshifted camera).
    pub fn frame_uniforms(&self) -> &FrameUniforms {
        &self.frame_uniforms
    }

    /// Shifts the camera by `offset_px` pixels (x right, y down; `[0, 0]` is the pixel
    /// centre) for the frames submitted from now on, in the camera G-buffer's view and
    /// in group 0's `view_proj`, so the base passes and every method pass see the same
    /// camera. A translation after the projection moves the whole image by a sub-pixel
    /// amount and leaves depth and the eye unchanged: the pixel centre then samples the
    /// scene where the continuous pixel position `(i + 0.5 + dx, j + 0.5 + dy)` of the
    /// unshifted camera lies (DESIGN "Camera"). Two uniform writes, no allocation.
    pub fn set_subpixel_offset(&self, queue: &wgpu::Queue, offset_px: [f32; 2]) {
        let [w, h] = [
            self.frame_uniforms.resolution[0],
            self.frame_uniforms.resolution[1],
        ];
        // NDC x grows right and y up; a content shift of −d pixels is +2d/size in NDC
        // along x and −2d/size along y (row 0 at the top).
        let shift = Mat4::from_translation(Vec3::new(
            -2.0 * offset_px[0] / w,
            2.0 * offset_px[1] / h,
            0.0,
        ));
        let view_proj = shift * self.camera_projection * self.camera_view;
        let uniforms = FrameUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            ..self.frame_uniforms
        };
        queue.write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        let eye = self.scene.scene.camera.eye;
        self.camera_gbuffer.write_view(
            queue,
            0,
            &ViewUniform {
                view_proj: view_proj.to_cols_array_2d(),
                eye: eye.extend(1.0).to_array(),
            },
        );
    }

    /// Group 0's schema (its bindings identify cached pipelines).
    pub(crate) fn frame_schema(&self) -> &BindGroupSchema {
        &self.frame_schema
    }

    /// Layout of group 0 (frame.wgsl), for method pipeline layouts.
    pub fn frame_layout(&self) -> &wgpu::BindGroupLayout {
        self.frame_schema.layout()
    }

    /// The group-0 bind group.
    pub fn frame_bind_group(&self) -> &wgpu::BindGroup {
        &self.frame_bind
    }

    /// The G-buffer pass, for methods that rasterize their own light views.
    pub fn gbuffer_pass(&self) -> &GBufferPass {
        &self.gbuffer_pass
    }

    /// Bytes of GPU memory owned by the base renderer (scene, G-buffers, targets).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Starts a frame: clears the targets (and the fill counter in count frames),
    /// then records the base passes: camera G-buffer, shadow maps, direct light.
    pub fn begin_frame<'a>(
        &'a self,
        profiler: &'a mut PassProfiler,
        mode: FrameMode,
    ) -> Result<Frame<'a>, GpuError> {
        self.begin(profiler, mode, false)
    }

    /// Starts a scoring sub-frame ([`FrameMode::Score`]). With `reuse_light_side` the
    /// frame keeps the light-side work of the frame before it ([`Frame::reuses_light_side`]):
    /// the base passes skip the shadow maps (they depend on the lights and the scene, not
    /// on the camera), and methods skip their own light-side passes. The caller must have
    /// rendered a whole frame of this scene and method just before, with nothing changed
    /// since but the sub-pixel offset (`caustics_method::render_scoring_frame` does).
    pub fn begin_scoring_subframe<'a>(
        &'a self,
        profiler: &'a mut PassProfiler,
        reuse_light_side: bool,
    ) -> Result<Frame<'a>, GpuError> {
        self.begin(profiler, FrameMode::Score, reuse_light_side)
    }

    fn begin<'a>(
        &'a self,
        profiler: &'a mut PassProfiler,
        mode: FrameMode,
        reuse_light_side: bool,
    ) -> Result<Frame<'a>, GpuError> {
        let mut frame = Frame::new(self, profiler, mode, reuse_light_side)?;
        if mode == FrameMode::Count {
            frame.encoder.clear_buffer(&self.fill_counts, 0, None);
        }
        let clear = |t: &'a crate::textures::Target| {
            Some(wgpu::RenderPassColorAttachment {
                view: &t.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        {
            let attachments = [
                clear(&self.targets.direct),
                clear(&self.targets.surface),
                clear(&self.targets.volume),
            ];
            let _pass = frame.render_pass("base/clear_targets", pass_desc(&attachments))?;
        }
        self.gbuffer_pass.record(
            &mut frame,
            "base/camera_gbuffer",
            &self.scene,
            &self.camera_gbuffer,
        )?;
        self.direct
            .record(&mut frame, &self.gbuffer_pass, &self.scene, &self.targets)?;
        Ok(frame)
    }

    /// Reads the per-pixel fragment counts of the last count frame (row 0 top).
    pub fn read_fill_counts(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        crate::readback::read_buffer_u32(
            ctx,
            &self.fill_counts,
            self.fill_counts.size(),
            "fill counts",
        )
    }
}

/// A render-pass descriptor with colour attachments only.
pub(crate) fn pass_desc<'a>(
    attachments: &'a [Option<wgpu::RenderPassColorAttachment<'a>>],
) -> wgpu::RenderPassDescriptor<'a> {
    wgpu::RenderPassDescriptor {
        label: None,
        color_attachments: attachments,
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    }
}

/// Bytes per camera pixel of the base renderer's camera-sized resources: the three
/// radiance targets, the camera G-buffer and its depth, the fill counts.
fn camera_bytes_per_pixel() -> u64 {
    use crate::textures::{HDR_FORMAT, IDS_FORMAT, NORMAL_FORMAT, POSITION_FORMAT};
    let texel = |f: wgpu::TextureFormat| u64::from(f.block_copy_size(None).unwrap_or(16));
    3 * texel(HDR_FORMAT) + texel(POSITION_FORMAT) + texel(NORMAL_FORMAT) + texel(IDS_FORMAT)
        + 4 // Depth32Float
        + 4 // one u32 fill count
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniforms_match_their_wgsl() {
        crate::assert_wgsl_layout!(
            shader::compose_method(""),
            FrameUniforms {
                view_proj,
                eye,
                forward,
                resolution,
                counts
            }
        );
        crate::assert_wgsl_layout!(shader::compose(shader::DIRECT_WGSL), DirectUniform as "DirectLight" { light, face_view_proj, params });
    }
}
