//! Camera and light-space G-buffers: world position, smooth normal, object and
//! material ids and depth, rasterized from any view. A light's view is general:
//! orthographic for a directional light, one perspective face for a spot light,
//! six perspective faces (a cube) for a point light.

use bytemuck::{Pod, Zeroable};
use caustics_scene::{Aabb, Camera, Light, Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::frame::Frame;
use crate::pass::{BindGroupSchema, RasterPass, Shader};
use crate::{GpuContext, GpuError};
use crate::scene_upload::{GpuScene, SceneVertex};
use crate::shader;
use crate::textures::{DEPTH_FORMAT, IDS_FORMAT, NORMAL_FORMAT, POSITION_FORMAT, Target};

/// Uniforms of one rasterized view (matches `View` in gbuffer.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewUniform {
    /// World to clip.
    pub view_proj: [[f32; 4]; 4],
    /// Eye position (perspective) or the view's centre (orthographic).
    pub eye: [f32; 4],
}

/// How a light G-buffer projects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightProjection {
    /// Directional light: one orthographic face.
    Orthographic,
    /// Spot light: one perspective face covering the cone.
    Perspective,
    /// Point light: six 90° perspective faces, order +X, −X, +Y, −Y, +Z, −Z.
    Cube,
}

/// One face of a light's view.
#[derive(Clone, Copy, Debug)]
pub struct LightFace {
    /// World to view.
    pub view: Mat4,
    /// View to clip (depth 0..1).
    pub proj: Mat4,
    /// World to clip.
    pub view_proj: Mat4,
}

/// A light's view: faces, resolution and texel footprint.
#[derive(Clone, Debug)]
pub struct LightView {
    /// Projection kind.
    pub projection: LightProjection,
    /// 1 or 6 faces.
    pub faces: Vec<LightFace>,
    /// Square resolution of each face (texels).
    pub resolution: u32,
    /// World size of a texel: in metres for orthographic views, per metre of distance
    /// from the light for perspective ones.
    pub texel_size: f32,
    /// Light position (point/spot) or the centre of the fitted volume (directional).
    pub origin: Vec3,
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() < 0.99 { Vec3::Y } else { Vec3::Z }
}

impl LightView {
    /// Fits the light's view around `bounds` (e.g. the whole scene for shadows, or
    /// only the specular objects for photon generation).
    pub fn fit(light: &Light, bounds: &Aabb, resolution: u32) -> Self {
        let center = bounds.center();
        let radius = bounds.bounding_sphere_radius().max(1e-3);
        let far_from = |p: Vec3| {
            let far = bounds
                .corners()
                .iter()
                .map(|c| (*c - p).length())
                .fold(0.0, f32::max);
            far * 1.01 + 1e-3
        };
        match *light {
            Light::Directional { direction, .. } => {
                let eye = center - direction * (2.0 * radius);
                let view = Mat4::look_at_rh(eye, center, any_up(direction));
                let proj =
                    Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.0, 4.0 * radius);
                Self {
                    projection: LightProjection::Orthographic,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * radius / resolution as f32,
                    origin: center,
                }
            }
            Light::Spot {
                position,
                direction,
                cone_deg,
                ..
            } => {
                let fov = (2.0 * cone_deg).clamp(1.0, 170.0).to_radians();
                let far = far_from(position);
                let near = (far * 1e-4).max(1e-4);
                let view = Mat4::look_at_rh(position, position + direction, any_up(direction));
                let proj = Mat4::perspective_rh(fov, 1.0, near, far);
                Self {
                    projection: LightProjection::Perspective,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * (fov * 0.5).tan() / resolution as f32,
                    origin: position,
                }
            }
            Light::Point { position, .. } => {
                let far = far_from(position);
                let near = (far * 1e-4).max(1e-4);
                let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
                let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
                let faces = dirs
                    .iter()
                    .map(|&d| {
                        let view = Mat4::look_at_rh(position, position + d, any_up(d));
                        LightFace {
                            view,
                            proj,
                            view_proj: proj * view,
                        }
                    })
                    .collect();
                Self {
                    projection: LightProjection::Cube,
                    faces,
                    resolution,
                    texel_size: 2.0 / resolution as f32,
                    origin: position,
                }
            }
        }
    }
}

impl LightView {
    /// One face of the light that just covers `points` (e.g. the vertices of the
    /// caustic generators): an orthographic square around their projection for a
    /// directional light, a perspective square cone towards them for a point or spot
    /// light (a point light is treated as a spot aimed at them, so the specular objects
    /// get the whole resolution instead of a sixth of a cube). None when `points` is
    /// empty or a positional light sits among them (no cone can hold them).
    pub fn fit_points(light: &Light, points: &[Vec3], resolution: u32) -> Option<Self> {
        points.first()?;
        match *light {
            Light::Directional { direction, .. } => {
                let dir = direction.normalize();
                let up = any_up(dir);
                let right = dir.cross(up).normalize();
                let up = right.cross(dir);
                let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
                for p in points {
                    let q = Vec3::new(p.dot(right), p.dot(up), p.dot(dir));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                // No margin: grid corners on the border of the view land on the generators' edges.
                let half = 0.5 * (hi.x - lo.x).max(hi.y - lo.y) * (1.0 + 1e-5) + 1e-6;
                let mid = 0.5 * (lo + hi);
                let depth = (hi.z - lo.z).max(1e-3);
                // The eye sits one depth before the nearest point, on the centre line.
                let eye = right * mid.x + up * mid.y + dir * (lo.z - depth);
                let view = Mat4::look_at_rh(eye, eye + dir, up);
                let proj = Mat4::orthographic_rh(-half, half, -half, half, 0.0, 3.0 * depth);
                Some(Self {
                    projection: LightProjection::Orthographic,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * half / resolution as f32,
                    origin: eye + dir * depth,
                })
            }
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                let centroid = points.iter().fold(Vec3::ZERO, |a, p| a + *p) / points.len() as f32;
                let axis = (centroid - position).try_normalize()?;
                let up = any_up(axis);
                let right = axis.cross(up).normalize();
                let up = right.cross(axis);
                let (mut tan_max, mut near, mut far) = (0.0f32, f32::MAX, 0.0f32);
                for p in points {
                    let v = *p - position;
                    let z = v.dot(axis);
                    if z <= 1e-4 * v.length().max(1e-6) {
                        return None;
                    }
                    tan_max = tan_max.max(v.dot(right).abs() / z).max(v.dot(up).abs() / z);
                    near = near.min(z);
                    far = far.max(v.length());
                }
                let fov = 2.0 * (tan_max * (1.0 + 1e-5) + 1e-6).atan();
                if fov >= std::f32::consts::PI * 0.95 {
                    return None;
                }
                let view = Mat4::look_at_rh(position, position + axis, up);
                let proj = Mat4::perspective_rh(fov, 1.0, (near * 0.5).max(1e-4), far * 1.01);
                Some(Self {
                    projection: LightProjection::Perspective,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * (fov * 0.5).tan() / resolution as f32,
                    origin: position,
                })
            }
        }
    }
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
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        // Open cylinders, quads and heightfields are seen from both sides: no culling.
        let vertex_buffers = [Some(SceneVertex::LAYOUT)];
        let full = RasterPass::builder(ctx, "gbuffer", &shader, "vs_main")
            .caller_group(0)
            .vertex_buffers(&vertex_buffers)
            .depth_stencil(depth_state())
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
            .depth_stencil(depth_state())
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
    pub fn shadow_map(
        &self,
        device: &wgpu::Device,
        view: &LightView,
    ) -> Result<ShadowMap, GpuError> {
        let layers = view.faces.len() as u32;
        let res = view.resolution;
        Ok(ShadowMap {
            depth: Target::new(
                device,
                "shadow map",
                DEPTH_FORMAT,
                res,
                res,
                layers,
                wgpu::TextureUsages::empty(),
            ),
            views: self.view_binds(device, "shadow map", &light_view_uniforms(view))?,
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
        device: &wgpu::Device,
        label: &str,
        width: u32,
        height: u32,
        views: &[ViewUniform],
    ) -> Result<GBuffer, GpuError> {
        let layers = views.len() as u32;
        let none = wgpu::TextureUsages::empty();
        let views = self.view_binds(device, label, views)?;
        Ok(GBuffer {
            position: Target::new(
                device,
                &format!("{label} position"),
                POSITION_FORMAT,
                width,
                height,
                layers,
                none,
            ),
            normal: Target::new(
                device,
                &format!("{label} normal"),
                NORMAL_FORMAT,
                width,
                height,
                layers,
                none,
            ),
            ids: Target::new(
                device,
                &format!("{label} ids"),
                IDS_FORMAT,
                width,
                height,
                layers,
                none,
            ),
            depth: Target::new(
                device,
                &format!("{label} depth"),
                DEPTH_FORMAT,
                width,
                height,
                layers,
                none,
            ),
            views,
            size: (width, height),
        })
    }

    /// Allocates the camera G-buffer at the camera's resolution.
    pub fn camera_gbuffer(
        &self,
        device: &wgpu::Device,
        camera: &Camera,
        near: f32,
        far: f32,
    ) -> Result<GBuffer, GpuError> {
        let vp = camera.projection(near, far) * camera.view();
        let u = ViewUniform {
            view_proj: vp.to_cols_array_2d(),
            eye: camera.eye.extend(1.0).to_array(),
        };
        self.allocate(device, "camera gbuffer", camera.width, camera.height, &[u])
    }

    /// Allocates a light G-buffer, one layer per face of `view`.
    pub fn light_gbuffer(
        &self,
        device: &wgpu::Device,
        view: &LightView,
    ) -> Result<GBuffer, GpuError> {
        self.allocate(
            device,
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

fn depth_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
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
