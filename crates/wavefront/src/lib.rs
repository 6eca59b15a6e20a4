//! `wavefront`: Wallace's WebGL caustics (2016) as a caustics-bench method.
//!
//! The light is a wavefront mesh: each vertex is a light ray, each triangle the bundle
//! of rays between its vertices. The rays are traced through the refractor to the
//! receivers (`trace.wgsl`; the rays' first hits on the generator once per wavefront,
//! then each sheet from there), triangles that stay on one path to one receiver are
//! kept and listed (`classify.wgsl`: an ordered compaction, counts, scan, scatter, not
//! an atomic append, so that the draw order and with it the additive blend are the
//! same every frame and the image is deterministic; the draws are indirect, so the
//! camera-side passes touch only what they draw), and the refracted mesh is drawn from
//! the camera with brightness = flux density ×
//! (area before)/(area after), the two areas taken from screen-space derivatives of
//! the old and new positions (`splat.wgsl`). Flux density is the light's irradiance
//! per unit area of the plane perpendicular to a directional light (or its intensity
//! per steradian for a point/spot light) times the Fresnel factor of each interface
//! and the reflectance of each mirror, so the result is absolute radiance ρ/π · E in
//! DESIGN units. For flat water it is exactly ρ/π · T(θ) · E · cos θ.
//!
//! One wavefront per light and specular object: its vertices start on the generator
//! (the water mesh itself for a heightfield, else a lattice of light rays over its
//! bounding sphere) and are traced through every specular surface they meet, a chain
//! of generators included (a glass sphere over water, two lenses): analytic shapes
//! exactly, meshes and heightfields through the scene's triangle BVH
//! (`caustics_gpu::triangle_bvh`) with interpolated normals and the adjoint
//! shading-normal factor the reference applies. A ray whose first surface is another
//! generator belongs to that one's wavefront. Receivers may be any diffuse object the
//! camera G-buffer shows; classify.wgsl keeps the triangles whose vertices took one
//! path to one receiver.
//!
//! By default a path passes each specular object once and is transmitted at every
//! dielectric interface, as Wallace's single refraction is: the light reflected at an
//! interface is ignored, and total internal reflection or a second hit on an object
//! already left ends a path. The complete light paths are further *sheets* of the
//! wavefront, each one fixed choice (transmit or reflect) per interface so that each is
//! one smooth wavefront, and together a partition of the light: `bounces` adds the
//! light reflected 1..=bounces times inside a closed refractor before it leaves (and
//! allows as many hits on an object already left, a mirror's opposite wall),
//! `reflections` the Fresnel reflection off each dielectric generator. A triangle whose
//! vertices part (one leaves the sheet, or they reach different receivers or paths) has
//! no area ratio and Wallace drops it; `splat_orphans` draws its landed vertices as
//! one-pixel points of a third of its flux each (`orphans.wgsl`; `orphan_kernel_px`
//! spreads each over a Gaussian of that many pixels instead), which a bumpy
//! refractor's speckle of total internal reflections needs. Like the original it
//! point-samples triangles thinner than a pixel (noisy cusps), and it renders no media.
//!
//! `raster=compute` (issue 17) replaces the raster splat by a compute pass of the same
//! name (`splat_compute.wgsl`): each kept triangle's invocation finds the pixels whose
//! centres it covers with edge functions (caustics-gpu's triangle_raster.wgsl), makes the
//! fragment shader's tests there and adds its radiance into a camera-sized fixed-point
//! accumulator with integer atomics (footprints over `raster_small_footprint` pixels
//! are walked by whole workgroups); a full-screen `resolve` adds the sums into the
//! surface caustic. The image is the same on every run, and within a stated bound of
//! the hardware path's (`tests/accuracy.rs`). The orphans' points stay rasterized.

mod sources;

use bytemuck::{Pod, Zeroable};
use caustics_gpu::limits::Reservation;
use caustics_gpu::pass::{
    BindGroupSchema, ComputePass, RasterPass, Shader, groups_2d, point_kernel_vertices,
};
use caustics_gpu::textures::{additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GpuContext, Renderer, shader};
use caustics_method::params::{Raster, above, closed};
use caustics_method::{
    Capabilities, CausticsMethod, CounterDoc, Counters, Method, MethodError, Unsupported,
    method_params,
};
use caustics_scene::{Material, Scene, Shape};

pub use sources::{Source, WavefrontMesh};

/// Types shared by the three passes (`Traced`, `TraceParams`).
const TYPES_WGSL: &str = include_str!("types.wgsl");
const TRACE_WGSL: &str = include_str!("trace.wgsl");
const CLASSIFY_WGSL: &str = include_str!("classify.wgsl");
const SPLAT_WGSL: &str = include_str!("splat.wgsl");
const ORPHANS_WGSL: &str = include_str!("orphans.wgsl");
const SPLAT_COMPUTE_WGSL: &str = include_str!("splat_compute.wgsl");
const RESOLVE_WGSL: &str = include_str!("resolve.wgsl");

/// Bytes of one source's `FirstHit` (trace.wgsl): five vec4<f32>.
const FIRST_HIT_BYTES: u64 = 80;

/// Triangles per chunk of classify.wgsl's ordered compaction (`CHUNK`, its workgroup).
const CLASSIFY_CHUNK: u64 = 64;

/// u32 words per pixel of the compute path's accumulator (`ACCUM_WORDS` in
/// splat_compute.wgsl and resolve.wgsl): r, g, b, each a 64-bit fixed-point number.
const ACCUM_WORDS_PER_PIXEL: u64 = 3 * shader::FIXED_POINT_WORDS;
/// Bytes of the compute path's counts (`raster_counts` in splat_compute.wgsl).
const RASTER_COUNTS_BYTES: u64 = 24;
/// Workgroups of `splat_large`: each takes every `LARGE_WORKGROUPS`-th listed
/// footprint; the ones with none left return at once.
const LARGE_WORKGROUPS: u32 = 256;
/// Group 1 of the splat and orphans passes (one sheet's drawing inputs).
const SHEET_DRAW_WGSL: &str = include_str!("sheet_draw.wgsl");

/// A pass's full WGSL: shared GPU files, wavefront's types, then the pass.
fn pass_source(pass: &str) -> String {
    shader::compose_method(&format!("{TYPES_WGSL}\n{pass}"))
}

/// A camera-side pass (splat, orphans): its bindings of one sheet, then the pass.
fn draw_source(pass: &str) -> String {
    pass_source(&format!("{SHEET_DRAW_WGSL}\n{pass}"))
}

/// The compute splat: the scan conversion and fixed-point functions before the pass.
fn splat_compute_source() -> String {
    draw_source(&format!(
        "{}\n{}\n{}\n{SPLAT_COMPUTE_WGSL}",
        shader::FIXED_POINT_WGSL,
        shader::RASTER_COUNTS_WGSL,
        shader::TRIANGLE_RASTER_WGSL
    ))
}

fn resolve_source() -> String {
    shader::compose_method(&format!("{}\n{RESOLVE_WGSL}", shader::FIXED_POINT_WGSL))
}

/// The trace pass also traces rays against the scene's triangle BVH (group 2).
fn trace_source() -> String {
    shader::compose_method(&format!(
        "{TYPES_WGSL}\n{}\n{TRACE_WGSL}",
        caustics_gpu::triangle_bvh::wgsl(2)
    ))
}

/// Registry name.
pub const NAME: &str = "wavefront";

method_params! {
    /// Parameters of `wavefront`.
    pub struct WavefrontParams {
        /// rays per side of the light-ray lattice over an analytic generator (heightfields
        /// use their vertex grid); 2 to 1024: a 1024² lattice is 1M rays and 2M triangles
        grid: u32 = 512 => closed(2.0, 1024.0);
        /// receiver match: max |G-buffer position - triangle point| / distance to eye
        /// (at most 0.5: a looser match accepts light on whatever surface is in front)
        tolerance: f64 = 2e-3 => above(0.0, 0.5);
        /// further specular events: sheets of light reflected 1..=bounces times inside a
        /// closed refractor before it leaves (Fresnel and total), and as many hits on
        /// an object a path has already left (a mirror's opposite wall) (0: Wallace's
        /// single pass; at most 8)
        bounces: u32 = 0 => closed(0.0, 8.0);
        /// also a sheet of the Fresnel reflection off each dielectric generator (Wallace: false)
        reflections: bool = false;
        /// also draw the light of the triangles classify drops (vertices that took
        /// different paths, receivers, or left the sheet) as one-pixel points at each
        /// landed vertex, a third of the triangle's flux each (Wallace: false, that light
        /// is lost)
        splat_orphans: bool = false;
        /// with splat_orphans: sigma (camera pixels) of a Gaussian each orphan point is spread over instead of one pixel (truncated at 2 sigma, normalised over the pixels it covers, so a flat receiver keeps its flux); 0 = one-pixel points (bound: a 33 x 33 pixel quad per point)
        orphan_kernel_px: f64 = 0.0 => closed(0.0, 8.0);
        /// how the kept triangles reach the image: hardware (drawn, additive blending: Wallace's) or compute (compute kernels find each triangle's covered pixels with edge functions and add them into a fixed-point accumulator with integer atomics, then resolved: the same image on every run)
        raster: Raster = Raster::Hardware;
        // At most 8192: under llvmpipe's 65,535 loop iterations per invocation.
        /// with raster = compute: a triangle's footprint (its bounding rectangle) of up to this many pixels is walked by the triangle's own invocation, a larger one by a workgroup of 64
        raster_small_footprint: u32 = 256 => closed(0.0, 8192.0);
    }
    check = orphan_kernel_needs_orphans;
}

/// The rule between parameters: a kernel for the orphans' points only where they are
/// drawn.
fn orphan_kernel_needs_orphans(p: &WavefrontParams) -> Result<(), String> {
    caustics_method::params::orphan_kernel_needs_orphans(p.orphan_kernel_px, p.splat_orphans)
}

impl Method for Wavefront {
    type Params = WavefrontParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str = "refracted or reflected wavefront mesh, brightness = area ratio from screen-space derivatives";
    const SOURCE: &'static str =
        "Wallace 2016, Rendering Realtime Caustics in WebGL (wallace-2016-webgl-caustics.txt)";
    const CAPABILITIES: Capabilities = Capabilities {
        surface: true,
        volume: false,
        reflection: true,
        refraction: true,
        multiple_bounces: true,
        directional_light: true,
        point_light: true,
        spot_light: true,
        sphere_light: false,
        environment_light: false,
        no_medium_in_paper: "Wallace's wavefront ends where its rays meet a surface (Wallace 2016: \u{201c}tracing a ray for that vertex along the sunlight direction, refracting it through the surface, and intersecting it with the ground geometry\u{201d}): no scattering or absorption on the way",
    };
    const COUNTERS: &'static [CounterDoc] = COUNTER_DOCS;

    fn check_scene(scene: &Scene, _params: &WavefrontParams) -> Result<(), Unsupported> {
        check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &WavefrontParams,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        Ok(Box::new(Wavefront::new(ctx, renderer, params)?))
    }
}

/// The caustic generators `wavefront` builds a wavefront for: every specular object
/// (each under each light is one sheet of the caustic), or why the scene is out of
/// reach.
pub fn caustic_generators(scene: &Scene) -> Result<Vec<usize>, Unsupported> {
    if scene.lights.is_empty() {
        return Err(Unsupported("the scene has no light".into()));
    }
    let generators: Vec<usize> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| scene.material(o).is_specular())
        .map(|(i, _)| i)
        .collect();
    if generators.is_empty() {
        return Err(Unsupported("the scene has no specular object".into()));
    }
    if scene.objects.len() == generators.len() {
        return Err(Unsupported("the scene has no diffuse receiver".into()));
    }
    Ok(generators)
}

fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    for g in caustic_generators(scene)? {
        let shape = &scene.objects[g].shape;
        if matches!(shape, Shape::Heightfield(_)) {
            continue;
        }
        let (center, radius) = sources::bounding_sphere(shape);
        for (l, light) in scene.lights.iter().enumerate() {
            if sources::ray_lattice(center, radius, light, 2).is_none() {
                return Err(Unsupported(format!(
                    "lights[{l}] is inside the bounding sphere of the generator objects[{g}], which wavefront's ray lattice must see from outside"
                )));
            }
        }
    }
    Ok(())
}

/// Matches `TraceParams` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TraceParams {
    specular_object: u32,
    light_index: u32,
    source_count: u32,
    triangle_count: u32,
    bounces: u32,
    reflect_mask: u32,
    _pad: [u32; 2],
}

/// Matches `SplatParams` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatParams {
    tolerance: f32,
    _pad: [f32; 3],
}

/// Names of the kept and dropped triangle counts and the orphan corners, in the order
/// of `Counters` in classify.wgsl.
const TRIANGLE_COUNTERS: [&str; 5] = [
    "kept_triangles",
    "dropped_invalid_vertex",
    "dropped_receiver_mismatch",
    "dropped_path_mismatch",
    "orphan_corners",
];

/// Names of the vertex outcomes, in the order of `VertexCounts` in trace.wgsl (the
/// `INVALID_*` codes, then the landed vertices whose path used a further bounce).
const VERTEX_COUNTERS: [&str; 10] = [
    "vertices_landed",
    "vertices_missed_generator",
    "vertices_shadowed",
    "vertices_total_internal_reflection",
    "vertices_no_receiver",
    "vertices_rehit",
    "vertices_wrong_side",
    "vertices_too_many_events",
    "vertices_other_sheet",
    "vertices_landed_after_rehit",
];

/// What each counter of `wavefront` counts ([`Method::COUNTERS`]): in the last frame,
/// summed over the sheets. Each traced vertex has one outcome (`vertices_landed` or one
/// of the drops), so those add up to `source_vertices`; `kept_triangles` and the
/// `dropped_*` counters add up to `triangles`.
#[rustfmt::skip]
const COUNTER_DOCS: &[CounterDoc] = &[
    CounterDoc { name: "sheets", doc: "wavefronts traced per frame: one per light, specular object and specular path (transmitted; with bounces, 1..=bounces internal reflections in a closed refractor; with reflections, the Fresnel reflection off a dielectric)" },
    CounterDoc { name: "source_vertices", doc: "wavefront vertices (light rays) traced by the trace_vertices pass, summed over the sheets: a grid x grid lattice over each analytic generator's bounding sphere, a heightfield's own vertex grid" },
    CounterDoc { name: "triangles", doc: "wavefront triangles judged by the classify_triangles pass, summed over the sheets" },
    CounterDoc { name: "bvh_triangles", doc: "triangles in the scene's triangle BVH (meshes and tessellated heightfields; analytic shapes are traced exactly) that the rays are traced against: a property of the scene, not a per-frame count" },
    CounterDoc { name: "kept_triangles", doc: "triangles whose three vertices landed on the same side of the same receiver by the same specular path: drawn by the splat pass with brightness from the area ratio before/after" },
    CounterDoc { name: "dropped_invalid_vertex", doc: "triangles dropped because at least one of their vertices did not land (any vertices_* drop)" },
    CounterDoc { name: "dropped_receiver_mismatch", doc: "triangles dropped because their vertices landed on different receivers, or on different sides of one" },
    CounterDoc { name: "dropped_path_mismatch", doc: "triangles dropped because their vertices took different specular paths (the objects met and the side each was met from, in order)" },
    CounterDoc { name: "orphan_corners", doc: "with splat_orphans: landed vertices of dropped triangles, once per dropped triangle they are a corner of, each drawn as a one-pixel point (or orphan_kernel_px's Gaussian) of a third of its triangle's flux (without splat_orphans that light is lost)" },
    CounterDoc { name: "raster_pixels_covered", doc: "with raster = compute: (triangle, pixel) pairs whose pixel centre a kept triangle covers, each then tested as a fragment (the hardware path's splat fragments)" },
    CounterDoc { name: "raster_large_footprints", doc: "with raster = compute: kept triangles whose footprint exceeds raster_small_footprint pixels, walked by a workgroup of 64 invocations instead of the triangle's own" },
    CounterDoc { name: "raster_footprints_walked_by_lane", doc: "with raster = compute: large footprints the list had no room for, walked by the triangle's own invocation (same light, slower)" },
    CounterDoc { name: "dropped_face_mismatch", doc: "older results only (now dropped_path_mismatch): triangles dropped because their vertices met different sides of the generator (a ring's outer and inner walls)" },
    CounterDoc { name: "vertices_landed", doc: "vertices whose ray reached a diffuse receiver along its sheet's path" },
    CounterDoc { name: "vertices_landed_after_rehit", doc: "those of vertices_landed whose path met an object it had already left again on the way (a mirror ring's opposite wall; only with bounces > 0)" },
    CounterDoc { name: "vertices_missed_generator", doc: "lattice rays whose first surface is not this wavefront's generator: they miss it, or meet another object first (another generator's wavefront, or direct light)" },
    CounterDoc { name: "vertices_shadowed", doc: "vertices whose light is blocked before the generator: anything behind a directional light's lattice plane, or between the light and a heightfield vertex" },
    CounterDoc { name: "vertices_total_internal_reflection", doc: "vertices whose path ends at a total internal reflection at an interface where their sheet transmits (Wallace's single refraction, the default path)" },
    CounterDoc { name: "vertices_no_receiver", doc: "vertices whose ray, after a specular event, meets no surface (it leaves the scene)" },
    CounterDoc { name: "vertices_rehit", doc: "vertices whose ray meets an object it has already left (a mirror ring's opposite wall) with no bounces left: the path ends" },
    CounterDoc { name: "vertices_wrong_side", doc: "vertices dropped where a mesh's shading and geometric normals disagree about the side the light arrives or leaves on (interpolated normals)" },
    CounterDoc { name: "vertices_too_many_events", doc: "vertices still meeting specular surfaces after 16 specular events: dropped" },
    CounterDoc { name: "vertices_other_sheet", doc: "vertices that reached a diffuse receiver before taking every reflection their sheet asks for (their light is another sheet's): dropped, so the sheets partition the light" },
];

/// The sheets of one generator: the `reflect_mask` of each (trace.wgsl). Light
/// transmitted at every interface first; then, for a closed refractor, the light that
/// reflects 1..=`bounces` times inside before leaving; then the Fresnel reflection off
/// a dielectric's outside.
fn sheet_masks(shape: &Shape, material: &Material, params: &WavefrontParams) -> Vec<u32> {
    let mut masks = vec![0];
    if !matches!(material, Material::Dielectric { .. }) {
        return masks;
    }
    if matches!(shape, Shape::Sphere { .. } | Shape::Mesh(_)) {
        // Bits 1..=j: reflect at the first j exits.
        masks.extend((1..=params.bounces).map(|j| ((1u32 << (j + 1)) - 1) & !1));
    }
    if params.reflections {
        masks.push(1);
    }
    masks
}

/// One wavefront: a generator under a light, its buffers and bind groups.
struct Sheet {
    source_count: u32,
    triangle_count: u32,
    trace_group: wgpu::BindGroup,
    classify_group: wgpu::BindGroup,
    splat_group: wgpu::BindGroup,
    /// With `splat_orphans`: the orphans pass's group 1 (splat.wgsl's bindings).
    orphan_group: Option<wgpu::BindGroup>,
    /// The splat's and the orphans' indirect draws, written by classify.wgsl.
    draw_args: wgpu::Buffer,
    /// The first sheet of its wavefront: its trace group finds the first hits the
    /// wavefront's other sheets start from.
    first_sheet: bool,
    bytes: u64,
}

/// How the kept triangles reach the surface caustic.
enum SplatDraw {
    /// Drawn with additive blending (Wallace's).
    Hardware(RasterPass),
    /// Added into a fixed-point accumulator by compute kernels, then resolved (boxed:
    /// its passes and buffers are the bigger variant, made once per scene).
    Compute(Box<ComputeSplat>),
}

/// The compute path's passes and buffers.
struct ComputeSplat {
    /// Kernels `splat`, `splat_large`, `next_sheet`; group 1 is each sheet's, group 2
    /// the accumulator, the list and the counts.
    pass: ComputePass,
    /// The full-screen pass adding the accumulator into the surface caustic.
    resolve: RasterPass,
    /// `raster_counts`: cleared each frame, read by `counters`.
    raster_counts: wgpu::Buffer,
    _accumulator: wgpu::Buffer,
    _large: wgpu::Buffer,
    _memory: Reservation,
}

impl ComputeSplat {
    fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &WavefrontParams,
    ) -> Result<(Self, u64), MethodError> {
        let camera = &renderer.scene().scene.camera;
        let pixels = u64::from(camera.width) * u64::from(camera.height);
        let accumulator_bytes = pixels * ACCUM_WORDS_PER_PIXEL * 4;
        // Room for a large footprint per 64 pixels; past it the triangle's own
        // invocation walks the footprint (same sums, `raster_footprints_walked_by_lane`).
        let large_bytes = pixels.div_ceil(64).max(1024) * 4;
        let what = format!(
            "raster=compute: the fixed-point accumulator and the list of large footprints ({pixels} pixels x {} bytes + {large_bytes} bytes)",
            ACCUM_WORDS_PER_PIXEL * 4
        );
        let lower = "render fewer pixels or use raster=hardware";
        let param = |e: caustics_gpu::GpuError| MethodError::Param {
            method: NAME,
            message: e.to_string(),
        };
        ctx.limits
            .storage(&what, accumulator_bytes, lower)
            .map_err(param)?;
        let memory = ctx
            .memory
            .reserve(&what, accumulator_bytes + large_bytes, lower)
            .map_err(param)?;
        let device = &ctx.device;
        let (accumulator, large, raster_counts) = ctx.checked("wavefront compute splat", || {
            let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE | usage,
                    mapped_at_creation: false,
                })
            };
            (
                // Zero at creation; each resolve zeroes what it read.
                buffer(
                    "wavefront compute accumulator",
                    accumulator_bytes,
                    wgpu::BufferUsages::empty(),
                ),
                buffer(
                    "wavefront large footprints",
                    large_bytes,
                    wgpu::BufferUsages::empty(),
                ),
                buffer(
                    "wavefront raster counts",
                    RASTER_COUNTS_BYTES,
                    wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                ),
            )
        })?;
        let shader = Shader::new(ctx, "wavefront splat_compute.wgsl", splat_compute_source())?;
        let pass = ComputePass::builder(ctx, "wavefront/splat", &shader)
            .frame(renderer)
            .caller_group(1)
            .bind(
                2,
                &[
                    ("accum", &accumulator),
                    ("large", &large),
                    ("raster_counts", &raster_counts),
                ],
            )
            .kernels(&["splat", "splat_large", "next_sheet"])
            .constants(&[("small_pixels", f64::from(params.raster_small_footprint))])
            .build()?;
        let shader = Shader::new(ctx, "wavefront resolve.wgsl", resolve_source())?;
        let resolve = RasterPass::fullscreen(
            ctx,
            "wavefront/resolve",
            &shader,
            "fs_resolve",
            &[Some(additive_hdr_target())],
        )
        .frame(renderer)
        .bind(1, &[("accum", &accumulator)])
        .build()?;
        let bytes = accumulator.size() + large.size() + raster_counts.size();
        Ok((
            Self {
                pass,
                resolve,
                raster_counts,
                _accumulator: accumulator,
                _large: large,
                _memory: memory,
            },
            bytes,
        ))
    }

    /// Every sheet's kept triangles into the accumulator, then into the surface caustic.
    fn record(&self, frame: &mut Frame<'_>, sheets: &[Sheet]) -> Result<(), MethodError> {
        frame.encoder.clear_buffer(&self.raster_counts, 0, None);
        {
            let mut pass = self.pass.begin(frame)?;
            for sheet in sheets {
                pass.set_bind_group(1, &sheet.splat_group, &[]);
                pass.dispatch(
                    "splat",
                    groups_2d(u64::from(sheet.triangle_count).div_ceil(64)),
                )?;
                pass.dispatch("splat_large", [LARGE_WORKGROUPS, 1, 1])?;
                pass.dispatch("next_sheet", [1, 1, 1])?;
            }
        }
        let renderer = frame.renderer;
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        self.resolve
            .begin(frame, &attachments, None)?
            .draw_fullscreen();
        Ok(())
    }

    /// `raster_pixels_covered`, `raster_large_footprints`,
    /// `raster_footprints_walked_by_lane`.
    fn counters(&self, ctx: &GpuContext, out: &mut Counters) -> Result<(), MethodError> {
        let w = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.raster_counts,
            RASTER_COUNTS_BYTES,
            "wavefront raster counts",
        )?;
        out.insert(
            "raster_pixels_covered".into(),
            u64::from(w[4]) | (u64::from(w[5]) << 32),
        );
        out.insert("raster_large_footprints".into(), u64::from(w[1]));
        out.insert("raster_footprints_walked_by_lane".into(), u64::from(w[2]));
        Ok(())
    }
}

/// `wavefront` bound to one scene.
pub struct Wavefront {
    trace: ComputePass,
    classify: ComputePass,
    /// The kept triangles into the surface caustic, on the hardware or compute path.
    splat: SplatDraw,
    /// With `splat_orphans`: the landed vertices of dropped triangles, as points.
    orphans: Option<RasterPass>,
    sheets: Vec<Sheet>,
    /// `TRIANGLE_COUNTERS` and `VERTEX_COUNTERS`, summed over the sheets.
    triangle_counts: wgpu::Buffer,
    vertex_counts: wgpu::Buffer,
    /// Zeros, copied over both counter buffers at the start of every frame.
    counters_init: wgpu::Buffer,
    bvh_triangles: u32,
    bytes: u64,
    /// The lattices' and sheets' bytes in the device's memory ledger.
    _memory: Vec<Reservation>,
}

impl Wavefront {
    /// Builds one wavefront per (light, specular object) and Wallace's three passes:
    /// trace the rays, flag the triangles that stay on one path to one receiver, draw
    /// them with the area ratio as brightness.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &WavefrontParams,
    ) -> Result<Self, MethodError> {
        let gpu_scene = renderer.scene();
        let scene = &gpu_scene.scene;
        let unsupported = |reason| MethodError::Unsupported {
            method: NAME,
            scene: scene.name.clone(),
            reason,
        };
        check_scene(scene).map_err(unsupported)?;
        let generators = caustic_generators(scene).map_err(unsupported)?;
        let bvh = gpu_scene.triangle_bvh(ctx)?;
        let device = &ctx.device;

        let shader = Shader::new(ctx, "wavefront trace.wgsl", trace_source())?;
        let trace = ComputePass::builder(ctx, "wavefront/trace_vertices", &shader)
            .frame(renderer)
            .caller_group(1)
            .bind(
                2,
                &[("bvh_nodes", &bvh.nodes), ("bvh_triangles", &bvh.triangles)],
            )
            .kernels(&["find_first_hits", "trace_vertices"])
            .build()?;
        let shader = Shader::new(ctx, "wavefront classify.wgsl", pass_source(CLASSIFY_WGSL))?;
        let classify = ComputePass::builder(ctx, "wavefront/classify_triangles", &shader)
            .frame(renderer)
            .caller_group(1)
            .kernels(&["classify_triangles", "scan_chunks", "scatter_chunks"])
            .constants(&[
                ("SPLAT_ORPHANS", f64::from(u8::from(params.splat_orphans))),
                (
                    "ORPHAN_VERTICES",
                    f64::from(point_kernel_vertices(params.orphan_kernel_px)),
                ),
            ])
            .build()?;
        let (splat, compute_bytes) = match params.raster {
            Raster::Hardware => {
                // Folded triangles face away: both windings count (the builder culls
                // nothing).
                let shader = Shader::new(ctx, "wavefront splat.wgsl", draw_source(SPLAT_WGSL))?;
                let pass = RasterPass::builder(ctx, "wavefront/splat", &shader, "vs_splat")
                    .frame(renderer)
                    .caller_group(1)
                    .fragment("fs_splat", &[Some(additive_hdr_target())])
                    .counted()
                    .build()?;
                (SplatDraw::Hardware(pass), 0)
            }
            Raster::Compute => {
                let (compute, bytes) = ComputeSplat::new(ctx, renderer, params)?;
                (SplatDraw::Compute(Box::new(compute)), bytes)
            }
        };
        let orphans = if params.splat_orphans {
            let shader = Shader::new(ctx, "wavefront orphans.wgsl", draw_source(ORPHANS_WGSL))?;
            Some(
                RasterPass::builder(ctx, "wavefront/orphan_points", &shader, "vs_orphan")
                    .frame(renderer)
                    .caller_group(1)
                    .fragment("fs_orphan", &[Some(additive_hdr_target())])
                    .counted()
                    .constants(&[("ORPHAN_SIGMA_PX", params.orphan_kernel_px)])
                    .points_or_kernel_quads(params.orphan_kernel_px)
                    .build()?,
            )
        } else {
            None
        };
        let (trace_schema, classify_schema, splat_schema) = (
            trace.caller_schema(1)?,
            classify.caller_schema(1)?,
            match &splat {
                SplatDraw::Hardware(pass) => pass.caller_schema(1)?,
                SplatDraw::Compute(compute) => compute.pass.caller_schema(1)?,
            },
        );
        let orphan_schema = match &orphans {
            Some(pass) => Some(pass.caller_schema(1)?),
            None => None,
        };

        let zeros = [0u32; TRIANGLE_COUNTERS.len() + VERTEX_COUNTERS.len()];
        let (triangle_counts, vertex_counts, counters_init) =
            ctx.checked("wavefront counters", || {
                let init = |label: &str, words: usize, usage| {
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: bytemuck::cast_slice(&zeros[..words]),
                        usage,
                    })
                };
                let counted = wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC;
                (
                    init(
                        "wavefront triangle counts",
                        TRIANGLE_COUNTERS.len(),
                        counted,
                    ),
                    init("wavefront vertex counts", VERTEX_COUNTERS.len(), counted),
                    init(
                        "wavefront counters reset",
                        zeros.len(),
                        wgpu::BufferUsages::COPY_SRC,
                    ),
                )
            })?;

        let splat_params = SplatParams {
            tolerance: params.tolerance as f32,
            _pad: [0.0; 3],
        };
        let mut sheets = Vec::new();
        let mut lattice_bytes = 0;
        let mut memory = Vec::new();
        for (light_index, light) in scene.lights.iter().enumerate() {
            for &generator in &generators {
                let object = &scene.objects[generator];
                let masks = sheet_masks(&object.shape, scene.material(object), params);
                let mesh = sources::for_shape(
                    &scene.objects[generator].shape,
                    &gpu_scene.meshes[generator],
                    light,
                    params.grid,
                )
                .ok_or_else(|| {
                    unsupported(Unsupported(format!(
                        "cannot build a wavefront for objects[{generator}] under lights[{light_index}]"
                    )))
                })?;
                // Before the lattice is uploaded: each sheet traces every source into
                // a 64-byte record; the device must bind that and the budget hold it.
                let (source_count, triangle_count) =
                    (mesh.sources.len() as u64, (mesh.triangles.len() / 3) as u64);
                let lattice_bytes_needed = std::mem::size_of_val(mesh.sources.as_slice()) as u64
                    + std::mem::size_of_val(mesh.triangles.as_slice()) as u64;
                let raise = "lower grid (or, on a heightfield, its resolution: its vertex grid is the lattice)";
                let what = format!(
                    "the wavefront of objects[{generator}] ({source_count} rays, {triangle_count} triangles, {} sheet(s))",
                    masks.len()
                );
                let limit = |e: caustics_gpu::GpuError| MethodError::Param {
                    method: NAME,
                    message: format!("grid: {e}"),
                };
                ctx.limits
                    .storage(&what, source_count * FIRST_HIT_BYTES.max(64), raise)
                    .map_err(limit)?;
                // Held (summed with every live resource) while the wavefront lives.
                memory.push(
                    ctx.memory
                        .reserve(
                            &what,
                            lattice_bytes_needed
                                + source_count * FIRST_HIT_BYTES
                                + masks.len() as u64
                                    * Sheet::bytes_needed(
                                        source_count,
                                        triangle_count,
                                        params.splat_orphans,
                                    ),
                            raise,
                        )
                        .map_err(limit)?,
                );
                // One upload of the lattice per (light, generator); its sheets share it,
                // and the rays' first hits (trace.wgsl `find_first_hits`).
                let (sources, triangles, first_hits) = ctx.checked("wavefront lattice", || {
                    let init = |label: &str, contents: &[u8]| {
                        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some(label),
                            contents,
                            usage: wgpu::BufferUsages::STORAGE,
                        })
                    };
                    (
                        init("wavefront sources", bytemuck::cast_slice(&mesh.sources)),
                        init("wavefront triangles", bytemuck::cast_slice(&mesh.triangles)),
                        device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("wavefront first hits"),
                            size: (source_count * FIRST_HIT_BYTES).max(FIRST_HIT_BYTES),
                            usage: wgpu::BufferUsages::STORAGE,
                            mapped_at_creation: false,
                        }),
                    )
                })?;
                lattice_bytes += sources.size() + triangles.size() + first_hits.size();
                for (sheet_index, reflect_mask) in masks.into_iter().enumerate() {
                    let trace_params = TraceParams {
                        specular_object: generator as u32,
                        light_index: light_index as u32,
                        source_count: mesh.sources.len() as u32,
                        triangle_count: (mesh.triangles.len() / 3) as u32,
                        bounces: params.bounces,
                        reflect_mask,
                        _pad: [0; 2],
                    };
                    sheets.push(ctx.checked("wavefront sheet", || {
                        Sheet::new(
                            device,
                            Lattice {
                                sources: &sources,
                                triangles: &triangles,
                                first_hits: &first_hits,
                                first_sheet: sheet_index == 0,
                            },
                            &trace_params,
                            &splat_params,
                            SheetGroups {
                                trace: trace_schema,
                                classify: classify_schema,
                                splat: splat_schema,
                                orphans: orphan_schema,
                                triangle_counts: &triangle_counts,
                                vertex_counts: &vertex_counts,
                            },
                        )
                    })??);
                }
            }
        }
        let bytes = sheets.iter().map(|s| s.bytes).sum::<u64>()
            + lattice_bytes
            + triangle_counts.size()
            + vertex_counts.size()
            + counters_init.size()
            + bvh.bytes
            + compute_bytes;
        Ok(Self {
            trace,
            classify,
            splat,
            orphans,
            sheets,
            triangle_counts,
            vertex_counts,
            counters_init,
            bvh_triangles: bvh.triangle_count,
            bytes,
            _memory: memory,
        })
    }
}

/// The per-sheet bind groups' layouts and the counters every sheet adds to.
struct SheetGroups<'a> {
    trace: &'a BindGroupSchema,
    classify: &'a BindGroupSchema,
    splat: &'a BindGroupSchema,
    orphans: Option<&'a BindGroupSchema>,
    triangle_counts: &'a wgpu::Buffer,
    vertex_counts: &'a wgpu::Buffer,
}

/// A wavefront's vertices and triangles on the GPU, shared by its sheets.
struct Lattice<'a> {
    sources: &'a wgpu::Buffer,
    triangles: &'a wgpu::Buffer,
    /// Where each source's ray meets the generator, found once for all sheets.
    first_hits: &'a wgpu::Buffer,
    /// Whether this is the wavefront's first sheet (the one that finds the first hits).
    first_sheet: bool,
}

/// Byte offsets of the two draws' arguments in a sheet's `draw_args` (classify.wgsl).
const SPLAT_DRAW_ARGS_OFFSET: u64 = 0;
const ORPHAN_DRAW_ARGS_OFFSET: u64 = 16;

impl Sheet {
    /// Device bytes of one sheet's own buffers (`new`), params aside: a `Traced` (64
    /// bytes) per source; per triangle a verdict and its draw-list entries (3 with
    /// `splat_orphans`: kept triangles plus orphan corners never exceed three per
    /// triangle); per chunk of 64 triangles its two counts; two draws' arguments.
    fn bytes_needed(source_count: u64, triangle_count: u64, splat_orphans: bool) -> u64 {
        let list_words = if splat_orphans { 3 } else { 1 };
        source_count * 64
            + triangle_count.max(1) * 4 * (1 + list_words)
            + triangle_count.div_ceil(CLASSIFY_CHUNK).max(1) * 8
            + 32
    }

    fn new(
        device: &wgpu::Device,
        lattice: Lattice<'_>,
        trace: &TraceParams,
        splat: &SplatParams,
        groups: SheetGroups<'_>,
    ) -> Result<Self, caustics_gpu::GpuError> {
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let storage = |label: &str, size: u64| buffer(label, size, wgpu::BufferUsages::empty());
        let uniform = wgpu::BufferUsages::UNIFORM;
        let trace_params = init("wavefront trace params", bytemuck::bytes_of(trace), uniform);
        let splat_params = init("wavefront splat params", bytemuck::bytes_of(splat), uniform);
        let Lattice {
            sources,
            triangles,
            first_hits,
            first_sheet,
        } = lattice;
        // One `Traced` (64 bytes) per source, one flag per triangle.
        let traced = storage("wavefront traced vertices", trace.source_count as u64 * 64);
        let triangle_count = u64::from(trace.triangle_count);
        let keep = storage("wavefront keep flags", triangle_count.max(1) * 4);
        // classify.wgsl's ordered compaction: counts then offsets per chunk, the list.
        let chunks = storage(
            "wavefront chunk offsets",
            triangle_count.div_ceil(CLASSIFY_CHUNK).max(1) * 8,
        );
        let list_words = if groups.orphans.is_some() { 3 } else { 1 };
        let draw_list = storage(
            "wavefront draw list",
            triangle_count.max(1) * 4 * list_words,
        );
        let draw_args = buffer("wavefront draw args", 32, wgpu::BufferUsages::INDIRECT);
        let trace_group = groups.trace.bind(
            device,
            &[
                ("tp", &trace_params),
                ("sources", sources),
                ("traced", &traced),
                ("vertex_counts", groups.vertex_counts),
                ("first_hits", first_hits),
            ],
        )?;
        let classify_group = groups.classify.bind(
            device,
            &[
                ("tp", &trace_params),
                ("traced", &traced),
                ("triangles", triangles),
                ("keep", &keep),
                ("counters", groups.triangle_counts),
                ("chunks", &chunks),
                ("draw_list", &draw_list),
                ("draw_args", &draw_args),
            ],
        )?;
        // The camera-side passes declare these in sheet_draw.wgsl.
        let draw_entries: [(&str, &dyn caustics_gpu::pass::Bindable); 5] = [
            ("sp", &splat_params),
            ("traced", &traced),
            ("triangles", triangles),
            ("keep", &keep),
            ("draw_list", &draw_list),
        ];
        let splat_group = groups.splat.bind(device, &draw_entries)?;
        let orphan_group = match groups.orphans {
            Some(schema) => Some(schema.bind(device, &draw_entries)?),
            None => None,
        };
        let bytes = [
            &trace_params,
            &splat_params,
            &traced,
            &keep,
            &chunks,
            &draw_list,
            &draw_args,
        ]
        .iter()
        .map(|b| b.size())
        .sum();
        Ok(Self {
            source_count: trace.source_count,
            triangle_count: trace.triangle_count,
            trace_group,
            classify_group,
            splat_group,
            orphan_group,
            draw_args,
            first_sheet,
            bytes,
        })
    }
}

impl Wavefront {
    /// Traces every sheet's vertices and classifies its triangles (camera-independent).
    fn record_light_side(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let triangle_bytes = self.triangle_counts.size();
        frame.encoder.copy_buffer_to_buffer(
            &self.counters_init,
            0,
            &self.triangle_counts,
            0,
            triangle_bytes,
        );
        frame.encoder.copy_buffer_to_buffer(
            &self.counters_init,
            0,
            &self.vertex_counts,
            0,
            self.vertex_counts.size(),
        );
        {
            let mut pass = self.trace.begin(frame)?;
            for sheet in &self.sheets {
                pass.set_bind_group(1, &sheet.trace_group, &[]);
                let groups = [sheet.source_count.div_ceil(64), 1, 1];
                if sheet.first_sheet {
                    pass.dispatch("find_first_hits", groups)?;
                }
                pass.dispatch("trace_vertices", groups)?;
            }
        }
        {
            let mut pass = self.classify.begin(frame)?;
            for sheet in &self.sheets {
                pass.set_bind_group(1, &sheet.classify_group, &[]);
                let chunks = sheet.triangle_count.div_ceil(CLASSIFY_CHUNK as u32);
                // One workgroup per chunk (its index is the chunk's).
                pass.dispatch("classify_triangles", [chunks, 1, 1])?;
                pass.dispatch("scan_chunks", [1, 1, 1])?;
                pass.dispatch("scatter_chunks", [chunks.div_ceil(64), 1, 1])?;
            }
        }
        Ok(())
    }
}

impl CausticsMethod for Wavefront {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        // Light side: the sheets' vertices and their triangles' verdicts do not depend on
        // the camera; a reused scoring sub-frame keeps them (and their counters).
        if !frame.reuses_light_side() {
            self.record_light_side(frame)?;
        }

        let attachments = [load_attachment(&renderer.targets().surface.view)];
        match &self.splat {
            SplatDraw::Hardware(splat) => {
                let mut pass = splat.begin(frame, &attachments, None)?;
                for sheet in &self.sheets {
                    pass.set_bind_group(1, &sheet.splat_group, &[]);
                    pass.draw_indirect(&sheet.draw_args, SPLAT_DRAW_ARGS_OFFSET);
                }
            }
            SplatDraw::Compute(compute) => compute.record(frame, &self.sheets)?,
        }
        if let Some(orphans) = &self.orphans {
            let mut pass = orphans.begin(frame, &attachments, None)?;
            for sheet in &self.sheets {
                if let Some(group) = &sheet.orphan_group {
                    pass.set_bind_group(1, group, &[]);
                    // One point (or kernel quad) per landed corner of a dropped triangle.
                    pass.draw_indirect(&sheet.draw_args, ORPHAN_DRAW_ARGS_OFFSET);
                }
            }
        }
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let read = |buffer: &wgpu::Buffer, what| {
            caustics_gpu::readback::read_buffer_u32(ctx, buffer, buffer.size(), what)
        };
        let triangles = read(&self.triangle_counts, "wavefront triangle counts")?;
        let vertices = read(&self.vertex_counts, "wavefront vertex counts")?;
        let mut out = Counters::new();
        out.insert("sheets".into(), self.sheets.len() as u64);
        out.insert(
            "source_vertices".into(),
            self.sheets.iter().map(|s| s.source_count as u64).sum(),
        );
        out.insert(
            "triangles".into(),
            self.sheets.iter().map(|s| s.triangle_count as u64).sum(),
        );
        out.insert("bvh_triangles".into(), self.bvh_triangles as u64);
        for (name, value) in TRIANGLE_COUNTERS.iter().zip(&triangles) {
            // The orphans' count only where they are drawn: the default's counters are
            // Wallace's (and the regression baselines').
            if *name == "orphan_corners" && self.orphans.is_none() {
                continue;
            }
            out.insert((*name).into(), *value as u64);
        }
        for (name, value) in VERTEX_COUNTERS.iter().zip(&vertices) {
            out.insert((*name).into(), *value as u64);
        }
        // The compute splat's work only where it runs (the hardware path's is its splat
        // pass's fragments).
        if let SplatDraw::Compute(compute) = &self.splat {
            compute.counters(ctx, &mut out)?;
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
    use caustics_method::params::parse;

    #[test]
    fn shaders_validate() -> Result<(), String> {
        shader::validate_wgsl("trace.wgsl", &trace_source())?;
        shader::validate_wgsl("classify.wgsl", &pass_source(CLASSIFY_WGSL))?;
        shader::validate_wgsl("splat.wgsl", &draw_source(SPLAT_WGSL))?;
        shader::validate_wgsl("orphans.wgsl", &draw_source(ORPHANS_WGSL))?;
        shader::validate_wgsl("splat_compute.wgsl", &splat_compute_source())?;
        shader::validate_wgsl("resolve.wgsl", &resolve_source())
    }

    #[test]
    fn the_first_hit_record_matches_the_wgsl() {
        let (_, size) = caustics_gpu::layout::wgsl_struct_layout(&trace_source(), "FirstHit")
            .expect("trace.wgsl declares FirstHit");
        assert_eq!(u64::from(size), FIRST_HIT_BYTES);
    }

    #[test]
    fn the_classify_chunk_matches_the_wgsl() {
        assert_eq!(
            caustics_gpu::layout::wgsl_u32_constant(&pass_source(CLASSIFY_WGSL), "CHUNK").ok(),
            Some(CLASSIFY_CHUNK as u32)
        );
    }

    #[test]
    fn accumulator_words_match_the_wgsl() {
        for source in [splat_compute_source(), resolve_source()] {
            assert_eq!(
                caustics_gpu::layout::wgsl_u32_constant(&source, "ACCUM_WORDS").ok(),
                Some(ACCUM_WORDS_PER_PIXEL as u32)
            );
        }
    }

    /// Every counter `Wavefront::counters` reports has a doc.
    #[test]
    fn every_counter_is_documented() {
        let names: Vec<&str> = [
            "sheets",
            "source_vertices",
            "triangles",
            "bvh_triangles",
            "raster_pixels_covered",
            "raster_large_footprints",
            "raster_footprints_walked_by_lane",
        ]
        .into_iter()
        .chain(TRIANGLE_COUNTERS)
        .chain(VERTEX_COUNTERS)
        .collect();
        // `dropped_face_mismatch` is documented for older result files only.
        let current: Vec<_> = COUNTER_DOCS
            .iter()
            .copied()
            .filter(|d| d.name != "dropped_face_mismatch")
            .collect();
        if let Err(e) = caustics_method::CounterDoc::check(&current, &names) {
            panic!("{e}");
        }
    }

    #[test]
    fn gpu_structs_match_their_wgsl() {
        caustics_gpu::assert_wgsl_layout!(
            trace_source(),
            Source {
                origin,
                dir_or_normal
            }
        );
        caustics_gpu::assert_wgsl_layout!(
            trace_source(),
            TraceParams {
                specular_object,
                light_index,
                source_count,
                triangle_count,
                bounces,
                reflect_mask
            }
        );
        caustics_gpu::assert_wgsl_layout!(draw_source(SPLAT_WGSL), SplatParams { tolerance });
    }

    /// The sheets of a generator: transmitted light first, then j internal reflections
    /// (bits 1..=j of the interfaces a path meets), then the outside reflection (bit
    /// 0); mirrors have no interface to choose at, open refractors no inside to
    /// reflect in.
    #[test]
    fn sheet_masks_follow_bounces_and_reflections() {
        let params = |bounces, reflections| WavefrontParams {
            bounces,
            reflections,
            ..WavefrontParams::default()
        };
        let glass = Material::Dielectric { ior: 1.5 };
        let sphere = Shape::Sphere {
            center: caustics_scene::Vec3::ZERO,
            radius: 1.0,
        };
        let quad = Shape::Quad {
            center: caustics_scene::Vec3::ZERO,
            normal: caustics_scene::Vec3::Y,
            size: caustics_scene::Vec2::ONE,
        };
        assert_eq!(sheet_masks(&sphere, &glass, &params(0, false)), [0]);
        assert_eq!(
            sheet_masks(&sphere, &glass, &params(3, true)),
            [0, 0b10, 0b110, 0b1110, 0b1]
        );
        assert_eq!(sheet_masks(&quad, &glass, &params(3, true)), [0, 0b1]);
        let mirror = Material::Mirror {
            reflectance: caustics_scene::Vec3::ONE,
        };
        assert_eq!(sheet_masks(&sphere, &mirror, &params(3, true)), [0]);
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"grid": 1}), "grid"),
            (serde_json::json!({"grid": 5000}), "grid"),
            (serde_json::json!({"grid": 2.5}), "grid"),
            (serde_json::json!({"tolerance": 0.0}), "tolerance"),
            (serde_json::json!({"tolerance": -1.0}), "tolerance"),
            (serde_json::json!({"tolerance": 1e308}), "tolerance"),
            (serde_json::json!({"bounces": 9}), "bounces"),
            (serde_json::json!({"raster": "gpu"}), "raster"),
            (
                serde_json::json!({"raster_small_footprint": 9000}),
                "raster_small_footprint",
            ),
            (serde_json::json!({"grd": 4}), "known parameters"),
            (
                serde_json::json!({"orphan_kernel_px": 1.0}),
                "splat_orphans",
            ),
            (
                serde_json::json!({"orphan_kernel_px": 9.0, "splat_orphans": true}),
                "orphan_kernel_px",
            ),
            (
                serde_json::json!({"orphan_kernel_px": -1.0}),
                "orphan_kernel_px",
            ),
        ] {
            let msg = parse::<WavefrontParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        use caustics_method::MethodParams;
        assert_eq!(
            serde_json::Value::Object(WavefrontParams::default().to_json()),
            serde_json::json!({"grid": 512, "tolerance": 2e-3, "bounces": 0, "reflections": false, "splat_orphans": false, "orphan_kernel_px": 0.0, "raster": "hardware", "raster_small_footprint": 256})
        );
    }
}
