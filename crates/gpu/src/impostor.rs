//! Distance impostors (Szirmay-Kalos et al. 2005): a cube map around a centre that
//! stores, per direction, the distance to (and the normal of) the nearest surface of
//! chosen objects. Rays are then traced against it in any shader with
//! `impostor_trace` ([`IMPOSTOR_TRACE_WGSL`]): the exit point of a ray inside a closed
//! refractor (Liktor & Dachsbacher 2011, Sect. 6; Umenhoffer et al.'s distance maps),
//! the next specular surface a beam meets, or the diffuse receiver a photon lands on.
//!
//! The cube map is a 6-layer 2D array (+X, −X, +Y, −Y, +Z, −Z) rather than a cube
//! texture: the shaders pick the face and texel themselves, so lookups are exact and
//! identical on every adapter (lavapipe's cube sampling misplaces long vectors; see
//! the pinhole crate).

use bytemuck::{Pod, Zeroable};
use caustics_scene::{Aabb, Vec3};
use wgpu::util::DeviceExt;

use crate::frame::Frame;
use crate::pass::{RasterPass, Shader};
use crate::scene_upload::{GpuScene, SceneVertex};
use crate::shader;
use crate::textures::{DEPTH_FORMAT, Target, depth_test_state, opaque_target};
use crate::{GpuContext, GpuError};

/// Render pass of an impostor (vertex + fragment), composed with `common.wgsl`.
pub const IMPOSTOR_RENDER_WGSL: &str = include_str!("shaders/impostor_render.wgsl");
/// `impostor_face_uv`, `impostor_fetch`, `impostor_object`, `impostor_trace`: compose
/// into any pass that traces rays against an impostor.
pub const IMPOSTOR_TRACE_WGSL: &str = include_str!("shaders/impostor_trace.wgsl");

/// Normal (xyz) and distance from the centre (w; 0 = no surface).
pub const IMPOSTOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Object index of the stored surface.
pub const IMPOSTOR_IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ImpostorView {
    view_proj: [[f32; 4]; 4],
    center: [f32; 4],
}

/// World-to-clip matrix of face `face` (0..6) of a cube around `center`, in the one
/// cube-face convention of [`crate::light_view::CUBE_FACES`].
pub use crate::light_view::cube_face_view_proj as face_view_proj;

/// One distance impostor: its textures, centre and reach.
pub struct DistanceImpostor {
    /// Normal and distance, 6 layers ([`IMPOSTOR_FORMAT`]).
    pub normal_distance: Target,
    /// Object index, 6 layers ([`IMPOSTOR_IDS_FORMAT`]).
    pub object_ids: Target,
    depth: Target,
    views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    /// Reference point (world, m).
    pub center: Vec3,
    /// Distance from `center` to the farthest corner of the objects' bounds (m): a ray
    /// search never needs to go farther than this past the centre.
    pub reach: f32,
    /// Objects drawn (indices into the scene's objects).
    pub objects: Vec<usize>,
    /// Texels per face side.
    pub resolution: u32,
}

impl DistanceImpostor {
    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.normal_distance.bytes + self.object_ids.bytes + self.depth.bytes
    }
}

/// Bounds of the given objects' tessellated triangles.
pub fn objects_bounds(scene: &GpuScene, objects: &[usize]) -> Option<Aabb> {
    let mut bounds: Option<Aabb> = None;
    for &o in objects {
        for &p in &scene.meshes[o].positions {
            let b = Aabb { min: p, max: p };
            bounds = Some(bounds.map_or(b, |acc| acc.union(&b)));
        }
    }
    bounds
}

/// The impostor render pass (built by each method that traces impostors); each face's
/// view uniform is its group 0, set per face.
pub struct ImpostorPass {
    pass: RasterPass,
}

impl ImpostorPass {
    /// Builds the pass.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let shader = Shader::new(
            ctx,
            "impostor_render.wgsl",
            shader::compose(IMPOSTOR_RENDER_WGSL),
        )?;
        let target = opaque_target;
        let vertex_buffers = [Some(SceneVertex::LAYOUT)];
        let pass = RasterPass::builder(ctx, "distance impostor", &shader, "vs_main")
            .caller_group(0)
            .vertex_buffers(&vertex_buffers)
            .depth_stencil(depth_test_state())
            .fragment(
                "fs_main",
                &[target(IMPOSTOR_FORMAT), target(IMPOSTOR_IDS_FORMAT)],
            )
            .build()?;
        Ok(Self { pass })
    }

    /// Allocates an impostor of `objects` around the centre of their bounds.
    pub fn impostor(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        objects: &[usize],
        resolution: u32,
    ) -> Result<DistanceImpostor, GpuError> {
        let bounds = objects_bounds(scene, objects)
            .ok_or_else(|| GpuError::Invalid("distance impostor of no objects".into()))?;
        self.impostor_around(ctx, scene, objects, bounds.center(), resolution)
    }

    /// Allocates an impostor of `objects` around `center` (e.g. the diffuse receivers
    /// around a refractor's centre, Umenhoffer's distance map of the environment).
    pub fn impostor_around(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        objects: &[usize],
        center: Vec3,
        resolution: u32,
    ) -> Result<DistanceImpostor, GpuError> {
        let bounds = objects_bounds(scene, objects)
            .ok_or_else(|| GpuError::Invalid("distance impostor of no objects".into()))?;
        if resolution == 0 {
            return Err(GpuError::Invalid("distance impostor resolution 0".into()));
        }
        let reach = reach_from(&bounds, center);
        let views = self.face_binds(&ctx.device, center, reach)?;
        let none = wgpu::TextureUsages::empty();
        Ok(DistanceImpostor {
            normal_distance: Target::new(
                ctx,
                "impostor normal+distance",
                IMPOSTOR_FORMAT,
                resolution,
                resolution,
                6,
                none,
            )?,
            object_ids: Target::new(
                ctx,
                "impostor object",
                IMPOSTOR_IDS_FORMAT,
                resolution,
                resolution,
                6,
                none,
            )?,
            depth: Target::new(
                ctx,
                "impostor depth",
                DEPTH_FORMAT,
                resolution,
                resolution,
                6,
                none,
            )?,
            views,
            center,
            reach,
            objects: objects.to_vec(),
            resolution,
        })
    }

    /// Records the six faces of `impostor`, one profiled render pass each named `name`.
    /// Call once per scene (the geometry is static) or per frame for animated scenes.
    pub fn record(
        &self,
        frame: &mut Frame<'_>,
        name: &str,
        scene: &GpuScene,
        impostor: &DistanceImpostor,
    ) -> Result<(), GpuError> {
        for (face, (_, bind)) in impostor.views.iter().enumerate() {
            self.draw_face(
                frame,
                name,
                scene,
                &impostor.objects,
                bind,
                [
                    &impostor.normal_distance.layer_views[face],
                    &impostor.object_ids.layer_views[face],
                ],
                &impostor.depth.layer_views[face],
            )?;
        }
        Ok(())
    }

    /// Allocates an atlas of impostors, each of `objects` around `center` (None: the
    /// centre of their bounds), six layers each, in one pair of textures: a shader
    /// then traces any of them through one binding and one call site
    /// (`impostor_trace_at` with `6 × index` as the first layer).
    pub fn atlas(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        entries: &[(Vec<usize>, Option<Vec3>)],
        resolution: u32,
    ) -> Result<ImpostorAtlas, GpuError> {
        if entries.is_empty() || resolution == 0 {
            return Err(GpuError::Invalid(
                "impostor atlas of no entries or resolution 0".into(),
            ));
        }
        let mut out = Vec::new();
        for (objects, center) in entries {
            let bounds = objects_bounds(scene, objects).ok_or_else(|| {
                GpuError::Invalid("atlas entry: distance impostor of no objects".into())
            })?;
            let center = center.unwrap_or_else(|| bounds.center());
            let reach = reach_from(&bounds, center);
            out.push(AtlasEntry {
                objects: objects.clone(),
                center,
                reach,
                views: self.face_binds(&ctx.device, center, reach)?,
            });
        }
        let layers = 6 * entries.len() as u32;
        let none = wgpu::TextureUsages::empty();
        let target =
            |label, format| Target::new(ctx, label, format, resolution, resolution, layers, none);
        Ok(ImpostorAtlas {
            normal_distance: target("impostor atlas normal+distance", IMPOSTOR_FORMAT)?,
            object_ids: target("impostor atlas object", IMPOSTOR_IDS_FORMAT)?,
            depth: Target::new(
                ctx,
                "impostor atlas depth",
                DEPTH_FORMAT,
                resolution,
                resolution,
                1,
                none,
            )?,
            entries: out,
            resolution,
        })
    }

    /// Records every face of every impostor of `atlas` (profiled passes named `name`).
    pub fn record_atlas(
        &self,
        frame: &mut Frame<'_>,
        name: &str,
        scene: &GpuScene,
        atlas: &ImpostorAtlas,
    ) -> Result<(), GpuError> {
        for (k, entry) in atlas.entries.iter().enumerate() {
            for (face, (_, bind)) in entry.views.iter().enumerate() {
                let layer = 6 * k + face;
                self.draw_face(
                    frame,
                    name,
                    scene,
                    &entry.objects,
                    bind,
                    [
                        &atlas.normal_distance.layer_views[layer],
                        &atlas.object_ids.layer_views[layer],
                    ],
                    &atlas.depth.view,
                )?;
            }
        }
        Ok(())
    }

    /// Six per-face view uniforms around `center` reaching `reach`.
    fn face_binds(
        &self,
        device: &wgpu::Device,
        center: Vec3,
        reach: f32,
    ) -> Result<Vec<(wgpu::Buffer, wgpu::BindGroup)>, GpuError> {
        let far = reach * 1.01 + 1e-3;
        let near = (far * 1e-5).max(1e-5);
        (0..6)
            .map(|face| {
                let uniform = ImpostorView {
                    view_proj: face_view_proj(face, center, near, far).to_cols_array_2d(),
                    center: center.extend(1.0).to_array(),
                };
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("impostor view"),
                    contents: bytemuck::bytes_of(&uniform),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let schema = self.pass.schema(0).ok_or_else(|| {
                    GpuError::Invalid("impostor_render.wgsl declares no group 0".into())
                })?;
                let bind = schema.bind(device, &[("view", &buffer)])?;
                Ok((buffer, bind))
            })
            .collect()
    }

    #[allow(clippy::too_many_arguments)]
    fn draw_face(
        &self,
        frame: &mut Frame<'_>,
        name: &str,
        scene: &GpuScene,
        objects: &[usize],
        bind: &wgpu::BindGroup,
        colors: [&wgpu::TextureView; 2],
        depth: &wgpu::TextureView,
    ) -> Result<(), GpuError> {
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let attachments = [clear(colors[0]), clear(colors[1])];
        let depth = wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        };
        let mut pass = self.pass.begin_as(frame, name, &attachments, Some(depth))?;
        pass.set_bind_group(0, bind, &[]);
        pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
        pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for &o in objects {
            let draw = scene.draws[o];
            pass.draw_indexed(
                draw.first_index..draw.first_index + draw.index_count,
                0,
                0..1,
            );
        }
        Ok(())
    }
}

/// Distance from `center` to the farthest corner of `bounds`.
fn reach_from(bounds: &Aabb, center: Vec3) -> f32 {
    bounds
        .corners()
        .iter()
        .map(|c| (*c - center).length())
        .fold(0.0, f32::max)
}

/// One impostor of an [`ImpostorAtlas`].
pub struct AtlasEntry {
    /// Objects drawn.
    pub objects: Vec<usize>,
    /// Reference point (world, m).
    pub center: Vec3,
    /// Distance to the farthest corner of the objects' bounds (m).
    pub reach: f32,
    views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
}

/// Several distance impostors in one pair of 6·N-layer textures (entry k: layers
/// 6k..6k+6), traced through one binding.
pub struct ImpostorAtlas {
    /// Normal and distance ([`IMPOSTOR_FORMAT`]).
    pub normal_distance: Target,
    /// Object index ([`IMPOSTOR_IDS_FORMAT`]).
    pub object_ids: Target,
    depth: Target,
    /// The impostors, in layer order.
    pub entries: Vec<AtlasEntry>,
    /// Texels per face side.
    pub resolution: u32,
}

impl ImpostorAtlas {
    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.normal_distance.bytes + self.object_ids.bytes + self.depth.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn impostor_view_matches_its_wgsl() {
        crate::assert_wgsl_layout!(
            shader::compose(IMPOSTOR_RENDER_WGSL),
            ImpostorView { view_proj, center }
        );
    }

    #[test]
    fn impostor_shaders_validate() -> Result<(), String> {
        shader::validate_wgsl(
            "impostor_render.wgsl",
            &shader::compose(IMPOSTOR_RENDER_WGSL),
        )?;
        shader::validate_wgsl("impostor_trace.wgsl", &shader::compose(IMPOSTOR_TRACE_WGSL))
    }

    /// The projection of each face puts a direction where `impostor_face_uv` (WGSL,
    /// mirrored here) looks for it.
    #[test]
    fn faces_match_the_lookup_convention() {
        fn face_uv(d: Vec3) -> (usize, f32, f32) {
            let a = d.abs();
            let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
                if d.x > 0.0 {
                    (0, -d.z, -d.y, a.x)
                } else {
                    (1, d.z, -d.y, a.x)
                }
            } else if a.y >= a.z {
                if d.y > 0.0 {
                    (2, d.x, d.z, a.y)
                } else {
                    (3, d.x, -d.z, a.y)
                }
            } else if d.z > 0.0 {
                (4, d.x, -d.y, a.z)
            } else {
                (5, -d.x, -d.y, a.z)
            };
            (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
        }
        let center = Vec3::new(0.3, -1.0, 2.0);
        for d in [
            Vec3::new(1.0, 0.2, -0.3),
            Vec3::new(-1.0, 0.5, 0.4),
            Vec3::new(0.3, 1.0, -0.6),
            Vec3::new(-0.2, -1.0, 0.7),
            Vec3::new(0.4, -0.3, 1.0),
            Vec3::new(-0.6, 0.1, -1.0),
        ] {
            let (face, u, v) = face_uv(d);
            let clip = face_view_proj(face, center, 0.01, 10.0) * (center + d).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            // Texture coordinates of the rasterized point: u = (x + 1)/2, v = (1 − y)/2.
            assert!(
                (0.5 * (ndc.x + 1.0) - u).abs() < 1e-5,
                "face {face} u for {d}"
            );
            assert!(
                (0.5 * (1.0 - ndc.y) - v).abs() < 1e-5,
                "face {face} v for {d}"
            );
            assert!((0.0..=1.0).contains(&ndc.z), "face {face} depth for {d}");
        }
    }
}
