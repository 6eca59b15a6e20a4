//! One upload per scene: triangles for rasterization, and the analytic shape, material
//! and light tables every shader reads (layouts mirrored in `shaders/common.wgsl`).

use std::sync::{Arc, OnceLock};

use bytemuck::{Pod, Zeroable};
use caustics_scene::{Light, Material, Scene, Shape, Tessellation, TriangleMesh};
use wgpu::util::DeviceExt;

use crate::limits::Reservation;
use crate::triangle_bvh::SceneTriangles;
use crate::{GpuContext, GpuError};

/// Vertex of the rasterized scene: world position, world normal, object and material ids.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SceneVertex {
    /// World-space position (m).
    pub position: [f32; 3],
    /// World-space unit normal (smooth: vertex normals or the analytic normal).
    pub normal: [f32; 3],
    /// Index into `Scene::objects`.
    pub object: u32,
    /// Index into `Scene::materials`.
    pub material: u32,
}

impl SceneVertex {
    /// Vertex buffer layout matching `SceneVertex` (locations 0..=2).
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<SceneVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32x2],
    };
}

/// Shape kinds as the shaders number them (`OBJ_*` in common.wgsl).
pub mod shape_kind {
    /// Analytic sphere: p0 = (center, radius).
    pub const SPHERE: u32 = 0;
    /// Rectangle: p0 = (center, half size u), p1 = (normal, half size v), p2 = u axis, p3 = v axis.
    pub const QUAD: u32 = 1;
    /// Heightfield of sine waves: p0 = (center, first wave index), p1 = (size.x, size.y, wave count, 0).
    pub const HEIGHTFIELD: u32 = 2;
    /// Open cylinder: p0 = (center, radius), p1 = (axis, half height).
    pub const CYLINDER: u32 = 3;
    /// Triangle mesh (no analytic form).
    pub const MESH: u32 = 4;
}

/// Material kinds as the shaders number them (`MAT_*` in common.wgsl).
pub mod material_kind {
    /// Lambertian, `color` = albedo.
    pub const DIFFUSE: u32 = 0;
    /// Smooth dielectric, `ior` relative to the outside (1.0).
    pub const DIELECTRIC: u32 = 1;
    /// Mirror, `color` = reflectance at every angle.
    pub const MIRROR: u32 = 2;
}

/// Light kinds as the shaders number them (`LIGHT_*` in common.wgsl).
pub mod light_kind {
    /// Directional: `power` = irradiance (W/m²) on a surface facing the light.
    pub const DIRECTIONAL: u32 = 0;
    /// Point: `power` = intensity (W/sr).
    pub const POINT: u32 = 1;
    /// Spot: point light times the cone factor.
    pub const SPOT: u32 = 2;
}

/// Analytic description of one object (std430 layout, 80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct GpuObject {
    /// `shape_kind::*`.
    pub kind: u32,
    /// Index into the material table.
    pub material: u32,
    /// Index of the object's first triangle in the scene index buffer / 3.
    pub first_triangle: u32,
    /// Number of triangles of its tessellation.
    pub triangle_count: u32,
    /// Shape parameters, see `shape_kind`.
    pub p0: [f32; 4],
    /// Shape parameters, see `shape_kind`.
    pub p1: [f32; 4],
    /// Shape parameters, see `shape_kind`.
    pub p2: [f32; 4],
    /// Shape parameters, see `shape_kind`.
    pub p3: [f32; 4],
}

/// One material (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct GpuMaterial {
    /// `material_kind::*`.
    pub kind: u32,
    /// Index of refraction (dielectrics), 1 otherwise.
    pub ior: f32,
    /// Padding.
    pub _pad: [u32; 2],
    /// Albedo (diffuse) or reflectance (mirror), linear RGB; alpha unused.
    pub color: [f32; 4],
}

/// One light (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct GpuLight {
    /// `light_kind::*`.
    pub kind: u32,
    /// Spot: half angle of the cone (radians).
    pub cone_rad: f32,
    /// Spot: width of the smooth falloff inside the edge (radians, 0 = hard edge).
    pub falloff_rad: f32,
    /// Padding.
    pub _pad: u32,
    /// Point/spot position (m).
    pub position: [f32; 4],
    /// Directional/spot unit direction the light travels.
    pub direction: [f32; 4],
    /// Irradiance (directional, W/m²) or intensity (point/spot, W/sr), linear RGB.
    pub power: [f32; 4],
}

/// One sine wave of a heightfield (16 bytes): (2π/λ·d̂.x, 2π/λ·d̂.y, amplitude, phase).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct GpuWave {
    /// Wave vector k = 2π/λ · d̂ (rad/m) in (x, z), amplitude (m), phase (rad).
    pub k_amp_phase: [f32; 4],
}

/// Index range of one object in the scene's index buffer.
#[derive(Clone, Copy, Debug)]
pub struct ObjectDraw {
    /// First index.
    pub first_index: u32,
    /// Number of indices.
    pub index_count: u32,
}

/// A scene uploaded to the GPU: created once, shared by the base passes and every method.
pub struct GpuScene {
    /// The scene it came from.
    pub scene: Arc<Scene>,
    /// Tessellation used for rasterization.
    pub tessellation: Tessellation,
    /// Each object's triangles on the CPU (world space), index-aligned with `scene.objects`.
    pub meshes: Vec<TriangleMesh>,
    /// All objects' vertices.
    pub vertex_buffer: wgpu::Buffer,
    /// All objects' indices (already offset into the shared vertex buffer).
    pub index_buffer: wgpu::Buffer,
    /// Total index count.
    pub index_count: u32,
    /// Per-object index ranges.
    pub draws: Vec<ObjectDraw>,
    /// `array<GpuObject>`.
    pub objects_buffer: wgpu::Buffer,
    /// `array<GpuMaterial>`.
    pub materials_buffer: wgpu::Buffer,
    /// `array<GpuLight>`.
    pub lights_buffer: wgpu::Buffer,
    /// `array<GpuWave>` of all heightfields (at least one entry).
    pub waves_buffer: wgpu::Buffer,
    /// Bytes of GPU memory the upload owns (the triangle BVH not included: the method
    /// that asks for it counts it).
    pub bytes: u64,
    /// The vertex and index buffers' bytes in the memory ledger (the tables are small).
    _memory: [Reservation; 2],
    /// Meshes and heightfields in one BVH, built on first use.
    triangle_bvh: OnceLock<SceneTriangles>,
}

/// Table entries of one shape, without the triangle range.
pub fn gpu_object(shape: &Shape, material: u32, waves: &mut Vec<GpuWave>) -> GpuObject {
    let mut o = GpuObject {
        material,
        ..Default::default()
    };
    match shape {
        Shape::Sphere { center, radius } => {
            o.kind = shape_kind::SPHERE;
            o.p0 = center.extend(*radius).to_array();
        }
        Shape::Quad {
            center,
            normal,
            size,
        } => {
            o.kind = shape_kind::QUAD;
            let (u, v) = caustics_scene::quad_axes(*normal);
            o.p0 = center.extend(size.x * 0.5).to_array();
            o.p1 = normal.extend(size.y * 0.5).to_array();
            o.p2 = u.extend(0.0).to_array();
            o.p3 = v.extend(0.0).to_array();
        }
        Shape::Heightfield(h) => {
            o.kind = shape_kind::HEIGHTFIELD;
            o.p0 = h.center.extend(waves.len() as f32).to_array();
            o.p1 = [h.size.x, h.size.y, h.waves.len() as f32, 0.0];
            for w in &h.waves {
                let k = w.direction * (std::f32::consts::TAU / w.wavelength);
                waves.push(GpuWave {
                    k_amp_phase: [k.x, k.y, w.amplitude, w.phase],
                });
            }
        }
        Shape::Cylinder {
            center,
            axis,
            radius,
            height,
        } => {
            o.kind = shape_kind::CYLINDER;
            o.p0 = center.extend(*radius).to_array();
            o.p1 = axis.extend(height * 0.5).to_array();
        }
        Shape::Mesh(_) => o.kind = shape_kind::MESH,
    }
    o
}

/// Table entry of one material.
pub fn gpu_material(m: &Material) -> GpuMaterial {
    match m {
        Material::Diffuse { albedo } => GpuMaterial {
            kind: material_kind::DIFFUSE,
            ior: 1.0,
            color: albedo.extend(0.0).to_array(),
            ..Default::default()
        },
        Material::Dielectric { ior } => GpuMaterial {
            kind: material_kind::DIELECTRIC,
            ior: *ior,
            color: [1.0; 4],
            ..Default::default()
        },
        Material::Mirror { reflectance } => GpuMaterial {
            kind: material_kind::MIRROR,
            ior: 1.0,
            color: reflectance.extend(0.0).to_array(),
            ..Default::default()
        },
    }
}

/// Table entry of one light.
pub fn gpu_light(l: &Light) -> GpuLight {
    match l {
        Light::Directional {
            direction,
            irradiance,
        } => GpuLight {
            kind: light_kind::DIRECTIONAL,
            direction: direction.extend(0.0).to_array(),
            power: irradiance.extend(0.0).to_array(),
            ..Default::default()
        },
        Light::Point {
            position,
            intensity,
        } => GpuLight {
            kind: light_kind::POINT,
            position: position.extend(1.0).to_array(),
            power: intensity.extend(0.0).to_array(),
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity,
            cone_deg,
            falloff_deg,
        } => GpuLight {
            kind: light_kind::SPOT,
            cone_rad: cone_deg.to_radians(),
            falloff_rad: falloff_deg.unwrap_or(0.0).to_radians(),
            position: position.extend(1.0).to_array(),
            direction: direction.extend(0.0).to_array(),
            power: intensity.extend(0.0).to_array(),
            ..Default::default()
        },
        // A sphere light is, from afar, a point light of intensity π r² L (pinhole
        // draws it as the disc of radius r it is); an environment a black directional
        // light (pinhole reads its map from the scene). The direct image does not use
        // these stand-ins: it draws each extended light's representative lights.
        Light::Sphere {
            position,
            radius,
            radiance,
        } => GpuLight {
            kind: light_kind::POINT,
            position: position.extend(1.0).to_array(),
            power: (*radiance * (std::f32::consts::PI * radius * radius))
                .extend(0.0)
                .to_array(),
            ..Default::default()
        },
        Light::Environment { .. } => GpuLight {
            kind: light_kind::DIRECTIONAL,
            direction: [0.0, -1.0, 0.0, 0.0],
            ..Default::default()
        },
    }
}

impl GpuScene {
    /// Triangulates every object and uploads geometry and tables once.
    pub fn upload(
        ctx: &GpuContext,
        scene: Arc<Scene>,
        tessellation: Tessellation,
    ) -> Result<Self, GpuError> {
        // A sphere light goes up as its far-field point light, an environment as a
        // black directional light (gpu_light): the methods that take them (pinhole)
        // read their radius or map from the scene; the direct image draws their
        // representative lights (`DIRECT_REPRESENTATIVE_LIGHTS`).
        let device = &ctx.device;
        let mut vertices: Vec<SceneVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut draws = Vec::new();
        let mut meshes = Vec::new();
        let mut objects = Vec::new();
        let mut waves = Vec::new();
        for (i, obj) in scene.objects.iter().enumerate() {
            let mesh = obj.shape.triangulate(&tessellation);
            let base = u32::try_from(vertices.len()).map_err(|_| GpuError::Upload {
                scene: scene.source.clone(),
                message: "more than 2^32 vertices".into(),
            })?;
            let first_index = indices.len() as u32;
            vertices.extend(
                mesh.positions
                    .iter()
                    .zip(&mesh.normals)
                    .map(|(p, n)| SceneVertex {
                        position: p.to_array(),
                        normal: n.to_array(),
                        object: i as u32,
                        material: obj.material as u32,
                    }),
            );
            indices.extend(mesh.indices.iter().map(|&k| k + base));
            let index_count = mesh.indices.len() as u32;
            draws.push(ObjectDraw {
                first_index,
                index_count,
            });
            let mut o = gpu_object(&obj.shape, obj.material as u32, &mut waves);
            o.first_triangle = first_index / 3;
            o.triangle_count = index_count / 3;
            objects.push(o);
            meshes.push(mesh);
        }
        if indices.is_empty() {
            return Err(GpuError::Upload {
                scene: scene.source.clone(),
                message: "no triangles".into(),
            });
        }
        if waves.is_empty() {
            waves.push(GpuWave::default());
        }
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| gpu_material(&m.material))
            .collect();
        let lights: Vec<GpuLight> = scene.lights.iter().map(gpu_light).collect();
        // Both are bound whole as storage by the passes that trace the scene.
        let raise = "use meshes of fewer triangles (--max-scene-triangles bounds them when the scene loads)";
        let memory = [
            ctx.reserve_storage(
                &format!("the scene's vertex buffer ({} vertices)", vertices.len()),
                std::mem::size_of_val(vertices.as_slice()) as u64,
                raise,
            )?,
            ctx.reserve_storage(
                &format!("the scene's index buffer ({} triangles)", indices.len() / 3),
                std::mem::size_of_val(indices.as_slice()) as u64,
                raise,
            )?,
        ];
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let mk = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let vertex_buffer = mk(
            "scene vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX | storage,
        );
        let index_buffer = mk(
            "scene indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX | storage,
        );
        let objects_buffer = mk("scene objects", bytemuck::cast_slice(&objects), storage);
        let materials_buffer = mk("scene materials", bytemuck::cast_slice(&materials), storage);
        let lights_buffer = mk("scene lights", bytemuck::cast_slice(&lights), storage);
        let waves_buffer = mk("scene waves", bytemuck::cast_slice(&waves), storage);
        let bytes = [
            &vertex_buffer,
            &index_buffer,
            &objects_buffer,
            &materials_buffer,
            &lights_buffer,
            &waves_buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum();
        Ok(Self {
            scene,
            tessellation,
            meshes,
            vertex_buffer,
            index_buffer,
            index_count: indices.len() as u32,
            draws,
            objects_buffer,
            materials_buffer,
            lights_buffer,
            waves_buffer,
            bytes,
            _memory: memory,
            triangle_bvh: OnceLock::new(),
        })
    }

    /// The scene's meshes and heightfields in one BVH on the GPU, for passes that trace
    /// rays against the whole scene (`triangle_bvh::wgsl`). Built and uploaded on the
    /// first call, then shared: one upload per scene.
    pub fn triangle_bvh(&self, ctx: &GpuContext) -> Result<&SceneTriangles, GpuError> {
        if let Some(bvh) = self.triangle_bvh.get() {
            return Ok(bvh);
        }
        let bvh = SceneTriangles::upload(ctx, &self.scene, &self.meshes)?;
        Ok(self.triangle_bvh.get_or_init(|| bvh))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_tables_match_common_wgsl() {
        let src = crate::shader::COMMON_WGSL;
        crate::assert_wgsl_layout!(
            src,
            GpuObject {
                kind,
                material,
                first_triangle,
                triangle_count,
                p0,
                p1,
                p2,
                p3
            }
        );
        crate::assert_wgsl_layout!(src, GpuMaterial { kind, ior, color });
        crate::assert_wgsl_layout!(
            src,
            GpuLight {
                kind,
                cone_rad,
                falloff_rad,
                position,
                direction,
                power
            }
        );
        crate::assert_wgsl_layout!(src, GpuWave { k_amp_phase });
    }

    #[test]
    fn vertex_layout_matches_the_struct() {
        let offsets: Vec<u64> = SceneVertex::LAYOUT
            .attributes
            .iter()
            .map(|a| a.offset)
            .collect();
        assert_eq!(
            offsets,
            [
                std::mem::offset_of!(SceneVertex, position) as u64,
                std::mem::offset_of!(SceneVertex, normal) as u64,
                std::mem::offset_of!(SceneVertex, object) as u64,
            ]
        );
        assert_eq!(
            std::mem::offset_of!(SceneVertex, material),
            std::mem::offset_of!(SceneVertex, object) + 4,
            "object and material are one Uint32x2 attribute"
        );
    }
}
