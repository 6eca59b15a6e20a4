//! The caustic ("light") cube map of §4.2 and the camera pass of §4.3.
//!
//! The six faces live side by side in one 3×2 atlas texture (face f at column f % 3,
//! row f / 3), so that a method reconstructs all of them in one render pass, one
//! viewport per face, instead of six passes; the face order, orientation and texel
//! convention are those of the distance impostors (`impostor_face_uv`,
//! [`caustics_gpu::impostor::face_view_proj`]), so lookups and rasterization agree.

use bytemuck::{Pod, Zeroable};
use caustics_gpu::impostor::face_view_proj;
use caustics_gpu::pass::{RasterPass, Shader};
use caustics_gpu::textures::{HDR_FORMAT, Target, additive_hdr_target, load_attachment};
use caustics_gpu::wgpu;
use caustics_gpu::{Frame, GpuContext, GpuError, Renderer};
use caustics_method::MethodError;
use caustics_method::params::Raster;
use caustics_scene::{Mat4, Vec3};

use caustics_gpu::buffers::uniform_buffer;

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
    lookup: RasterPass,
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
        Self::with_atlas_usage(
            ctx,
            renderer,
            method,
            center,
            reach,
            config,
            wgpu::TextureUsages::empty(),
        )
    }

    /// [`CausticMap::new`] around `hits`' generator for a reconstruction on `raster`'s
    /// path (the compute path's resolve writes the atlas as a storage texture).
    pub fn for_raster(
        ctx: &GpuContext,
        renderer: &Renderer,
        method: &'static str,
        hits: &crate::PhotonHits,
        config: &PhotonHitConfig,
        raster: Raster,
    ) -> Result<Self, MethodError> {
        let usage = match raster {
            Raster::Hardware => wgpu::TextureUsages::empty(),
            Raster::Compute => wgpu::TextureUsages::STORAGE_BINDING,
        };
        Self::with_atlas_usage(
            ctx,
            renderer,
            method,
            hits.center,
            hits.reach,
            config,
            usage,
        )
    }

    /// [`CausticMap::new`] with `usage` added to the atlas's (e.g. `STORAGE_BINDING`
    /// for a compute pass that writes it).
    pub fn with_atlas_usage(
        ctx: &GpuContext,
        renderer: &Renderer,
        method: &'static str,
        center: Vec3,
        reach: f32,
        config: &PhotonHitConfig,
        usage: wgpu::TextureUsages,
    ) -> Result<Self, MethodError> {
        let device = &ctx.device;
        let size = config.cube_size;
        let far = reach * 1.01 + 1e-3;
        let near = (far * 1e-5).max(1e-5);
        let faces: [Mat4; 6] = std::array::from_fn(|f| face_view_proj(f, center, near, far));
        // The atlas is sized by a parameter: refused naming it, before it is made.
        let what = format!(
            "cube_size: the caustic cube map atlas ({}x{} texels)",
            3 * size,
            2 * size
        );
        let raise = "lower cube_size";
        let param = |e: GpuError| MethodError::Param {
            method,
            message: e.to_string(),
        };
        ctx.limits
            .texture(&what, 3 * size, 2 * size, raise)
            .map_err(param)?;
        ctx.memory
            .check(
                &what,
                Target::bytes_of(HDR_FORMAT, 3 * size, 2 * size, 1),
                raise,
            )
            .map_err(param)?;
        let (atlas, uniform) = ctx.checked("caustic cube map setup", || {
            let atlas = Target::new(
                ctx,
                "caustic cube map",
                HDR_FORMAT,
                3 * size,
                2 * size,
                1,
                usage,
            )?;
            let uniform = uniform_buffer(
                device,
                "caustic cube map",
                &MapUniform {
                    face_view_proj: faces.map(|m| m.to_cols_array_2d()),
                    center: center.extend(0.0).to_array(),
                    params: [
                        size as f32,
                        if config.distance_test { 1.0 } else { 0.0 },
                        config.distance_tolerance as f32,
                        0.0,
                    ],
                },
            );
            Ok::<_, GpuError>((atlas, uniform))
        })??;
        let lookup = lookup_pass(ctx, renderer, method, &uniform, &atlas)?;
        Ok(Self {
            bytes: atlas.bytes + uniform.size(),
            atlas,
            size,
            center,
            faces,
            uniform,
            lookup,
        })
    }

    /// The `CausticMapUniform` buffer, for the reconstruction passes' bind groups.
    pub fn uniform(&self) -> &wgpu::Buffer {
        &self.uniform
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

    /// The atlas as the colour attachment of a further reconstruction pass, which adds
    /// to what the first one drew.
    pub fn added_attachment(&self) -> [Option<wgpu::RenderPassColorAttachment<'_>>; 1] {
        [Some(wgpu::RenderPassColorAttachment {
            view: &self.atlas.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
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
        let target = [load_attachment(&renderer.targets().surface.view)];
        self.lookup.begin(frame, &target, None)?.draw_fullscreen();
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

/// §4.3: the camera pass, at camera resolution (fill-counted), adding into the
/// surface caustic target.
fn lookup_pass(
    ctx: &GpuContext,
    renderer: &Renderer,
    method: &str,
    uniform: &wgpu::Buffer,
    atlas: &Target,
) -> Result<RasterPass, GpuError> {
    let shader = Shader::new(ctx, "photon-hits lookup.wgsl", compose(LOOKUP_WGSL))?;
    let name = format!("{method}/camera_lookup");
    RasterPass::fullscreen(
        ctx,
        &name,
        &shader,
        "fs_lookup",
        &[Some(additive_hdr_target())],
    )
    .frame(renderer)
    .bind(1, &[("cm", uniform), ("caustic_atlas", &atlas.view)])
    .counted()
    .build()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_uniform_matches_its_wgsl() {
        caustics_gpu::assert_wgsl_layout!(
            compose(LOOKUP_WGSL),
            MapUniform as "CausticMapUniform" { face_view_proj, center, params }
        );
    }
}
