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
//! - each grid vertex's main path is traced once per frame (`vertex_cache`, on by
//!   default; generate.wgsl `trace_lattice`), where the paper's geometry shader traces
//!   it for every triangle that has it as a corner, again as an oracle midpoint and
//!   when the leaf's beam is written: the same beams bit for bit (through the BVH on a
//!   mesh, where lavapipe rounds the same WGSL in another kernel differently, but for
//!   the last bits of a few paths), in half the time of `generate` on lavapipe;
//! - the split oracle's discontinuity criterion also traces the three edge midpoints
//!   and splits where their light lands more than `split_hit_px` camera pixels and
//!   more than `split_hit_rel` of the edge's landing length off the linear prediction
//!   (the "photon hit differences" of Sect. 6, used at every level; the relative bound
//!   is the share of its irradiance a beam misplaces, so gently bending large beams
//!   stay whole); the energy criterion is the beam's flux relative to an unrefined
//!   beam's × A(0)/A(y) where the beam is seen (at its receiver; at its narrowest in a
//!   medium);
//! - with `beam_budget` > 0 the refinement spends a beam budget by priority (the
//!   paper's "convergent beams ... are refined with higher priority", Sect. 4.2, which
//!   gives no rule): each level ranks the splits the oracle asks for by how much light
//!   they would misplace in pixels (the largest edge-midpoint deviation, or the size of
//!   the light a discontinuity cuts) and, coarse levels first, takes those above a
//!   threshold found from the level's priority histogram while their children (four
//!   beams per beam at stake) fit the beams left; the rest stay leaves
//!   (`splits_deferred`). The budget counts the main path's and the Fresnel
//!   reflection's beams, the paper's families; the internal reflections of `bounces`
//!   follow the leaves it buys, so following more light does not coarsen the main
//!   caustic;
//! - the paper's oracle looks at the main path only; `split_families` (off by default)
//!   also splits a leaf whose Fresnel reflection or internal reflections part ways at
//!   its corners while its main path does not, ranked by that light's share times its
//!   size in pixels (such a leaf otherwise loses that light or, with `splat_orphans`,
//!   draws it as bright points where it is coarse);
//! - all distance impostors (one per specular object, one of the diffuse receivers
//!   around the generators) share one texture atlas, so each query is one inlined
//!   search (WGSL inlines every call);
//! - the volume segment is clipped exactly at the visible surface, so the
//!   soft-particle fade (Sect. 5.2) is optional (`soft_depth_m`, default off);
//! - beam extrusion stops at the receiver found through the receivers' impostor, not
//!   at an energy cut-off;
//! - light that the paper drops is dropped by default too: total internal reflection
//!   ends a path, the Fresnel reflection at the exit surface is not followed, and a
//!   beam that would meet the surface it just left again (concave generators, the
//!   inside of a ring) passes through it. `bounces` (default 0, the paper's path)
//!   follows up to that many further specular events, the photon-hit methods'
//!   parameter of the same name: the light reflected j times inside the first object,
//!   a closed refractor, is a beam family of its own (j = 1..=bounces, beside the main
//!   path and the first interface's Fresnel reflection, on the same refined grid),
//!   total internal reflections elsewhere are followed within a path, and so is a
//!   generator met again. Counters `beams_path_main`, `beams_path_fresnel_reflection`,
//!   `beams_path_internal_<j>`, `beams_path_rehit` and `beams_path_tir` say what each
//!   kind delivered.
//! - the paper traces every hit after the first through distance impostors, which
//!   misplace points and normals on surfaces that are not star-shaped around the
//!   impostor's centre (bumps, concave meshes). `tracer` = bvh traces every corner
//!   path exactly instead, the first hit included: the scene's triangle BVH and the
//!   analytic shapes (`caustics_gpu::triangle_bvh`), with the adjoint shading-normal
//!   factor at each event (Veach 1997, §5.3) as the reference; the light G-buffer and
//!   impostor passes are then not recorded.
//! - a leaf whose corners part ways (a silhouette, a fold, different receivers) emits
//!   no beam for that family and its light is lost, as in the paper (refinement only
//!   narrows where). `splat_orphans` writes such a family's landed corners as orphan
//!   records (a third of the triangle's flux each, in candidate order beside the
//!   beams' prefix sum) and draws them as one-pixel points (with `orphan_kernel_px`,
//!   Gaussians of that many pixels: frame.wgsl's point kernel) into the raw surface
//!   caustic before the filter (`orphans.wgsl`); in a medium their in-scattered light
//!   stays lost. `clip_leaves` keeps that light in beams instead: each group of the
//!   leaf's corners on one path (same objects, same receiver) emits the part of the
//!   triangle around it, its edges to the other corners cut where 6 bisections find
//!   the group's path ending (a quad of two beams for a pair, a triangle for a corner
//!   alone), traced in `emit_beams`; a clipped beam whose exit points admit no beam
//!   space (at a silhouette the exit points lie edge-on to the light) starts where its
//!   rays cross the plane across their mean direction (generate.wgsl `clip_leaf`,
//!   `rebased`).
//! - `raster` = compute (issue 17) replaces the hull rasterization by a compute pass of
//!   the same name (`rasterize_compute.wgsl`): the workgroups of a beam clip its hull at
//!   the camera plane, find the convex polygon it projects to and shade the pixels
//!   inside it with the fragment shader's own function (`beam_shading.wgsl`), adding
//!   the light into a fixed-point accumulator with integer atomics, which a full-screen
//!   `resolve` pass writes into the raw surface caustic and the volume target. The image
//!   is the same on every run and within a stated bound of the hardware path's
//!   (`tests/gpu_beams.rs`); orphan points stay on the rasterizer.
//!
//! - the paper uses one area function per beam (Sect. 7: small steps at beam edges,
//!   hidden by the low-pass filter); `vertex_irradiance` (off by default) gives each
//!   corner the irradiance of the beams around its grid vertex (ΔΦ/ΔA), as a clamped
//!   factor on its beam's own that keeps the beam's flux, interpolated across the beam
//!   (after Ernst et al. 2005, whom Sect. 7 names; generate.wgsl `vertex_irradiance`).
//! - the paper builds the beams of one light; a scene with several gets the pipeline
//!   once per light, each as if alone (its own light view and G-buffer, grid, refinement
//!   and beam budget), into the same images ([`BeamMethod`]); counters are summed over
//!   the lights.
//!
//! Passes (names `<method>/<pass>`): `light_gbuffer` (one per light), `impostors`,
//! `generate` (compute: per light `init_grid`, then per level `gather_lattice`,
//! `lattice_args` and `trace_lattice` (the vertex cache, [`vertex_cache_side`]),
//! `decide`, `budget` (with a beam budget), `scan`, `emit` (the splits' children and
//! a job per leaf beam), `advance`, then `emit_beams` (one invocation per beam of every
//! level's leaves), `emit_orphans` (with `splat_orphans`),
//! `vertex_irradiance` (with it) and `finalize`), `rasterize` (the hulls, one indirect draw per light; with `raster` = compute one indirect dispatch per light,
//! then `resolve`), `orphan_points` (with `splat_orphans`, one indirect draw per light)
//! and `surface_filter`.

pub mod config;
mod control;
pub mod geometry;
mod gpu_types;

use caustics_gpu::impostor::{IMPOSTOR_TRACE_WGSL, ImpostorAtlas, ImpostorPass};
use caustics_gpu::limits::Reservation;
use caustics_gpu::pass::{ComputePass, RasterPass, Shader, point_kernel_vertices};
use caustics_gpu::textures::{HDR_FORMAT, Target, additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GBuffer, GpuContext, GpuError, LightView, Renderer, shader};
use caustics_method::params::Raster;
use caustics_method::{Capabilities, CausticsMethod, Counters, MethodError, Unsupported};
use caustics_scene::{Light, Scene, Vec3};

pub use config::{BeamConfig, BeamParams, HullKind, MAX_BOUNCES, MAX_LEVELS, Refinement, Tracer};
pub use control::COUNTER_DOCS;
use control::{CONTROL_WORDS, VERTEX_LIST_WORDS};
pub use gpu_types::BeamRecord;
use gpu_types::{
    BEAM_BYTES, BeamUniforms, CANDIDATE_BYTES, FilterUniforms, ORPHAN_BYTES, Slot,
    VERTEX_PATH_BYTES,
};

const TYPES_WGSL: &str = include_str!("types.wgsl");
const PATH_WGSL: &str = include_str!("path.wgsl");
const GENERATE_WGSL: &str = include_str!("generate.wgsl");
const BEAM_SHADING_WGSL: &str = include_str!("beam_shading.wgsl");
const RASTERIZE_WGSL: &str = include_str!("rasterize.wgsl");
const RASTERIZE_COMPUTE_WGSL: &str = include_str!("rasterize_compute.wgsl");
const RESOLVE_WGSL: &str = include_str!("resolve.wgsl");
const FILTER_WGSL: &str = include_str!("filter.wgsl");
const ORPHANS_WGSL: &str = include_str!("orphans.wgsl");

/// types.wgsl after the limits it sizes its arrays and counters with.
fn types_wgsl() -> String {
    format!(
        "const MAX_SPECULAR: u32 = {MAX_SPECULAR}u;\nconst MAX_LEVELS: u32 = {MAX_LEVELS}u;\nconst MAX_BOUNCES: u32 = {MAX_BOUNCES}u;\n{TYPES_WGSL}"
    )
}

/// Group of the generate pass that holds the scene's triangle BVH (exact tracing).
const BVH_GROUP: u32 = 3;

/// Beam generation: types, impostor tracing, the scene's BVH, light paths, the control
/// words, the refinement kernels.
pub fn generate_source() -> String {
    shader::compose_method(&format!(
        "{}\n{IMPOSTOR_TRACE_WGSL}\n{}\n{PATH_WGSL}\n{}\n{GENERATE_WGSL}",
        types_wgsl(),
        caustics_gpu::triangle_bvh::wgsl(BVH_GROUP),
        control::wgsl()
    ))
}

/// Hull rasterization with the per-fragment beam intersection; `depth_culled`: with
/// the fragment shader's depth test forced before it runs (`@early_depth_test(force)`,
/// [`wgpu::Features::SHADER_EARLY_DEPTH_TEST`]), for the depth-culled pass of a scene
/// without a medium ([`HullRaster`]).
pub fn rasterize_source(depth_culled: bool) -> String {
    let fragment = if depth_culled {
        "@fragment @early_depth_test(force)"
    } else {
        "@fragment"
    };
    shader::compose_method(&format!(
        "{}\n{BEAM_SHADING_WGSL}\n{}",
        types_wgsl(),
        RASTERIZE_WGSL.replace(RASTERIZE_FRAGMENT_ATTRIBUTE, fragment)
    ))
}

/// The attribute line of `fs_beam` in rasterize.wgsl, where [`rasterize_source`] forces
/// the early depth test.
const RASTERIZE_FRAGMENT_ATTRIBUTE: &str = "@fragment // fs_beam";

/// The depth test of the depth-culled hull pass: a back-face fragment passes at or
/// behind the visible surface. Read-only. The bias moves the hull's depth back by a few
/// depth units (more on faces seen edge-on), so that a visible point on the hull's
/// boundary (a receiver in the plane of the beam's far cap, a point on a side face)
/// is not rejected by rounding: the test may keep a fragment that lights nothing, and
/// the images stay the same byte for byte (every built-in scene at 96×72, the
/// ci-smoke baseline; water_pool and sphere_on_plane at 1024×768).
fn hull_depth_cull_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: caustics_gpu::textures::DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
        stencil: Default::default(),
        bias: wgpu::DepthBiasState {
            constant: 16,
            slope_scale: 2.0,
            clamp: 0.0,
        },
    }
}

/// The compute rasterizer (`raster` = compute): the same per-pixel beam intersection
/// over each hull's screen rectangle, into the fixed-point accumulator.
pub fn rasterize_compute_source() -> String {
    shader::compose_method(&format!(
        "{}\n{}\n{BEAM_SHADING_WGSL}\n{}\n{}\n{RASTERIZE_COMPUTE_WGSL}",
        types_wgsl(),
        control::wgsl(),
        shader::FIXED_POINT_WGSL,
        shader::RASTER_COUNTS_WGSL
    ))
}

/// The compute rasterizer's accumulator into the raw surface caustic and the volume.
pub fn resolve_source() -> String {
    shader::compose_method(&format!("{}\n{RESOLVE_WGSL}", shader::FIXED_POINT_WGSL))
}

/// The orphan corners as points (`splat_orphans`).
pub fn orphans_source() -> String {
    shader::compose_method(&format!("{}\n{ORPHANS_WGSL}", types_wgsl()))
}

/// The surface-caustic low-pass filter.
pub fn filter_source() -> String {
    shader::compose_method(FILTER_WGSL)
}

/// Most caustic generators (specular objects) a scene may have.
pub const MAX_SPECULAR: usize = 4;

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
    sphere_light: false,
    environment_light: false,
    no_medium_in_paper: "",
};

/// Scene limits of the beam pipeline beyond [`CAPABILITIES`].
pub fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    if scene.lights.is_empty() {
        return Err(Unsupported("the scene has no light".into()));
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
    if let Some(b) = scene.specular_bounds() {
        for (l, light) in scene.lights.iter().enumerate() {
            if LightView::fit_points(light, &b.corners(), 16).is_none() {
                return Err(Unsupported(format!(
                    "lights[{l}] is among the specular objects; its light G-buffer must see them from outside"
                )));
            }
        }
    }
    Ok(())
}

/// Byte offset of the hull draw's arguments in the indirect-arguments buffer.
const DRAW_ARGS_OFFSET: u64 = 16;
/// Byte offset of the orphan point draw's arguments there.
const ORPHAN_DRAW_ARGS_OFFSET: u64 = 32;
/// Byte offset of the compute rasterizer's dispatch arguments there.
const RASTER_DISPATCH_ARGS_OFFSET: u64 = 48;
/// Byte offset of `trace_lattice`'s dispatch (the vertex cache) in the indirect buffer.
const LATTICE_DISPATCH_ARGS_OFFSET: u64 = 64;
/// Byte offset of `emit_beams`'s dispatch (one invocation per beam).
const BEAM_DISPATCH_ARGS_OFFSET: u64 = 80;
/// Byte offset of `emit_orphans`'s dispatch (one invocation per orphan record).
const ORPHAN_DISPATCH_ARGS_OFFSET: u64 = 92;
/// Bytes of the indirect-arguments buffer (`indirect_args` in generate.wgsl).
const INDIRECT_ARGS_BYTES: u64 = 104;
/// u32 words per camera pixel of the compute rasterizer's accumulator (`ACCUM_WORDS` in
/// rasterize_compute.wgsl and resolve.wgsl): surface and volume RGB, a fixed-point
/// channel each.
const ACCUM_WORDS_PER_PIXEL: u64 = 6 * shader::FIXED_POINT_WORDS;
/// Bytes of the compute rasterizer's pair counts (`raster_counts`: two 64-bit counts).
const RASTER_COUNTS_BYTES: u64 = 16;

/// The beam pipeline bound to one scene.
///
/// The paper builds the beams of one light. A scene with several gets the paper's
/// pipeline once per light, as if each were alone (its own light view, G-buffer, grid,
/// refinement and beam budget), into the same images: beams of different lights never
/// interact, so the caustic is the sum of each light's (the superposition the
/// reference's photons obey too). The passes are shared: each light binds its own
/// group 1 (and the generate pass's group 2) inside them.
pub struct BeamMethod {
    config: BeamConfig,
    impostor_pass: ImpostorPass,
    atlas: ImpostorAtlas,
    buffers: Buffers,
    /// Vertices a side of the vertex cache's lattice (0: none).
    vertex_cache_side: u32,
    /// The vertex cache also holds the Fresnel reflection: corners are traced at the
    /// last level too.
    cache_reflected: bool,
    /// `vertex_irradiance`: its kernel gives the beams their corners' factors after the
    /// last level.
    vertex_irradiance: bool,
    /// The vertices' beam lists `vertex_irradiance` adds to each light's control
    /// buffer, in the memory ledger.
    _vertex_list_memory: Option<Reservation>,
    /// One per scene light, in the scene's order.
    lights: Vec<LightBeams>,
    generate: ComputePass,
    rasterize: HullRaster,
    /// With `splat_orphans`: the landed corners of the families leaves drop, as points.
    orphan_points: Option<RasterPass>,
    surface_filter: RasterPass,
    pass_names: PassNames,
    bytes: u64,
}

/// One light's beams: its light G-buffer, what its beams are written to, and its bind
/// groups of the shared passes.
struct LightBeams {
    light_gbuffer: GBuffer,
    buffers: LightBuffers,
    /// Group 1 of `generate`.
    generate_group: wgpu::BindGroup,
    /// Group 2 of `generate`: the indirect arguments, for the kernels that write them.
    args: wgpu::BindGroup,
    /// Group 1 of the hull rasterization (hardware or compute).
    raster_group: wgpu::BindGroup,
    /// Group 1 of `orphan_points` (with `splat_orphans`).
    orphan_group: Option<wgpu::BindGroup>,
}

/// How the hulls reach the image (`raster`).
enum HullRaster {
    /// The paper's: the hulls drawn, their fragments blended.
    Hardware {
        pass: RasterPass,
        /// Back faces tested against the camera G-buffer's depth (no medium, and the
        /// adapter forces early depth tests): see [`HullRaster::build`].
        depth_culled: bool,
    },
    /// The compute rasterizer and its resolve, the fixed-point accumulator they share
    /// and the pair counters.
    Compute {
        rasterize: ComputePass,
        resolve: RasterPass,
        /// `raster_pairs_shaded`, `raster_pairs_lit` (64-bit): cleared each frame,
        /// added to by every light's beams.
        counts: wgpu::Buffer,
        /// Every light's beams add into it; the one resolve writes their sum.
        accumulator: wgpu::Buffer,
        _memory: Reservation,
    },
}

impl HullRaster {
    /// The passes `raster` asks for, and the bytes they hold; group 1 is each light's
    /// ([`HullRaster::light_group`]).
    fn build(
        ctx: &GpuContext,
        renderer: &Renderer,
        config: &BeamConfig,
        name: &'static str,
    ) -> Result<(Self, u64), MethodError> {
        // beam_shading.wgsl's volume caustic is compiled in only for a scene with a
        // medium: lavapipe runs both sides of a branch on a uniform, so every pixel
        // of every hull paid for the scan-plane segment (sphere_on_plane 256x192,
        // static 64^2: rasterize 224.1 -> 171.2 ms without it).
        // vertex_irradiance's factors likewise exist only where asked.
        let shading = [
            (
                "BEAM_MEDIUM",
                f64::from(u8::from(renderer.scene().scene.medium.is_some())),
            ),
            (
                "VERTEX_IRRADIANCE",
                f64::from(u8::from(config.beams.vertex_irradiance)),
            ),
        ];
        match config.beams.raster {
            Raster::Hardware => {
                // Without a medium a beam lights only the visible point, and only where
                // that point lies inside its hull: then the camera ray leaves the hull
                // through a back face at or behind the point. A back-face fragment in
                // front of the visible surface (the sides of a tall beam seen against
                // the floor beyond it) lights nothing, so the camera G-buffer's depth,
                // attached read-only, rejects it before the shader runs; the image is
                // the same (the shader returns zero there). Forced early (the fill
                // counting frame writes storage, which would otherwise test late), so
                // every frame shades and counts the same fragments; an adapter without
                // the feature draws every back face, as the paper's pass does.
                let depth_culled = renderer.scene().scene.medium.is_none()
                    && ctx
                        .features
                        .contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST);
                let shader =
                    Shader::new(ctx, "beams rasterize.wgsl", rasterize_source(depth_culled))?;
                let mut builder =
                    RasterPass::builder(ctx, &format!("{name}/rasterize"), &shader, "vs_beam")
                        .frame(renderer)
                        .caller_group(1)
                        .fragment(
                            "fs_beam",
                            &[Some(additive_hdr_target()), Some(additive_hdr_target())],
                        )
                        // Hull triangles face outwards: drawing back faces only shades
                        // each covered pixel once per beam, also with the camera inside
                        // a hull.
                        .primitive(wgpu::PrimitiveState {
                            front_face: wgpu::FrontFace::Ccw,
                            cull_mode: Some(wgpu::Face::Front),
                            ..Default::default()
                        })
                        .counted()
                        .constants(&shading);
                if depth_culled {
                    builder = builder.depth_stencil(hull_depth_cull_state());
                }
                let pass = builder.build()?;
                Ok((Self::Hardware { pass, depth_culled }, 0))
            }
            Raster::Compute => {
                let camera = &renderer.scene().scene.camera;
                let pixels = u64::from(camera.width) * u64::from(camera.height);
                let bytes = pixels * ACCUM_WORDS_PER_PIXEL * 4;
                let what = format!(
                    "raster=compute: the fixed-point accumulator ({pixels} pixels x {} bytes)",
                    ACCUM_WORDS_PER_PIXEL * 4
                );
                let param = |e: GpuError| MethodError::Param {
                    method: name,
                    message: e.to_string(),
                };
                let lower = "render fewer pixels or use raster=hardware";
                // rasterize_compute.wgsl finds a pixel's row with an f32 quotient, exact
                // below 2^24.
                if pixels > 1 << 24 {
                    return Err(MethodError::Param {
                        method: name,
                        message: format!(
                            "raster=compute: {pixels} camera pixels, more than the compute rasterizer's 2^24; {lower}"
                        ),
                    });
                }
                ctx.limits.storage(&what, bytes, lower).map_err(param)?;
                let memory = ctx.memory.reserve(&what, bytes, lower).map_err(param)?;
                let device = &ctx.device;
                // Zero at creation; each resolve zeroes what it read.
                let accumulator = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("beam compute raster accumulator"),
                    size: bytes,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                });
                let counts = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("beam compute raster counts"),
                    size: RASTER_COUNTS_BYTES,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let shader = Shader::new(
                    ctx,
                    "beams rasterize_compute.wgsl",
                    rasterize_compute_source(),
                )?;
                let rasterize = ComputePass::builder(ctx, &format!("{name}/rasterize"), &shader)
                    .frame(renderer)
                    .caller_group(1)
                    .kernels(&["rasterize"])
                    .constants(&shading)
                    .build()?;
                let shader = Shader::new(ctx, "beams resolve.wgsl", resolve_source())?;
                let resolve = RasterPass::fullscreen(
                    ctx,
                    &format!("{name}/resolve"),
                    &shader,
                    "fs_resolve",
                    &[Some(additive_hdr_target()), Some(additive_hdr_target())],
                )
                .frame(renderer)
                .bind(1, &[("accum", &accumulator)])
                .build()?;
                Ok((
                    Self::Compute {
                        rasterize,
                        resolve,
                        counts,
                        accumulator,
                        _memory: memory,
                    },
                    bytes + RASTER_COUNTS_BYTES,
                ))
            }
        }
    }

    /// Group 1 of the rasterization for one light's beams.
    fn light_group(
        &self,
        device: &wgpu::Device,
        light: &LightBuffers,
    ) -> Result<wgpu::BindGroup, GpuError> {
        match self {
            Self::Hardware { pass, .. } => pass
                .caller_schema(1)?
                .bind(device, &[("u", &light.uniforms), ("beams", &light.beams)]),
            Self::Compute {
                rasterize,
                counts,
                accumulator,
                ..
            } => rasterize.caller_schema(1)?.bind(
                device,
                &[
                    ("u", &light.uniforms),
                    ("beams", &light.beams),
                    ("control", &light.control),
                    ("accum", accumulator),
                    ("raster_counts", counts),
                ],
            ),
        }
    }
}

struct PassNames {
    light_gbuffer: String,
    impostors: String,
}

/// A uniform buffer holding `contents`.
fn uniform_buffer(device: &wgpu::Device, label: &str, contents: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// Most bytes the vertex cache may take: beyond them (a fine grid refined deep) the
/// paths are traced where they are asked for, as without it.
const VERTEX_CACHE_MAX_BYTES: u64 = 64 << 20;

/// Vertices a side of the vertex cache's lattice (generate.wgsl `trace_lattice`):
/// grid·2^levels cells a side, the finest the refinement reaches, where every corner and
/// oracle midpoint lies; 0 where its entries (one per vertex and cached light-path
/// family, and one for the generation count) would take more than
/// [`VERTEX_CACHE_MAX_BYTES`] or `max_binding_bytes`.
pub fn vertex_cache_side(grid: u32, levels: u32, families: u32, max_binding_bytes: u64) -> u32 {
    // grid <= 256 and levels <= MAX_LEVELS: the side fits a u32 with room.
    let side = u32::try_from((u64::from(grid) << levels) + 1).unwrap_or(u32::MAX);
    if vertex_cache_bytes(side, families) <= VERTEX_CACHE_MAX_BYTES.min(max_binding_bytes) {
        side
    } else {
        0
    }
}

/// The vertex cache's buffer bytes for a lattice of `side` vertices a side and
/// `families` light-path families (one entry where there is none: the shader declares
/// an array of them).
fn vertex_cache_bytes(side: u32, families: u32) -> u64 {
    (1 + u64::from(families) * u64::from(side).pow(2)) * VERTEX_PATH_BYTES
}

/// The vertex cache a run gets: its lattice, the families it holds and its bytes in the
/// memory ledger.
struct VertexCachePlan {
    /// Vertices a side (0: no cache).
    side: u32,
    /// 1: the main path; 2: also the Fresnel reflection (generate.wgsl
    /// `CACHE_REFLECTED`).
    families: u32,
    memory: Option<Reservation>,
}

/// The vertex cache for `config` on this device, its bytes held in the memory ledger:
/// the main path and, where a leaf may ask for it (`reflects`: `reflections` on a scene
/// with a dielectric generator), the Fresnel reflection; the main path alone where both
/// would not fit, none (side 0) where that would not either, for it only saves time.
fn plan_vertex_cache(ctx: &GpuContext, config: &BeamConfig, reflects: bool) -> VertexCachePlan {
    let none = VertexCachePlan {
        side: 0,
        families: 1,
        memory: None,
    };
    if !config.beams.vertex_cache {
        return none;
    }
    let limits = &ctx.limits;
    let binding = limits
        .max_storage_binding_bytes
        .min(limits.max_buffer_bytes);
    let families: &[u32] = if reflects { &[2, 1] } else { &[1] };
    for &families in families {
        let side = vertex_cache_side(
            config.beams.grid,
            config.refinement.levels,
            families,
            binding,
        );
        if side == 0 {
            continue;
        }
        if let Ok(reservation) = ctx.memory.reserve(
            "beam vertex cache",
            vertex_cache_bytes(side, families),
            "none needed: the cache is left out",
        ) {
            return VertexCachePlan {
                side,
                families,
                memory: Some(reservation),
            };
        }
    }
    none
}

/// The words each light's control buffer holds past the counters for
/// `vertex_irradiance` (0 without it): a beam list per lattice vertex and
/// light-path family (control.rs `VERTEX_LIST_WORDS`), held for `lights` lights in the
/// memory ledger. The lattice is the vertex cache's, so it must be there.
fn plan_vertex_lists(
    ctx: &GpuContext,
    config: &BeamConfig,
    name: &'static str,
    vertex_cache_side: u32,
    lights: usize,
) -> Result<(u64, Option<Reservation>), MethodError> {
    if !config.beams.vertex_irradiance {
        return Ok((0, None));
    }
    let param = |message: String| MethodError::Param {
        method: name,
        message,
    };
    if vertex_cache_side == 0 {
        return Err(param(format!(
            "vertex_irradiance finds the beams of a vertex on the vertex cache's lattice, which this run has not: vertex_cache={} and its (grid x 2^levels + 1)^2 = {}^2 entries of {VERTEX_PATH_BYTES} bytes must fit 64 MiB and the device's storage binding; set vertex_cache=true, lower grid or levels, or vertex_irradiance=false",
            config.beams.vertex_cache,
            (u64::from(config.beams.grid) << config.refinement.levels) + 1,
        )));
    }
    let families = 2 + u64::from(config.beams.bounces);
    let words = u64::from(vertex_cache_side).pow(2) * families * VERTEX_LIST_WORDS as u64;
    let what = format!(
        "vertex_irradiance: the beam lists of {vertex_cache_side}^2 lattice vertices x {families} light-path families ({} bytes each) beside the control words",
        VERTEX_LIST_WORDS * 4
    );
    let lower = "lower grid, levels or bounces, or vertex_irradiance=false";
    ctx.limits
        .storage(&what, (CONTROL_WORDS as u64 + words) * 4, lower)
        .map_err(|e| param(e.to_string()))?;
    let memory = ctx
        .memory
        .reserve(&what, words * 4 * lights as u64, lower)
        .map_err(|e| param(e.to_string()))?;
    Ok((words, Some(memory)))
}

/// A storage buffer of `size` bytes (at least 16), with `extra` usages.
fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | extra,
        mapped_at_creation: false,
    })
}

/// Orphan records (and slots) only where they are written (`splat_orphans`).
fn orphan_capacity(config: &BeamConfig) -> u64 {
    if config.beams.splat_orphans {
        u64::from(config.beams.max_beams)
    } else {
        0
    }
}

/// What every light's beam generation uses in turn, sized by `max_beams` (the lights'
/// generations run one after another, so one set serves all), and the raw surface
/// caustic all lights' beams are drawn into.
struct Buffers {
    raw_surface: Target,
    candidates_a: wgpu::Buffer,
    candidates_b: wgpu::Buffer,
    actions: wgpu::Buffer,
    offsets: wgpu::Buffer,
    /// The vertex cache (one entry without it): the lights' generations run one after
    /// another and each stamps its own entries.
    vertex_paths: wgpu::Buffer,
    /// Its bytes in the memory ledger (none without it).
    _vertex_cache_memory: Option<Reservation>,
    control_init: wgpu::Buffer,
    filter_uniforms: wgpu::Buffer,
    /// The `max_beams` buffers' bytes (these and every light's) in the device's memory
    /// ledger.
    _memory: Reservation,
}

/// What one light's beams are written to and drawn from: kept until the next frame's
/// generation, so a scoring sub-frame that reuses the light side draws them again.
struct LightBuffers {
    uniforms: wgpu::Buffer,
    beams: wgpu::Buffer,
    /// `splat_orphans`' records (a 16-byte placeholder without it).
    orphans: wgpu::Buffer,
    control: wgpu::Buffer,
    indirect_args: wgpu::Buffer,
}

impl LightBuffers {
    /// With `vertex_list_words` words for `vertex_irradiance` past the control
    /// words (0 without).
    fn new(
        device: &wgpu::Device,
        config: &BeamConfig,
        uniforms: &BeamUniforms,
        vertex_list_words: u64,
    ) -> Self {
        let cap = u64::from(config.beams.max_beams);
        let copy = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        Self {
            uniforms: uniform_buffer(device, "beam uniforms", bytemuck::bytes_of(uniforms)),
            beams: storage_buffer(
                device,
                "beams",
                cap * BEAM_BYTES,
                wgpu::BufferUsages::COPY_SRC,
            ),
            // At least one record: the shader declares an array of them.
            orphans: storage_buffer(
                device,
                "beam orphans",
                orphan_capacity(config).max(1) * ORPHAN_BYTES,
                wgpu::BufferUsages::empty(),
            ),
            control: storage_buffer(
                device,
                "beam control",
                (CONTROL_WORDS as u64 + vertex_list_words) * 4,
                copy,
            ),
            indirect_args: storage_buffer(
                device,
                "beam indirect args",
                INDIRECT_ARGS_BYTES,
                wgpu::BufferUsages::INDIRECT,
            ),
        }
    }

    fn bytes(&self) -> u64 {
        [
            &self.uniforms,
            &self.beams,
            &self.orphans,
            &self.control,
            &self.indirect_args,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }
}

impl Buffers {
    fn new(
        ctx: &GpuContext,
        camera: &caustics_scene::Camera,
        config: &BeamConfig,
        memory: Reservation,
        vertex_cache: VertexCachePlan,
    ) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let storage = |label: &str, size: u64| {
            storage_buffer(device, label, size, wgpu::BufferUsages::empty())
        };
        let cap = u64::from(config.beams.max_beams);
        let filter = FilterUniforms::new(config.beams.surface_filter_px);
        Ok(Self {
            raw_surface: Target::new(
                ctx,
                "beam raw surface caustic",
                HDR_FORMAT,
                camera.width,
                camera.height,
                1,
                wgpu::TextureUsages::empty(),
            )?,
            candidates_a: storage("beam candidates a", cap * CANDIDATE_BYTES),
            candidates_b: storage("beam candidates b", cap * CANDIDATE_BYTES),
            actions: storage("beam actions", cap * 4),
            // Children and beam offsets, and splat_orphans' family mask and record
            // offset.
            offsets: storage("beam offsets", cap * 16),
            vertex_paths: storage(
                "beam vertex cache",
                vertex_cache_bytes(vertex_cache.side, vertex_cache.families),
            ),
            _vertex_cache_memory: vertex_cache.memory,
            control_init: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("beam control reset"),
                contents: bytemuck::cast_slice(&[0u32; CONTROL_WORDS]),
                usage: wgpu::BufferUsages::COPY_SRC,
            }),
            filter_uniforms: uniform_buffer(
                device,
                "beam filter uniforms",
                bytemuck::bytes_of(&filter),
            ),
            _memory: memory,
        })
    }

    fn bytes(&self) -> u64 {
        self.raw_surface.bytes
            + [
                &self.candidates_a,
                &self.candidates_b,
                &self.actions,
                &self.offsets,
                &self.vertex_paths,
                &self.control_init,
                &self.filter_uniforms,
            ]
            .iter()
            .map(|b| b.size())
            .sum::<u64>()
    }
}

impl BeamMethod {
    /// Builds the pipeline for the renderer's scene. `name` prefixes every pass.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        config: &BeamConfig,
        name: &'static str,
    ) -> Result<Self, MethodError> {
        config.check().map_err(|message| MethodError::Param {
            method: name,
            message,
        })?;
        let gpu_scene = renderer.scene();
        let scene = &gpu_scene.scene;
        let unsupported = |reason: Unsupported| MethodError::Unsupported {
            method: name,
            scene: scene.name.clone(),
            reason,
        };
        check_scene(scene).map_err(unsupported)?;
        let slots = gpu_types::slots(scene, gpu_scene);
        let points: Vec<Vec3> = slots
            .iter()
            .flat_map(|s| gpu_scene.meshes[s.object].positions.iter().copied())
            .collect();
        let views = scene
            .lights
            .iter()
            .enumerate()
            .map(|(l, light)| {
                LightView::fit_points(light, &points, config.beams.light_resolution).ok_or_else(
                    || {
                        unsupported(Unsupported(format!(
                            "no view of lights[{l}] holds the specular objects"
                        )))
                    },
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        let memory =
            reserve_beam_buffers(ctx, config, views.len()).map_err(|e| MethodError::Param {
                method: name,
                message: e.to_string(),
            })?;
        ctx.checked("beam pipeline setup", || {
            Self::build(ctx, renderer, config, name, &slots, &views, memory)
        })?
    }

    /// The passes of Sect. 4–7: the light G-buffer (one per light) and the impostors
    /// of the generators, beam generation, hull rasterization, the surface filter.
    fn build(
        ctx: &GpuContext,
        renderer: &Renderer,
        config: &BeamConfig,
        name: &'static str,
        slots: &[Slot],
        views: &[LightView],
        memory: Reservation,
    ) -> Result<Self, MethodError> {
        let device = &ctx.device;
        let scene = &renderer.scene().scene;
        let impostor_pass = ImpostorPass::new(ctx)?;
        let atlas = impostor_atlas(ctx, renderer, &impostor_pass, slots, config)?;
        // Whether a leaf may ask for the Fresnel reflection at all.
        let reflects = config.beams.reflections && slots.iter().any(Slot::is_dielectric);
        let vertex_cache = plan_vertex_cache(ctx, config, reflects);
        let vertex_cache_side = vertex_cache.side;
        let cache_reflected = vertex_cache_side > 0 && vertex_cache.families > 1;
        // The families a leaf may trace itself: the internal reflections, and the
        // Fresnel reflection of a dielectric where the cache does not hold it.
        let family_tracer = config.beams.bounces > 0 || (reflects && !cache_reflected);
        let (vertex_list_words, vertex_list_memory) =
            plan_vertex_lists(ctx, config, name, vertex_cache_side, views.len())?;
        let b = Buffers::new(ctx, &scene.camera, config, memory, vertex_cache)?;

        // Built (once per scene) also for the impostor tracer: the pass binds it either way.
        let bvh = renderer.scene().triangle_bvh(ctx)?;
        let shader = Shader::new(ctx, "beams generate.wgsl", generate_source())?;
        let generate = ComputePass::builder(ctx, &format!("{name}/generate"), &shader)
            .frame(renderer)
            .caller_group(1)
            .bind(
                BVH_GROUP,
                &[("bvh_nodes", &bvh.nodes), ("bvh_triangles", &bvh.triangles)],
            )
            .caller_group(2)
            .kernels(&[
                "init_grid",
                "gather_lattice",
                "lattice_args",
                "trace_lattice",
                "decide",
                "budget",
                "scan",
                "emit",
                "emit_beams",
                "emit_orphans",
                "advance",
                "vertex_irradiance",
                "finalize",
            ])
            // The kernels dispatched from the indirect arguments must not also bind
            // them as storage (group 2): a buffer is one or the other in a dispatch.
            .kernel_groups("gather_lattice", &[0, 1])
            .kernel_groups("trace_lattice", &[0, 1, BVH_GROUP])
            .kernel_groups("decide", &[0, 1, BVH_GROUP])
            .kernel_groups("budget", &[0, 1])
            .kernel_groups("scan", &[0, 1])
            .kernel_groups("emit", &[0, 1])
            .kernel_groups("emit_beams", &[0, 1, BVH_GROUP])
            .kernel_groups("emit_orphans", &[0, 1, BVH_GROUP])
            .kernel_groups("vertex_irradiance", &[0, 1])
            // split_families is compiled in only where asked (generate.wgsl `decide`),
            // and the vertex cache where it is used (`main_path`).
            .constants(&[
                (
                    "SPLIT_FAMILIES",
                    f64::from(u8::from(config.refinement.split_families)),
                ),
                ("CLIP_LEAVES", f64::from(u8::from(config.beams.clip_leaves))),
                ("VERTEX_CACHE", f64::from(u8::from(vertex_cache_side > 0))),
                ("CACHE_REFLECTED", f64::from(u8::from(cache_reflected))),
                ("FAMILY_TRACER", f64::from(u8::from(family_tracer))),
                (
                    "POSITIONAL_LIGHTS",
                    f64::from(u8::from(
                        scene
                            .lights
                            .iter()
                            .any(|light| !matches!(light, Light::Directional { .. })),
                    )),
                ),
                (
                    "VERTEX_IRRADIANCE",
                    f64::from(u8::from(vertex_list_words > 0)),
                ),
                ("VERTEX_IRRADIANCE_MAX", config.beams.vertex_irradiance_max),
                (
                    "ORPHAN_VERTICES",
                    f64::from(point_kernel_vertices(config.beams.orphan_kernel_px)),
                ),
            ])
            .build()?;

        let (rasterize, raster_bytes) = HullRaster::build(ctx, renderer, config, name)?;

        let orphan_points = if config.beams.splat_orphans {
            let shader = Shader::new(ctx, "beams orphans.wgsl", orphans_source())?;
            Some(
                RasterPass::builder(ctx, &format!("{name}/orphan_points"), &shader, "vs_orphan")
                    .frame(renderer)
                    .caller_group(1)
                    .fragment("fs_orphan", &[Some(additive_hdr_target())])
                    .counted()
                    .constants(&[("ORPHAN_SIGMA_PX", config.beams.orphan_kernel_px)])
                    .points_or_kernel_quads(config.beams.orphan_kernel_px)
                    .build()?,
            )
        } else {
            None
        };

        let shader = Shader::new(ctx, "beams filter.wgsl", filter_source())?;
        let surface_filter = RasterPass::fullscreen(
            ctx,
            &format!("{name}/surface_filter"),
            &shader,
            "fs_filter",
            &[Some(additive_hdr_target())],
        )
        .frame(renderer)
        .bind(
            1,
            &[
                ("fu", &b.filter_uniforms),
                ("raw_surface", &b.raw_surface.view),
            ],
        )
        .build()?;

        let mut lights = Vec::with_capacity(views.len());
        let mut bytes = atlas.bytes() + b.bytes() + raster_bytes;
        for (index, view) in views.iter().enumerate() {
            let light_gbuffer = renderer.gbuffer_pass().light_gbuffer(ctx, view)?;
            let uniforms =
                BeamUniforms::new(scene, config, index, view, slots, &atlas, vertex_cache_side);
            let lb = LightBuffers::new(device, config, &uniforms, vertex_list_words);
            let generate_group = generate.caller_schema(1)?.bind(
                device,
                &[
                    ("u", &lb.uniforms),
                    ("light_position", &light_gbuffer.position.view),
                    ("light_normal", &light_gbuffer.normal.view),
                    ("light_ids", &light_gbuffer.ids.view),
                    ("impostor_map", &atlas.normal_distance.view),
                    ("impostor_ids", &atlas.object_ids.view),
                    ("candidates_a", &b.candidates_a),
                    ("candidates_b", &b.candidates_b),
                    ("actions", &b.actions),
                    ("offsets", &b.offsets),
                    ("control", &lb.control),
                    ("beams", &lb.beams),
                    ("orphans", &lb.orphans),
                    ("vertex_paths", &b.vertex_paths),
                ],
            )?;
            let args = indirect_args_group(device, &generate, &lb.indirect_args)?;
            let raster_group = rasterize.light_group(device, &lb)?;
            let orphan_group = match &orphan_points {
                Some(pass) => Some(
                    pass.caller_schema(1)?
                        .bind(device, &[("u", &lb.uniforms), ("orphans", &lb.orphans)])?,
                ),
                None => None,
            };
            bytes += light_gbuffer.bytes() + lb.bytes();
            lights.push(LightBeams {
                light_gbuffer,
                buffers: lb,
                generate_group,
                args,
                raster_group,
                orphan_group,
            });
        }
        Ok(Self {
            config: config.clone(),
            impostor_pass,
            atlas,
            buffers: b,
            vertex_cache_side,
            cache_reflected,
            vertex_irradiance: vertex_list_words > 0,
            _vertex_list_memory: vertex_list_memory,
            lights,
            generate,
            rasterize,
            orphan_points,
            surface_filter,
            pass_names: PassNames {
                light_gbuffer: format!("{name}/light_gbuffer"),
                impostors: format!("{name}/impostors"),
            },
            bytes,
        })
    }

    /// The light-path families the vertex cache holds: 0 without it, 1 (the main path)
    /// or 2 (also the Fresnel reflection).
    pub fn vertex_cache_families(&self) -> u32 {
        match (self.vertex_cache_side, self.cache_reflected) {
            (0, _) => 0,
            (_, false) => 1,
            (_, true) => 2,
        }
    }

    /// The beams of the last frame, read back, the scene's lights in order (tests and
    /// diagnostics; not per frame).
    pub fn read_beams(&self, ctx: &GpuContext) -> Result<Vec<BeamRecord>, MethodError> {
        let mut out = Vec::new();
        for light in &self.lights {
            let control = read_control(ctx, &light.buffers)?;
            let count = control[control::BEAM_TOTAL.index] as u64;
            if count == 0 {
                continue;
            }
            let bytes = caustics_gpu::readback::read_buffer_bytes(
                ctx,
                &light.buffers.beams,
                count * BEAM_BYTES,
                "beams",
            )?;
            out.extend(bytemuck::pod_collect_to_vec::<u8, BeamRecord>(&bytes));
        }
        Ok(out)
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &BeamConfig {
        &self.config
    }
}

/// One light's control words, read back.
fn read_control(ctx: &GpuContext, light: &LightBuffers) -> Result<Vec<u32>, MethodError> {
    let control = &light.control;
    // The counters only, not `vertex_irradiance`'s lists after them.
    Ok(caustics_gpu::readback::read_buffer_u32(
        ctx,
        control,
        (CONTROL_WORDS * 4) as u64,
        "beam control",
    )?)
}

/// The beam and candidate buffers `max_beams` sizes (the candidates once, the beams
/// once per light of `lights`), against the device's largest storage binding and the
/// memory budget (summed with what is held), reserved before any is made.
fn reserve_beam_buffers(
    ctx: &GpuContext,
    config: &BeamConfig,
    lights: usize,
) -> Result<Reservation, GpuError> {
    let limits = &ctx.limits;
    // The light G-buffer and the impostors are textures (their bytes are reserved as
    // they are made); their sides are checked here, naming the parameter.
    for (name, side) in [
        ("light_resolution", config.beams.light_resolution),
        ("impostor_resolution", config.beams.impostor_resolution),
    ] {
        limits.texture(
            &format!("{name}: a {side}x{side} texture"),
            side,
            side,
            &format!("lower {name}"),
        )?;
    }
    let cap = u64::from(config.beams.max_beams);
    let most = limits.storage_elements(BEAM_BYTES.max(CANDIDATE_BYTES));
    let raise = format!("lower max_beams (at most {most} on this device)");
    limits.storage(
        &format!("max_beams: the beam buffer ({cap} x {BEAM_BYTES} bytes)"),
        cap * BEAM_BYTES,
        &raise,
    )?;
    // Both candidate lists, the actions and the offsets once; each light's beams (with
    // splat_orphans its orphan records).
    let orphan_bytes = if config.beams.splat_orphans {
        ORPHAN_BYTES
    } else {
        0
    };
    let per_beam = 2 * CANDIDATE_BYTES + 4 + 16 + lights as u64 * (BEAM_BYTES + orphan_bytes);
    ctx.memory.reserve(
        &format!("max_beams: the beam generation buffers ({cap} beams, {lights} lights)"),
        cap * per_beam,
        &raise,
    )
}

/// One atlas of distance impostors: the specular slots in order, then the receivers
/// around the generators' centre (Umenhoffer's distance map of the environment).
fn impostor_atlas(
    ctx: &GpuContext,
    renderer: &Renderer,
    pass: &ImpostorPass,
    slots: &[Slot],
    config: &BeamConfig,
) -> Result<ImpostorAtlas, MethodError> {
    let gpu_scene = renderer.scene();
    let scene = &gpu_scene.scene;
    let receivers: Vec<usize> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| !scene.material(o).is_specular())
        .map(|(i, _)| i)
        .collect();
    let specular_center = scene.specular_bounds().map(|b| b.center());
    let mut entries: Vec<(Vec<usize>, Option<Vec3>)> =
        slots.iter().map(|s| (vec![s.object], s.center)).collect();
    entries.push((receivers, specular_center));
    Ok(pass.atlas(ctx, gpu_scene, &entries, config.beams.impostor_resolution)?)
}

/// Group 2 of the generate pass: the indirect arguments `buffer`.
fn indirect_args_group(
    device: &wgpu::Device,
    generate: &ComputePass,
    buffer: &wgpu::Buffer,
) -> Result<wgpu::BindGroup, MethodError> {
    Ok(generate
        .caller_schema(2)?
        .bind(device, &[("indirect_args", buffer)])?)
}

impl BeamMethod {
    /// Generates the beams: light G-buffers and impostors (impostor tracer), then per
    /// light the base grid, refined level by level, and the draw arguments.
    fn record_light_side(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        let scene = renderer.scene();
        let b = &self.buffers;
        for light in &self.lights {
            let control = &light.buffers.control;
            let words = (CONTROL_WORDS * 4) as u64;
            frame
                .encoder
                .copy_buffer_to_buffer(&b.control_init, 0, control, 0, words);
            if self.vertex_irradiance {
                // The lattice vertices' beam lists start empty.
                frame.encoder.clear_buffer(control, words, None);
            }
        }
        // Exact tracing reads neither the light G-buffer nor the impostors.
        if self.config.beams.tracer == Tracer::Impostor {
            for light in &self.lights {
                renderer.gbuffer_pass().record(
                    frame,
                    &self.pass_names.light_gbuffer,
                    scene,
                    &light.light_gbuffer,
                )?;
            }
            self.impostor_pass.record_atlas(
                frame,
                &self.pass_names.impostors,
                scene,
                &self.atlas,
            )?;
        }
        let mut pass = self.generate.begin(frame)?;
        let base = 2 * self.config.beams.grid * self.config.beams.grid;
        let ranked = self.config.refinement.beam_budget > 0;
        let levels = self.config.refinement.levels;
        // One light after another: they share the candidate lists.
        for light in &self.lights {
            let args = &light.buffers.indirect_args;
            pass.set_bind_group(1, &light.generate_group, &[]);
            pass.set_bind_group(2, &light.args, &[]);
            pass.dispatch("init_grid", [base.div_ceil(64), 1, 1])?;
            for level in 0..=levels {
                // The vertices this level needs and the earlier ones did not trace: the
                // base grid's and its midpoints, then the midpoints of each level's
                // candidates (its corners were the level before's), and with the
                // Fresnel reflection cached, the reflected paths of the level's new
                // corners. The last level of a refined grid needs no midpoints.
                if self.vertex_cache_side > 0
                    && (level < levels || levels == 0 || self.cache_reflected)
                {
                    let side = (self.config.beams.grid << (level + 1).min(levels)) + 1;
                    pass.dispatch("gather_lattice", [(side * side).div_ceil(64), 1, 1])?;
                    pass.dispatch("lattice_args", [1, 1, 1])?;
                    pass.dispatch_indirect("trace_lattice", args, LATTICE_DISPATCH_ARGS_OFFSET)?;
                }
                pass.dispatch_indirect("decide", args, 0)?;
                // The last level splits nothing: no threshold to find.
                if ranked && level < levels {
                    pass.dispatch("budget", [1, 1, 1])?;
                }
                pass.dispatch("scan", [1, 1, 1])?;
                pass.dispatch_indirect("emit", args, 0)?;
                pass.dispatch("advance", [1, 1, 1])?;
            }
            // Every level's leaves at once: one dispatch of the tracer and the hull
            // per light, not one per level.
            pass.dispatch_indirect("emit_beams", args, BEAM_DISPATCH_ARGS_OFFSET)?;
            if self.config.beams.splat_orphans {
                pass.dispatch_indirect("emit_orphans", args, ORPHAN_DISPATCH_ARGS_OFFSET)?;
            }
            if self.vertex_irradiance {
                let cap = self.config.beams.max_beams;
                pass.dispatch("vertex_irradiance", [cap.div_ceil(256), 1, 1])?;
            }
            pass.dispatch("finalize", [1, 1, 1])?;
        }
        Ok(())
    }
}

impl CausticsMethod for BeamMethod {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        let b = &self.buffers;
        // Light side: the beams (and, for adaptive beams, the refinement the camera
        // decided in the whole frame before) are kept by a reused scoring sub-frame.
        if !frame.reuses_light_side() {
            self.record_light_side(frame)?;
        }
        // The raw surface caustic is cleared, the volume target added to.
        let targets = renderer.targets();
        let attachments = [
            Some(wgpu::RenderPassColorAttachment {
                view: &b.raw_surface.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            }),
            load_attachment(&targets.volume.view),
        ];
        match &self.rasterize {
            HullRaster::Hardware {
                pass: rasterize,
                depth_culled,
            } => {
                // Read-only (no depth ops): the G-buffer's depth stays as the base
                // passes wrote it.
                let depth = depth_culled.then(|| wgpu::RenderPassDepthStencilAttachment {
                    view: &renderer.camera_gbuffer().depth.layer_views[0],
                    depth_ops: None,
                    stencil_ops: None,
                });
                let mut pass = rasterize.begin(frame, &attachments, depth)?;
                for light in &self.lights {
                    pass.set_bind_group(1, &light.raster_group, &[]);
                    pass.draw_indirect(&light.buffers.indirect_args, DRAW_ARGS_OFFSET);
                }
            }
            HullRaster::Compute {
                rasterize,
                resolve,
                counts,
                ..
            } => {
                frame.encoder.clear_buffer(counts, 0, None);
                {
                    let mut pass = rasterize.begin(frame)?;
                    for light in &self.lights {
                        pass.set_bind_group(1, &light.raster_group, &[]);
                        pass.dispatch_indirect(
                            "rasterize",
                            &light.buffers.indirect_args,
                            RASTER_DISPATCH_ARGS_OFFSET,
                        )?;
                    }
                }
                let mut pass = resolve.begin(frame, &attachments, None)?;
                pass.draw_fullscreen();
            }
        }
        if let Some(orphan_points) = &self.orphan_points {
            // Into the raw surface caustic, before the filter, beside the beams' light.
            let attachments = [load_attachment(&b.raw_surface.view)];
            let mut pass = orphan_points.begin(frame, &attachments, None)?;
            for light in &self.lights {
                if let Some(group) = &light.orphan_group {
                    pass.set_bind_group(1, group, &[]);
                    pass.draw_indirect(&light.buffers.indirect_args, ORPHAN_DRAW_ARGS_OFFSET);
                }
            }
        }
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        let mut pass = self.surface_filter.begin(frame, &attachments, None)?;
        pass.draw_fullscreen();
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        // Summed over the lights (each light's generation is the paper's whole one),
        // but for the levels run, which every light runs alike.
        let mut out = Counters::new();
        let mut beams = 0u64;
        for light in &self.lights {
            let c = read_control(ctx, &light.buffers)?;
            beams += u64::from(c[control::BEAM_TOTAL.index]);
            let counters =
                control::counters(&c, self.config.refinement.levels, self.config.beams.bounces);
            for (name, value) in counters {
                let sum = out.entry(name.clone()).or_insert(0);
                *sum = if Some(name.as_str()) == control::LEVEL.counter {
                    (*sum).max(value)
                } else {
                    *sum + value
                };
            }
        }
        // The orphans' counters only where they are drawn: the default's counters are
        // the paper's (and the regression baselines').
        if !self.config.beams.splat_orphans {
            for name in ["orphans", "overflow_orphans", "orphan_corners"] {
                out.remove(name);
            }
        }
        if !self.config.beams.clip_leaves {
            for name in [
                "beams_clipped",
                "beams_clipped_empty",
                "beams_clipped_rebased",
                "beams_clipped_landing",
            ] {
                out.remove(name);
            }
        }
        // Derived: 8 hull triangles per beam, 2 base triangles per grid cell and light.
        out.insert("hull_triangles".into(), 8 * beams);
        let grid = u64::from(self.config.beams.grid);
        out.insert(
            "base_triangles".into(),
            2 * grid * grid * self.lights.len() as u64,
        );
        // The compute rasterizer's pairs only where it runs (the hardware path's work
        // is its rasterize pass's fragments).
        if let HullRaster::Compute { counts, .. } = &self.rasterize {
            let w = caustics_gpu::readback::read_buffer_u32(
                ctx,
                counts,
                RASTER_COUNTS_BYTES,
                "beam raster counts",
            )?;
            let count = |i: usize| u64::from(w[i]) | (u64::from(w[i + 1]) << 32);
            out.insert("raster_pairs_shaded".into(), count(0));
            out.insert("raster_pairs_lit".into(), count(2));
        }
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
        shader::validate_wgsl("beams rasterize.wgsl", &rasterize_source(false))?;
        let culled = rasterize_source(true);
        if !culled.contains("@early_depth_test(force)") {
            return Err("the depth-culled rasterize.wgsl lacks its forced early depth test".into());
        }
        shader::validate_wgsl("beams rasterize.wgsl (depth-culled)", &culled)?;
        shader::validate_wgsl("beams rasterize_compute.wgsl", &rasterize_compute_source())?;
        shader::validate_wgsl("beams resolve.wgsl", &resolve_source())?;
        shader::validate_wgsl("beams orphans.wgsl", &orphans_source())?;
        shader::validate_wgsl("beams filter.wgsl", &filter_source())
    }

    #[test]
    fn the_vertex_cache_holds_the_finest_lattice_or_is_left_out() {
        let unlimited = u64::MAX;
        // adaptive-beams' defaults: 16² refined 3 times, 129² entries (2.1 MB).
        assert_eq!(vertex_cache_side(16, 3, 1, unlimited), 129);
        assert_eq!(
            vertex_cache_bytes(129, 1),
            (1 + 129 * 129) * VERTEX_PATH_BYTES
        );
        // With the Fresnel reflection, twice the entries.
        assert_eq!(vertex_cache_side(16, 3, 2, unlimited), 129);
        assert_eq!(
            vertex_cache_bytes(129, 2),
            (1 + 2 * 129 * 129) * VERTEX_PATH_BYTES
        );
        // static-grid's: 64², not refined.
        assert_eq!(vertex_cache_side(64, 0, 2, unlimited), 65);
        // 64² refined 3 times: 513² entries of 128 bytes (33.7 MB) fit 64 MiB, once...
        assert_eq!(vertex_cache_side(64, 3, 1, unlimited), 513);
        // ... not twice (67.4 MB), nor a 32 MiB binding, nor 256² refined 4 times
        // (4,097², 2.1 GB).
        assert_eq!(vertex_cache_side(64, 3, 2, unlimited), 0);
        assert_eq!(vertex_cache_side(64, 3, 1, 32 << 20), 0);
        assert_eq!(vertex_cache_side(256, MAX_LEVELS, 1, unlimited), 0);
    }

    #[test]
    fn the_compute_rasterizer_agrees_with_its_buffers() {
        let words = format!("const ACCUM_WORDS: u32 = {ACCUM_WORDS_PER_PIXEL}u;");
        assert!(RASTERIZE_COMPUTE_WGSL.contains(&words));
        assert!(RESOLVE_WGSL.contains(&words));
        assert!(RASTERIZE_COMPUTE_WGSL.contains(&format!(
            "raster_counts: array<atomic<u32>, {}>;",
            RASTER_COUNTS_BYTES / 4
        )));
        // The dispatch's three words end the indirect-arguments array.
        assert!(GENERATE_WGSL.contains(&format!(
            "indirect_args: array<u32, {}>;",
            INDIRECT_ARGS_BYTES / 4
        )));
        assert_eq!(RASTER_DISPATCH_ARGS_OFFSET / 4, 12);
        assert_eq!(LATTICE_DISPATCH_ARGS_OFFSET / 4, 16);
        assert_eq!(BEAM_DISPATCH_ARGS_OFFSET / 4, 20);
        assert_eq!(ORPHAN_DISPATCH_ARGS_OFFSET / 4, 23);
        assert!(
            GENERATE_WGSL
                .contains("indirect_args[20] = (atomicLoad(&control[C_BEAM_TOTAL]) + 63u) / 64u;")
        );
        assert!(GENERATE_WGSL.contains("indirect_args[16] = (n + 63u) / 64u;"));
        assert!(GENERATE_WGSL.contains("indirect_args[12] = min(beams, 32768u);"));
    }
}
