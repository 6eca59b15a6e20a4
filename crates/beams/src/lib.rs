//! `beams`: caustic beam tracing on the GPU (Liktor & Dachsbacher 2010, 2011), the
//! pipeline shared by the `static-grid` and `adaptive-beams` methods.
//!
//! The specular surfaces are rasterized from the light into a light G-buffer; a grid
//! in the light's uv space is projected onto them (Sect. 4.1), and each grid triangle
//! is the base of a caustic beam: the bundle of light paths through its three
//! corners. A corner's path is traced from the G-buffer through reflections and
//! refractions, two-sided refraction and further specular objects via distance
//! impostors (Sect. 6), so a beam starts on the last specular surface with three edge
//! rays. With `levels > 0` the grid is refined on the GPU by the split oracle
//! (Sect. 4.2: surface discontinuities, beam energy, camera distance) in compute
//! shaders, the paper's named future work, in place of its geometry shader. Each beam
//! gets the beam space of Ernst et al. (y along the base normal, edges scaled to unit
//! height), its area function A(y) and a hull, either Ernst's bounding prism or the
//! paper's tight six-triangle hull (Sect. 4.3), which is rasterized from the camera.
//! Per fragment, the camera ray is intersected with the beam through a scan plane
//! (Sect. 5.1) to add single-scattered radiance over the covered segment (volume
//! caustic, Sect. 5.2), and the camera G-buffer point is tested against the beam's
//! cross-section at its height to add the irradiance Φ/A(y) on the receiver (surface
//! caustic, Sect. 5.3), low-pass filtered (Sect. 7).
//!
//! Units follow DESIGN: a beam's flux is the light's irradiance × the beam's area
//! perpendicular to a directional light (or intensity × solid angle) × Fresnel,
//! reflectance and extinction along its path; radiance = ρ/π · E on receivers.
//!
//! Differences from the paper, all stated where they live:
//! - refinement is four compute kernels per level with a deterministic prefix sum
//!   instead of a geometry shader with stream-out, so the same beams land in the same
//!   slots every frame (and the additive image is bit-identical frame to frame);
//! - the split oracle's discontinuity criterion also traces the three edge midpoints
//!   and splits where their light lands more than `split_hit_px` camera pixels off
//!   the linear prediction (the "photon hit differences" of Sect. 6, used at every
//!   level); the energy criterion is (flux share) × A(0)/A(y) where the beam is seen
//!   (at its receiver; at its narrowest in a medium);
//! - all distance impostors (one per specular object, one of the diffuse receivers
//!   around the generators) share one texture atlas, so each query is one inlined
//!   search (WGSL inlines every call);
//! - the volume segment is clipped exactly at the visible surface, so the
//!   soft-particle fade (Sect. 5.2) is optional (`soft_depth_m`, default off);
//! - beam extrusion stops at the receiver found through the receivers' impostor, not
//!   at an energy cut-off;
//! - light that the paper drops is dropped here too: total internal reflection ends
//!   a path, the Fresnel reflection at the exit surface is not followed, and a beam
//!   that would meet the surface it just left again (concave generators, the inside
//!   of a ring) passes through it.

pub mod config;
pub mod geometry;

use bytemuck::{Pod, Zeroable};
use caustics_gpu::binding::{
    buffer_binding, storage_entry, texture_binding, texture_entry, uniform_entry,
};
use caustics_gpu::impostor::{IMPOSTOR_TRACE_WGSL, ImpostorAtlas, ImpostorPass};
use caustics_gpu::textures::{HDR_FORMAT, Target, additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{
    CountedPipeline, Frame, GBuffer, GpuContext, GpuScene, LightView, Renderer, shader,
};
use caustics_method::{Capabilities, CausticsMethod, Counters, MethodError, Unsupported};
use caustics_scene::{Light, Material, Scene, Shape, Vec3};

pub use config::{BeamConfig, HullKind, SHARED_PARAM_DOCS};

const TYPES_WGSL: &str = include_str!("types.wgsl");
const PATH_WGSL: &str = include_str!("path.wgsl");
const GENERATE_WGSL: &str = include_str!("generate.wgsl");
const RASTERIZE_WGSL: &str = include_str!("rasterize.wgsl");
const FILTER_WGSL: &str = include_str!("filter.wgsl");

/// Beam generation: types, impostor tracing, light paths, the refinement kernels.
pub fn generate_source() -> String {
    shader::compose_method(&format!(
        "{TYPES_WGSL}\n{IMPOSTOR_TRACE_WGSL}\n{PATH_WGSL}\n{GENERATE_WGSL}"
    ))
}

/// Hull rasterization with the per-fragment beam intersection.
pub fn rasterize_source() -> String {
    shader::compose_method(&format!("{TYPES_WGSL}\n{RASTERIZE_WGSL}"))
}

/// The surface-caustic low-pass filter.
pub fn filter_source() -> String {
    shader::compose_method(FILTER_WGSL)
}

/// Most caustic generators (specular objects) a scene may have.
pub const MAX_SPECULAR: usize = 4;
/// Most refinement levels.
pub const MAX_LEVELS: u32 = 4;

/// What both beam methods render.
pub const CAPABILITIES: Capabilities = Capabilities {
    surface: true,
    volume: true,
    reflection: true,
    refraction: true,
    multiple_bounces: true,
    directional_light: true,
    point_light: true,
    spot_light: true,
};

/// Scene limits of the beam pipeline beyond [`CAPABILITIES`].
pub fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    if scene.lights.len() != 1 {
        return Err(Unsupported(format!(
            "needs exactly one light (the light G-buffer is one view), the scene has {}",
            scene.lights.len()
        )));
    }
    let specular = scene
        .objects
        .iter()
        .filter(|o| scene.material(o).is_specular())
        .count();
    if specular == 0 {
        return Err(Unsupported("the scene has no specular object".into()));
    }
    if specular > MAX_SPECULAR {
        return Err(Unsupported(format!(
            "{specular} specular objects; the beam tracer binds at most {MAX_SPECULAR} distance impostors"
        )));
    }
    if !scene
        .objects
        .iter()
        .any(|o| !scene.material(o).is_specular())
    {
        return Err(Unsupported(
            "the scene has no diffuse receiver for the caustic".into(),
        ));
    }
    if let Some(b) = scene.specular_bounds()
        && LightView::fit_points(&scene.lights[0], &b.corners(), 16).is_none()
    {
        return Err(Unsupported(
            "the light is among the specular objects; the light G-buffer must see them from outside".into(),
        ));
    }
    Ok(())
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct SpecularSlot {
    center_reach: [f32; 4],
    color: [f32; 4],
    object: u32,
    kind: u32,
    closed: u32,
    ior: f32,
}

/// Mirrors `BeamUniforms` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct BeamUniforms {
    light_inv_view_proj: [[f32; 4]; 4],
    light_dir_kind: [f32; 4],
    light_pos_start: [f32; 4],
    light_power: [f32; 4],
    sigma_t: [f32; 4],
    sigma_s_g: [f32; 4],
    receivers: [f32; 4],
    specular: [SpecularSlot; MAX_SPECULAR],
    specular_count: u32,
    grid: u32,
    levels: u32,
    max_beams: u32,
    split_flags: u32,
    split_cos_normal: f32,
    split_depth_slope: f32,
    split_energy: f32,
    split_camera_px: f32,
    pixel_angle: f32,
    reflections: u32,
    tight_hulls: u32,
    max_focus: f32,
    soft_depth: f32,
    impostor_tolerance: f32,
    scene_reach: f32,
    split_hit_px: f32,
    _pad: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct FilterUniforms {
    sigma_px: f32,
    radius_px: i32,
    _pad: [u32; 2],
}

/// One beam as stored on the GPU (mirrors `Beam` in types.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BeamRecord {
    /// xyz: base vertex v_i; w: coefficient a_i of A(y) = a0 + a1·y + a2·y².
    pub v: [[f32; 4]; 3],
    /// xyz: edge direction scaled to unit height; w: height where edge i meets a receiver.
    pub d: [[f32; 4]; 3],
    /// rgb: flux (W) if every ray carried vertex i's weight.
    pub flux: [[f32; 4]; 3],
    /// xyz: unit base normal; w: extrusion height y_max.
    pub n: [f32; 4],
    /// Hull points: base 3, top 3.
    pub hull: [[f32; 4]; 6],
    /// 24 packed 4-bit hull indices; w: 1 tight, 0 prism.
    pub tris: [u32; 4],
}

const CANDIDATE_BYTES: u64 = 32;
const BEAM_BYTES: u64 = std::mem::size_of::<BeamRecord>() as u64;
const CONTROL_WORDS: usize = 32;
// Words of the control buffer (mirrors generate.wgsl).
const C_LEVEL: usize = 8;
const C_BEAM_TOTAL: usize = 12;
const C_OVERFLOW_CANDIDATES: usize = 13;
const C_OVERFLOW_BEAMS: usize = 14;
const C_BEAMS_PER_LEVEL: usize = 15;
const C_TIGHT: usize = 20;
const C_PRISM: usize = 21;
const C_DROPPED_INVALID: usize = 22;
const C_DROPPED_DISCONTINUITY: usize = 23;
const C_SPLIT_DISCONTINUITY: usize = 24;
const C_SPLIT_ENERGY: usize = 25;
const C_SPLIT_CAMERA: usize = 26;
const C_CANDIDATES_TOTAL: usize = 27;
const C_DROPPED_NO_RECEIVER: usize = 28;
/// Byte offset of the hull draw's arguments in the indirect-arguments buffer.
const DRAW_ARGS_OFFSET: u64 = 16;

/// The beam pipeline bound to one scene.
pub struct BeamMethod {
    config: BeamConfig,
    light_gbuffer: GBuffer,
    impostor_pass: ImpostorPass,
    atlas: ImpostorAtlas,
    raw_surface: Target,
    control: wgpu::Buffer,
    control_init: wgpu::Buffer,
    indirect_args: wgpu::Buffer,
    beams: wgpu::Buffer,
    init_pipeline: wgpu::ComputePipeline,
    decide_pipeline: wgpu::ComputePipeline,
    scan_pipeline: wgpu::ComputePipeline,
    emit_pipeline: wgpu::ComputePipeline,
    advance_pipeline: wgpu::ComputePipeline,
    finalize_pipeline: wgpu::ComputePipeline,
    rasterize_pipeline: CountedPipeline<wgpu::RenderPipeline>,
    filter_pipeline: wgpu::RenderPipeline,
    generate_bind: wgpu::BindGroup,
    args_bind: wgpu::BindGroup,
    rasterize_bind: wgpu::BindGroup,
    filter_bind: wgpu::BindGroup,
    pass_names: PassNames,
    bytes: u64,
}

struct PassNames {
    light_gbuffer: String,
    impostors: String,
    generate: String,
    rasterize: String,
    surface_filter: String,
}

/// One specular object's role in the pipeline.
struct Slot {
    object: usize,
    uniform: SpecularSlot,
    /// Impostor centre; None = the centre of its bounds (closed objects).
    center: Option<Vec3>,
}

fn slots(scene: &Scene, gpu_scene: &GpuScene) -> Vec<Slot> {
    let mut out = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (kind, ior, color) = match scene.material(o) {
            Material::Dielectric { ior } => (1u32, *ior, Vec3::ONE),
            Material::Mirror { reflectance } => (2u32, 1.0, *reflectance),
            Material::Diffuse { .. } => continue,
        };
        let bounds = caustics_gpu::impostor::objects_bounds(gpu_scene, &[i]);
        let extent = bounds.map_or(1.0, |b| (b.max - b.min).max_element());
        // Closed generators are star-shaped around their centre; an open surface
        // (water, a mirror quad) is seen from a point behind it, a ring from its axis.
        let (closed, center) = match &o.shape {
            Shape::Sphere { .. } | Shape::Mesh(_) => (true, None),
            Shape::Heightfield(_) => (
                false,
                bounds.map(|b| b.center() - Vec3::Y * (0.5 * extent + 0.5 * (b.max.y - b.min.y))),
            ),
            Shape::Quad { normal, .. } => (
                false,
                bounds.map(|b| b.center() - normal.normalize() * (0.5 * extent)),
            ),
            Shape::Cylinder { .. } => (false, None),
        };
        out.push(Slot {
            object: i,
            uniform: SpecularSlot {
                center_reach: [0.0; 4],
                color: color.extend(1.0).to_array(),
                object: i as u32,
                kind,
                closed: closed as u32,
                ior,
            },
            center,
        });
    }
    out
}

impl BeamMethod {
    /// Builds the pipeline for the renderer's scene. `name` prefixes every pass.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        config: &BeamConfig,
        name: &'static str,
    ) -> Result<Self, MethodError> {
        config.validate(name)?;
        let gpu_scene = renderer.scene();
        let scene = &gpu_scene.scene;
        let unsupported = |reason: Unsupported| MethodError::Unsupported {
            method: name,
            scene: scene.name.clone(),
            reason,
        };
        check_scene(scene).map_err(unsupported)?;
        let slots = slots(scene, gpu_scene);
        let points: Vec<Vec3> = slots
            .iter()
            .flat_map(|s| gpu_scene.meshes[s.object].positions.iter().copied())
            .collect();
        let light = &scene.lights[0];
        let view =
            LightView::fit_points(light, &points, config.light_resolution).ok_or_else(|| {
                unsupported(Unsupported(
                    "no light view holds the specular objects".into(),
                ))
            })?;
        ctx.checked("beam pipeline setup", || {
            Self::build(ctx, renderer, config, name, &slots, &view)
        })?
    }

    fn build(
        ctx: &GpuContext,
        renderer: &Renderer,
        config: &BeamConfig,
        name: &'static str,
        slots: &[Slot],
        view: &LightView,
    ) -> Result<Self, MethodError> {
        let device = &ctx.device;
        let gpu_scene = renderer.scene();
        let scene = &gpu_scene.scene;
        let light_gbuffer = renderer.gbuffer_pass().light_gbuffer(device, view);
        let impostor_pass = ImpostorPass::new(device);
        let receivers: Vec<usize> = scene
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| !scene.material(o).is_specular())
            .map(|(i, _)| i)
            .collect();
        let specular_center = scene.specular_bounds().map(|b| b.center());
        // One atlas: the specular slots in order, then the receivers around the
        // generators' centre (Umenhoffer's distance map of the environment).
        let mut entries: Vec<(Vec<usize>, Option<Vec3>)> =
            slots.iter().map(|s| (vec![s.object], s.center)).collect();
        entries.push((receivers, specular_center));
        let atlas = impostor_pass.atlas(device, gpu_scene, &entries, config.impostor_resolution)?;
        let mut slot_uniforms = [SpecularSlot::default(); MAX_SPECULAR];
        for (k, s) in slots.iter().enumerate() {
            let e = &atlas.entries[k];
            slot_uniforms[k] = s.uniform;
            slot_uniforms[k].center_reach = e.center.extend(e.reach).to_array();
        }
        let receiver_entry = &atlas.entries[slots.len()];
        let receivers_center_reach = receiver_entry
            .center
            .extend(receiver_entry.reach)
            .to_array();

        let bounds = scene.bounds();
        let scene_reach = 2.0 * bounds.bounding_sphere_radius().max(1e-3);
        let (light_dir_kind, light_pos_start, power) = match *light_of(scene) {
            Light::Directional {
                direction,
                irradiance,
            } => {
                let dir = direction.normalize();
                // The reference starts directional photons 1 m before the scene's
                // bounds along the light; extinction is counted from the same plane.
                let start = bounds
                    .corners()
                    .iter()
                    .map(|c| c.dot(dir))
                    .fold(f32::INFINITY, f32::min)
                    - 1.0;
                let side = view.texel_size * view.resolution as f32;
                (
                    dir.extend(0.0),
                    [0.0, 0.0, 0.0, start],
                    irradiance.extend(side * side),
                )
            }
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => (
                Vec3::ZERO.extend(1.0),
                position.extend(0.0).to_array(),
                intensity.extend(0.0),
            ),
        };
        let (sigma_t, sigma_s_g) = match &scene.medium {
            Some(m) => (
                m.sigma_t().extend(1.0).to_array(),
                m.sigma_s.extend(m.g).to_array(),
            ),
            None => ([0.0; 4], [0.0; 4]),
        };
        let cam = &scene.camera;
        let flags = (config.split_discontinuity as u32)
            | ((config.split_energy as u32) << 1)
            | ((config.split_camera as u32) << 2);
        let uniforms = BeamUniforms {
            light_inv_view_proj: view.faces[0].view_proj.inverse().to_cols_array_2d(),
            light_dir_kind: light_dir_kind.to_array(),
            light_pos_start,
            light_power: power.to_array(),
            sigma_t,
            sigma_s_g,
            receivers: receivers_center_reach,
            specular: slot_uniforms,
            specular_count: slots.len() as u32,
            grid: config.grid,
            levels: config.levels,
            max_beams: config.max_beams,
            split_flags: flags,
            split_cos_normal: (config.split_normal_deg.to_radians().cos()) as f32,
            split_depth_slope: config.split_depth_slope as f32,
            split_energy: config.split_energy_threshold as f32,
            split_camera_px: config.split_camera_px as f32,
            pixel_angle: cam.fov_y_rad() / cam.height as f32,
            reflections: config.reflections as u32,
            tight_hulls: (config.hull == HullKind::Tight) as u32,
            max_focus: config.max_focus as f32,
            soft_depth: config.soft_depth_m as f32,
            impostor_tolerance: 0.01,
            scene_reach,
            split_hit_px: config.split_hit_px as f32,
            _pad: [0; 3],
        };
        let uniform_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("beam uniforms"),
            contents: bytemuck::bytes_of(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let cap = config.max_beams as u64;
        let none = wgpu::BufferUsages::empty();
        let candidates_a = storage("beam candidates a", cap * CANDIDATE_BYTES, none);
        let candidates_b = storage("beam candidates b", cap * CANDIDATE_BYTES, none);
        let actions = storage("beam actions", cap * 4, none);
        let offsets = storage("beam offsets", cap * 8, none);
        let beams = storage("beams", cap * BEAM_BYTES, wgpu::BufferUsages::COPY_SRC);
        let control = storage(
            "beam control",
            (CONTROL_WORDS * 4) as u64,
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let indirect_args = storage("beam indirect args", 32, wgpu::BufferUsages::INDIRECT);
        let control_init = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("beam control reset"),
            contents: bytemuck::cast_slice(&[0u32; CONTROL_WORDS]),
            usage: wgpu::BufferUsages::COPY_SRC,
        });
        let raw_surface = Target::new(
            device,
            "beam raw surface caustic",
            HDR_FORMAT,
            cam.width,
            cam.height,
            1,
            wgpu::TextureUsages::empty(),
        );

        // Group 1 of the generate kernels.
        let cs = wgpu::ShaderStages::COMPUTE;
        let float_tex = |b, dim| {
            texture_entry(
                b,
                cs,
                wgpu::TextureSampleType::Float { filterable: false },
                dim,
            )
        };
        let d2 = wgpu::TextureViewDimension::D2;
        let d2a = wgpu::TextureViewDimension::D2Array;
        let mut entries = vec![
            uniform_entry(0, cs),
            float_tex(1, d2),
            float_tex(2, d2),
            texture_entry(3, cs, wgpu::TextureSampleType::Uint, d2),
        ];
        entries.push(float_tex(4, d2a));
        entries.push(texture_entry(5, cs, wgpu::TextureSampleType::Uint, d2a));
        for b in 6..12 {
            entries.push(storage_entry(b, false, cs));
        }
        let generate_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("beam generate"),
            entries: &entries,
        });
        let tex = texture_binding;
        let buf = buffer_binding;
        let generate_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("beam generate"),
            layout: &generate_layout,
            entries: &[
                buf(0, &uniform_buffer),
                tex(1, &light_gbuffer.position.view),
                tex(2, &light_gbuffer.normal.view),
                tex(3, &light_gbuffer.ids.view),
                tex(4, &atlas.normal_distance.view),
                tex(5, &atlas.object_ids.view),
                buf(6, &candidates_a),
                buf(7, &candidates_b),
                buf(8, &actions),
                buf(9, &offsets),
                buf(10, &control),
                buf(11, &beams),
            ],
        });
        let args_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("beam indirect args"),
            entries: &[storage_entry(0, false, cs)],
        });
        let args_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("beam indirect args"),
            layout: &args_layout,
            entries: &[buf(0, &indirect_args)],
        });
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let rasterize_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("beam rasterize"),
            entries: &[uniform_entry(0, vf), storage_entry(1, true, vf)],
        });
        let rasterize_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("beam rasterize"),
            layout: &rasterize_layout,
            entries: &[buf(0, &uniform_buffer), buf(1, &beams)],
        });
        let fs = wgpu::ShaderStages::FRAGMENT;
        let sigma = config.surface_filter_px as f32;
        let filter_uniforms = FilterUniforms {
            sigma_px: sigma.max(1e-3),
            radius_px: if sigma > 0.0 {
                (2.0 * sigma).ceil() as i32
            } else {
                0
            },
            _pad: [0; 2],
        };
        let filter_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("beam filter uniforms"),
            contents: bytemuck::bytes_of(&filter_uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let filter_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("beam surface filter"),
            entries: &[
                uniform_entry(0, fs),
                texture_entry(
                    1,
                    fs,
                    wgpu::TextureSampleType::Float { filterable: false },
                    d2,
                ),
            ],
        });
        let filter_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("beam surface filter"),
            layout: &filter_layout,
            entries: &[buf(0, &filter_buffer), tex(1, &raw_surface.view)],
        });

        let pipeline_layout = |label: &str, own: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(renderer.frame_layout()), Some(own)],
                immediate_size: 0,
            })
        };
        let generate_module = shader::module(device, "beams generate.wgsl", generate_source());
        let generate_pl = pipeline_layout("beam generate", &generate_layout);
        let generate_args_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("beam generate + args"),
            bind_group_layouts: &[
                Some(renderer.frame_layout()),
                Some(&generate_layout),
                Some(&args_layout),
            ],
            immediate_size: 0,
        });
        let compute = |entry: &str, writes_args: bool| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(if writes_args {
                    &generate_args_pl
                } else {
                    &generate_pl
                }),
                module: &generate_module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let rasterize_module = shader::module(device, "beams rasterize.wgsl", rasterize_source());
        let rasterize_pl = pipeline_layout("beam rasterize", &rasterize_layout);
        let rasterize_pipeline = CountedPipeline::new(|constants| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("beam rasterize"),
                layout: Some(&rasterize_pl),
                vertex: wgpu::VertexState {
                    module: &rasterize_module,
                    entry_point: Some("vs_beam"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                // Hull triangles face outwards: drawing back faces only shades each
                // covered pixel once per beam, also with the camera inside a hull.
                primitive: wgpu::PrimitiveState {
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: Some(wgpu::Face::Front),
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &rasterize_module,
                    entry_point: Some("fs_beam"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        ..Default::default()
                    },
                    targets: &[Some(additive_hdr_target()), Some(additive_hdr_target())],
                }),
                multiview_mask: None,
                cache: None,
            })
        });
        let filter_module = shader::module(device, "beams filter.wgsl", filter_source());
        let filter_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("beam surface filter"),
            layout: Some(&pipeline_layout("beam surface filter", &filter_layout)),
            vertex: wgpu::VertexState {
                module: &filter_module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &filter_module,
                entry_point: Some("fs_filter"),
                compilation_options: Default::default(),
                targets: &[Some(additive_hdr_target())],
            }),
            multiview_mask: None,
            cache: None,
        });

        let mut bytes = light_gbuffer.bytes() + raw_surface.bytes + atlas.bytes();
        bytes += [
            &uniform_buffer,
            &candidates_a,
            &candidates_b,
            &actions,
            &offsets,
            &beams,
            &control,
            &control_init,
            &indirect_args,
            &filter_buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>();
        Ok(Self {
            config: config.clone(),
            light_gbuffer,
            impostor_pass,
            atlas,
            raw_surface,
            control,
            control_init,
            indirect_args,
            beams,
            init_pipeline: compute("init_grid", true),
            decide_pipeline: compute("decide", false),
            scan_pipeline: compute("scan", false),
            emit_pipeline: compute("emit", false),
            advance_pipeline: compute("advance", true),
            finalize_pipeline: compute("finalize", true),
            rasterize_pipeline,
            filter_pipeline,
            generate_bind,
            args_bind,
            rasterize_bind,
            filter_bind,
            pass_names: PassNames {
                light_gbuffer: format!("{name}/light_gbuffer"),
                impostors: format!("{name}/impostors"),
                generate: format!("{name}/generate"),
                rasterize: format!("{name}/rasterize"),
                surface_filter: format!("{name}/surface_filter"),
            },
            bytes,
        })
    }

    /// The beams of the last frame, read back (tests and diagnostics; not per frame).
    pub fn read_beams(&self, ctx: &GpuContext) -> Result<Vec<BeamRecord>, MethodError> {
        let control = self.read_control(ctx)?;
        let count = control[C_BEAM_TOTAL] as u64;
        if count == 0 {
            return Ok(Vec::new());
        }
        let bytes = caustics_gpu::readback::read_buffer_bytes(
            ctx,
            &self.beams,
            count * BEAM_BYTES,
            "beams",
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    fn read_control(&self, ctx: &GpuContext) -> Result<Vec<u32>, MethodError> {
        Ok(caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.control,
            self.control.size(),
            "beam control",
        )?)
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &BeamConfig {
        &self.config
    }
}

fn light_of(scene: &Scene) -> &Light {
    &scene.lights[0]
}

impl CausticsMethod for BeamMethod {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        let scene = renderer.scene();
        frame.encoder.copy_buffer_to_buffer(
            &self.control_init,
            0,
            &self.control,
            0,
            self.control.size(),
        );
        renderer.gbuffer_pass().record(
            frame,
            &self.pass_names.light_gbuffer,
            scene,
            &self.light_gbuffer,
        )?;
        self.impostor_pass
            .record_atlas(frame, &self.pass_names.impostors, scene, &self.atlas)?;
        {
            let mut pass = frame.compute_pass(&self.pass_names.generate)?;
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.generate_bind, &[]);
            pass.set_bind_group(2, &self.args_bind, &[]);
            pass.set_pipeline(&self.init_pipeline);
            let base = 2 * self.config.grid * self.config.grid;
            pass.dispatch_workgroups(base.div_ceil(64), 1, 1);
            for _ in 0..=self.config.levels {
                pass.set_pipeline(&self.decide_pipeline);
                pass.dispatch_workgroups_indirect(&self.indirect_args, 0);
                pass.set_pipeline(&self.scan_pipeline);
                pass.dispatch_workgroups(1, 1, 1);
                pass.set_pipeline(&self.emit_pipeline);
                pass.dispatch_workgroups_indirect(&self.indirect_args, 0);
                pass.set_pipeline(&self.advance_pipeline);
                pass.dispatch_workgroups(1, 1, 1);
            }
            pass.set_pipeline(&self.finalize_pipeline);
            pass.dispatch_workgroups(1, 1, 1);
        }
        {
            let pipeline = self.rasterize_pipeline.get(frame);
            let targets = renderer.targets();
            let attachments = [
                Some(wgpu::RenderPassColorAttachment {
                    view: &self.raw_surface.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                }),
                load_attachment(&targets.volume.view),
            ];
            let mut pass = frame.render_pass(
                &self.pass_names.rasterize,
                caustics_gpu::pass_desc(&attachments),
            )?;
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
            pass.set_bind_group(1, &self.rasterize_bind, &[]);
            pass.draw_indirect(&self.indirect_args, DRAW_ARGS_OFFSET);
        }
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        let mut pass = frame.render_pass(
            &self.pass_names.surface_filter,
            caustics_gpu::pass_desc(&attachments),
        )?;
        pass.set_pipeline(&self.filter_pipeline);
        pass.set_bind_group(0, renderer.frame_bind_group(), &[]);
        pass.set_bind_group(1, &self.filter_bind, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let c = self.read_control(ctx)?;
        let mut out = Counters::new();
        let beams = c[C_BEAM_TOTAL] as u64;
        out.insert("beams".into(), beams);
        out.insert("hull_triangles".into(), 8 * beams);
        out.insert("hulls_tight".into(), c[C_TIGHT] as u64);
        out.insert("hulls_prism".into(), c[C_PRISM] as u64);
        out.insert(
            "base_triangles".into(),
            2 * (self.config.grid as u64).pow(2),
        );
        out.insert("candidates".into(), c[C_CANDIDATES_TOTAL] as u64);
        for level in 0..=self.config.levels as usize {
            out.insert(
                format!("beams_level_{level}"),
                c[C_BEAMS_PER_LEVEL + level] as u64,
            );
        }
        out.insert("levels_run".into(), c[C_LEVEL] as u64);
        out.insert(
            "splits_discontinuity".into(),
            c[C_SPLIT_DISCONTINUITY] as u64,
        );
        out.insert("splits_energy".into(), c[C_SPLIT_ENERGY] as u64);
        out.insert("splits_camera".into(), c[C_SPLIT_CAMERA] as u64);
        out.insert("dropped_invalid".into(), c[C_DROPPED_INVALID] as u64);
        out.insert(
            "dropped_discontinuity".into(),
            c[C_DROPPED_DISCONTINUITY] as u64,
        );
        out.insert(
            "dropped_no_receiver".into(),
            c[C_DROPPED_NO_RECEIVER] as u64,
        );
        out.insert(
            "overflow_candidates".into(),
            c[C_OVERFLOW_CANDIDATES] as u64,
        );
        out.insert("overflow_beams".into(), c[C_OVERFLOW_BEAMS] as u64);
        Ok(out)
    }

    fn gpu_memory_bytes(&self) -> u64 {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shaders_validate() -> Result<(), String> {
        shader::validate_wgsl("beams generate.wgsl", &generate_source())?;
        shader::validate_wgsl("beams rasterize.wgsl", &rasterize_source())?;
        shader::validate_wgsl("beams filter.wgsl", &filter_source())
    }

    #[test]
    fn gpu_structs_match_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<BeamRecord>(), 272);
        assert_eq!(std::mem::size_of::<SpecularSlot>(), 48);
        assert_eq!(std::mem::size_of::<BeamUniforms>(), 432);
    }
}
