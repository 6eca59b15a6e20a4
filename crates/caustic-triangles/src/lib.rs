//! `caustic-triangles`: Umenhoffer, Patow & Szirmay-Kalos, "Caustic Triangles on the
//! GPU", as a caustics-bench method.
//!
//! Splatting photon hits needs a kernel size, and no single size suits the uneven
//! density of a caustic (the paper's Fig. 1). The paper instead joins neighbouring
//! photon hits into triangles, which adapt to the local density by construction: a
//! vertex carries the irradiance ΔΦ/ΔA of its photon's flux over the receiver area its
//! triangles cover, and Gouraud shading spreads it. The triangles are drawn into a
//! cube map around the caustic generator, which also knows distances, so that the
//! camera pass can refuse light reconstructed on a surface nearer to the generator
//! than the one being shaded (no light leaks).
//!
//! Passes (names `caustic-triangles/<pass>`), every frame:
//! 1. `light_gbuffer`, `distance_maps`, `trace_photons`: the photon hit location
//!    image (shared with `splatting`, see the [`photon_hits`] crate; §3, §4.1);
//! 2. `triangle_areas` (compute): the discard rule and each triangle's receiver area
//!    (`areas.wgsl` states the rule);
//! 3. `vertex_irradiance` (compute, the §5 per-vertex pass): ΔΦ/ΔA per vertex, with
//!    ΔA = (2/n) × the area of its n kept triangles (one cell's worth; `vertex_area =
//!    third` takes a third of it instead, which delivers every vertex's flux exactly);
//! 4. `triangles` (raster, §4.2): all triangles into the six faces of the caustic
//!    cube map, additive, irradiance and luminance × distance;
//! 5. `orphan_splats` (raster, only with `splat_orphans`): the hits none of whose
//!    triangles was kept, each as a one-texel splat (`orphans.wgsl`; `orphan_kernel_px`
//!    widens it to splatting's box kernel), so their light is not lost; the
//!    `photon_hits_without_triangles` counter says how many there are either way;
//! 6. `camera_lookup` (§4.3): ρ/π · E at each camera pixel whose distance from the
//!    centre matches the map's (`distance_test`).
//!
//! `raster=compute` (issue 17) replaces passes 4 and 5 by one compute pass of the name
//! `triangles` (`triangles_compute.wgsl`): each triangle's invocation finds the texels
//! of each face whose centres it covers with edge functions (caustics-gpu's
//! triangle_raster.wgsl, shared with wavefront), interpolates as the rasterizer does and adds fs_triangle's value into a
//! fixed-point accumulator with integer atomics (footprints over
//! `raster_small_footprint` are walked by whole workgroups); the orphans' splats go into
//! the same accumulator, which a last dispatch resolves into the cube map. The map is
//! the same on every run, and within a stated bound of the hardware path's
//! (`tests/accuracy.rs`): the odd texel on an edge shared by two triangles goes to the
//! other one, since the rasterizer decides ties on snapped vertices.
//!
//! Every pass runs once per (light, caustic generator) pair: each has its own photon
//! hit image, one light view fitted to the generator (a cube for a light inside it),
//! and its own cube map; the camera passes add up (§4.1). Triangles do not cross
//! between the faces of a cube view, nor between the sheets of the light paths beyond
//! the paper's (`bounces`, `reflections`: the [`photon_hits`] crate doc).
//!
//! ```no_run
//! use caustics_gpu::{AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer};
//! use caustics_method::CausticsMethod;
//! use caustic_triangles::{CausticTriangles, CausticTrianglesParams};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(None))?;
//! let scene = caustics_scene::Scene::load(&caustics_scene::resolve("sphere_on_plane")?)?;
//! let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default())?;
//! let renderer = Renderer::new(&ctx, gpu_scene, Default::default())?;
//! let mut method = CausticTriangles::new(&ctx, &renderer, &CausticTrianglesParams::default())?;
//! let mut profiler = PassProfiler::new(&ctx, 1);
//! let mut frame = renderer.begin_frame(&mut profiler, FrameMode::Timed)?;
//! method.record(&mut frame)?; // adds ρ/π · E into renderer.targets().surface
//! frame.submit(&ctx)?;
//! println!("{:?}", method.counters(&ctx)?);
//! # Ok(())
//! # }
//! ```

use bytemuck::{Pod, Zeroable};
use caustics_gpu::buffers::{storage_buffer, uniform_buffer};
use caustics_gpu::limits::Reservation;
use caustics_gpu::pass::{Bindable, ComputePass, RasterPass, Shader, groups_2d};
use caustics_gpu::textures::additive_hdr_target;
use caustics_gpu::wgpu;
use caustics_gpu::{Frame, GpuContext, GpuError, Renderer};
use caustics_method::params::{Raster, closed};
use caustics_method::{
    Capabilities, CausticsMethod, CounterDoc, Counters, Method, MethodError, Unsupported,
    method_params,
};
use caustics_scene::Scene;
use photon_hits::{AtlasAccumulator, CausticMap, PhotonHitConfig, PhotonHits};

/// The shared photon-hit crate, for callers that read hits or the cube map back.
pub use photon_hits;

const GRID_WGSL: &str = include_str!("grid.wgsl");
const AREAS_WGSL: &str = include_str!("areas.wgsl");
const TRIANGLES_WGSL: &str = include_str!("triangles.wgsl");
const ORPHANS_WGSL: &str = include_str!("orphans.wgsl");
const TRIANGLES_COMPUTE_WGSL: &str = include_str!("triangles_compute.wgsl");

/// Workgroups of `rasterize_large` (triangles_compute.wgsl): each takes every
/// `LARGE_WORKGROUPS`-th listed footprint; the ones with none left return at once.
const LARGE_WORKGROUPS: u32 = 256;
/// Bytes of the compute path's counts (`raster_counts` in triangles_compute.wgsl).
const RASTER_COUNTS_BYTES: u64 = 16;

fn pass_source(pass: &str) -> String {
    photon_hits::compose(&format!("{GRID_WGSL}\n{pass}"))
}

fn triangles_compute_source() -> String {
    pass_source(&format!(
        "{}\n{}\n{}\n{}\n{TRIANGLES_COMPUTE_WGSL}",
        photon_hits::SPLAT_KERNEL_WGSL,
        photon_hits::accumulator_wgsl(),
        caustics_gpu::shader::RASTER_COUNTS_WGSL,
        caustics_gpu::shader::TRIANGLE_RASTER_WGSL
    ))
}

fn orphans_source() -> String {
    photon_hits::compose(&format!(
        "{}\n{ORPHANS_WGSL}",
        photon_hits::SPLAT_KERNEL_WGSL
    ))
}

/// Registry name.
pub const NAME: &str = "caustic-triangles";

/// Profiling scope of the per-vertex ΔΦ/ΔA kernel (it shares the areas pass's shader
/// and bind group, so it is recorded with `begin_as`).
const VERTEX_IRRADIANCE_PASS: &str = "caustic-triangles/vertex_irradiance";

method_params! {
    /// Parameters of `caustic-triangles` (defaults: the paper's §6 where it gives them).
    pub struct CausticTrianglesParams {
        group
        /// The photon hit image, distance maps and cube map (shared with `splatting`).
        hits: PhotonHitConfig;
        // At least 1: a triangle may always cover as much receiver area as its light had
        // at the generator. At most 1e6, a triangle whose sides grew 1000x from the
        // generator to the receiver: at the paper's 128² image over a generator of the
        // scenes' size (radius 0.5-1 m) that is a triangle metres wide, a span across a
        // silhouette rather than a caustic, and a larger bound only switches the rule
        // off. It also stays a finite f32 on the GPU (1e308 became infinity there).
        /// discard triangles whose receiver area exceeds this x their area at the generator
        max_stretch: f64 = 1000.0 => closed(1.0, 1e6);
        /// a vertex's receiver area: fan ((2/n) x its n kept triangles, the irradiance right at the lit region's edge) or third (1/3 of them, every hit's flux delivered exactly)
        vertex_area: VertexArea = VertexArea::Fan;
        /// splat the hits none of whose triangles is kept as one cube-map texel each, so their light is not lost (paper: false)
        splat_orphans: bool = false;
        /// with splat_orphans: side (cube-map texels) of the box kernel each orphan hit is splatted as, splatting's energy-conserving kernel (1: one texel; 0: splatting's default kernel, 4 x cube_size / resolution; a wider kernel spreads the lone texels of light a torn wavefront leaves)
        orphan_kernel_px: u32 = 1 => closed(0.0, 64.0);
        /// how the triangles reach the cube map: hardware (drawn, additive blending: the paper's) or compute (compute kernels find each triangle's covered texels with edge functions and add them into a fixed-point accumulator with integer atomics, then resolved: the same image on every run)
        raster: Raster = Raster::Hardware;
        // At most 8192: an invocation walks up to six such footprints (a triangle on
        // every face), under llvmpipe's 65,535 loop iterations per invocation.
        /// with raster = compute: a triangle's footprint on a face (its bounding rectangle) of up to this many texels is walked by the triangle's own invocation, a larger one by a workgroup of 64
        raster_small_footprint: u32 = 256 => closed(0.0, 8192.0);
    }
    check = orphan_kernel_fits;
}

/// The rules between parameters: a wider orphan kernel only where orphans are splatted,
/// and no wider than a cube face.
fn orphan_kernel_fits(p: &CausticTrianglesParams) -> Result<(), String> {
    if p.orphan_kernel_px != 1 && !p.splat_orphans {
        return Err(format!(
            "orphan_kernel_px: {} texels for the orphans' splats, which only splat_orphans = true draws",
            p.orphan_kernel_px
        ));
    }
    if orphan_kernel_px(p) > p.hits.cube_size {
        return Err(format!(
            "orphan_kernel_px: expected at most cube_size ({}), got {}",
            p.hits.cube_size, p.orphan_kernel_px
        ));
    }
    Ok(())
}

/// The orphans' kernel side `params` ask for, `orphan_kernel_px = 0` resolved.
pub fn orphan_kernel_px(params: &CausticTrianglesParams) -> u32 {
    match params.orphan_kernel_px {
        0 => photon_hits::auto_kernel_px(&params.hits),
        k => k,
    }
}

impl Method for CausticTriangles {
    type Params = CausticTrianglesParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str = "photon hit image from the light, neighbouring hits as triangles with per-vertex irradiance in a cube map with distance (no light leaks), camera lookup";
    const SOURCE: &'static str = "Umenhoffer, Patow & Szirmay-Kalos, Caustic Triangles on the GPU (umenhoffer-patow-szirmay-kalos-caustic-triangles.txt)";
    const CAPABILITIES: Capabilities = photon_hits::CAPABILITIES;
    const COUNTERS: &'static [CounterDoc] = &CounterDoc::concat::<
        { photon_hits::COUNTER_DOCS.len() + TRIANGLE_COUNTER_DOCS.len() },
    >(photon_hits::COUNTER_DOCS, TRIANGLE_COUNTER_DOCS);

    fn check_scene(scene: &Scene, _params: &CausticTrianglesParams) -> Result<(), Unsupported> {
        photon_hits::check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &CausticTrianglesParams,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        Ok(Box::new(CausticTriangles::new(ctx, renderer, params)?))
    }
}

/// Matches `TriUniform` in grid.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TriUniform {
    layers: u32,
    resolution: u32,
    max_stretch: f32,
    vertex_area: u32,
}

/// How a vertex's receiver area ΔA is taken from its kept triangles (areas.wgsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VertexArea {
    /// (2/n) × the area of its n kept triangles, one cell's worth: the irradiance is
    /// right up to the edge of the lit region, whose vertices deliver n/6 of their flux.
    Fan,
    /// (1/3) × that area, each triangle's barycentric share: every vertex with a kept
    /// triangle delivers all of its flux; edge vertices are brighter.
    Third,
}

caustics_method::param_enum!(VertexArea, [VertexArea::Fan, VertexArea::Third]);

/// The triangle counters: the counter at index `TRI_*` of grid.wgsl and its name (a
/// test checks each constant's value is its index here).
const TRI_REASONS: [(&str, &str); 6] = [
    ("TRI_KEPT", "triangles_kept"),
    ("TRI_INVALID_VERTEX", "triangles_dropped_invalid_vertex"),
    (
        "TRI_RECEIVER_MISMATCH",
        "triangles_dropped_receiver_mismatch",
    ),
    ("TRI_PATH_MISMATCH", "triangles_dropped_path_mismatch"),
    ("TRI_STRETCHED", "triangles_dropped_stretched"),
    ("TRI_DEGENERATE", "triangles_dropped_degenerate"),
];

/// The counter after the `TRI_*` reasons (grid.wgsl `ORPHAN_HITS`): valid hits none of
/// whose triangles is kept.
const ORPHAN_COUNTER: (&str, &str) = ("ORPHAN_HITS", "photon_hits_without_triangles");

/// What each of caustic-triangles' own counters counts (the triangle passes, summed
/// over the (light, generator) pairs); [`Method::COUNTERS`] adds them to the photon
/// tracing ones of [`photon_hits::COUNTER_DOCS`]. `triangles_kept` and the
/// `triangles_dropped_*` counters add up to `triangles`.
#[rustfmt::skip]
pub const TRIANGLE_COUNTER_DOCS: &[CounterDoc] = &[
    CounterDoc { name: "triangles", doc: "triangles of the photon hit image (two per cell of four neighbouring texels, within one face and sheet) judged by the last frame's triangle_areas pass, summed over every (light, generator) pair" },
    CounterDoc { name: "triangles_kept", doc: "triangles kept and drawn into the caustic cube map: three valid hits on one receiver by one specular path, with a non-zero receiver area at most max_stretch x their area at the generator" },
    CounterDoc { name: "triangles_dropped_invalid_vertex", doc: "triangles dropped because at least one of their three texels holds no valid hit (any photons_* outcome)" },
    CounterDoc { name: "triangles_dropped_receiver_mismatch", doc: "triangles dropped because their three hits land on different receiver objects" },
    CounterDoc { name: "triangles_dropped_path_mismatch", doc: "triangles dropped because their hits took different specular paths (path ids: the side of the generator the light met, the number of further bounces off a mirror)" },
    CounterDoc { name: "triangles_dropped_stretched", doc: "triangles dropped because their area on the receiver exceeds max_stretch x the area their light had at the generator (half the mean texel footprint): a span across a silhouette or a grazing exit" },
    CounterDoc { name: "triangles_dropped_degenerate", doc: "triangles dropped because their area on the receiver is zero (coincident or collinear hits)" },
    CounterDoc { name: "raster_texels_covered", doc: "with raster = compute: (triangle, cube-map texel) pairs whose texel centre a kept triangle covers, each adding its light (the hardware path's triangles fragments)" },
    CounterDoc { name: "raster_large_footprints", doc: "with raster = compute: (triangle, face) footprints larger than raster_small_footprint, walked by a workgroup of 64 invocations instead of the triangle's own" },
    CounterDoc { name: "raster_footprints_walked_by_lane", doc: "with raster = compute: large footprints the list had no room for, walked by the triangle's own invocation (same light, slower)" },
    CounterDoc { name: "photon_hits_without_triangles", doc: "valid photon hits none of whose triangles is kept (orphans), counted by the vertex_irradiance pass: their light is lost unless splat_orphans draws each as a splat of orphan_kernel_px texels a side (one by default)" },
];

/// `caustic-triangles` bound to one scene.
pub struct CausticTriangles {
    /// One per (light, caustic generator) pair, light-major ([`PhotonHits::for_scene`]).
    pairs: Vec<Reconstruction>,
    bytes: u64,
}

/// The photon hit image of one (light, generator) pair, its cube map and the passes
/// that reconstruct it.
pub struct Reconstruction {
    hits: PhotonHits,
    map: CausticMap,
    areas: ComputePass,
    /// The triangles (and orphans) into the cube map, on the hardware or compute path.
    draw: TriangleDraw,
    buffers: TriangleBuffers,
    triangle_count: u32,
    bytes: u64,
}

/// How a reconstruction's triangles reach its cube map.
enum TriangleDraw {
    /// Drawn with additive blending (the paper's).
    Hardware {
        triangles: RasterPass,
        /// With `splat_orphans`: the one-texel splats of the hits no kept triangle
        /// carries.
        orphans: Option<RasterPass>,
    },
    /// Added into a fixed-point accumulator by compute kernels, then resolved.
    Compute(ComputeDraw),
}

/// The compute path's pass and buffers.
struct ComputeDraw {
    /// Kernels `rasterize`, `rasterize_large`, `orphan_splats`, `resolve`.
    pass: ComputePass,
    accumulator: AtlasAccumulator,
    /// (triangle, face) of the footprints walked by workgroups.
    large: wgpu::Buffer,
    /// `raster_counts`: cleared each frame, read by `counters`.
    raster_counts: wgpu::Buffer,
    splat_orphans: bool,
    /// The list's hold on the memory ledger.
    _memory: Reservation,
}

impl ComputeDraw {
    fn bytes(&self) -> u64 {
        self.accumulator.bytes() + self.large.size() + self.raster_counts.size()
    }
}

/// The reconstruction's own buffers.
struct TriangleBuffers {
    /// `TriUniform`.
    uniform: wgpu::Buffer,
    /// Receiver area of each triangle, 0 where discarded.
    tri_area: wgpu::Buffer,
    /// ΔΦ/ΔA of each vertex (one per photon-image texel).
    vertex_irradiance: wgpu::Buffer,
    /// One per `TRI_*` reason.
    tri_counters: wgpu::Buffer,
    /// The areas' and irradiances' bytes in the device's memory ledger.
    _memory: [Reservation; 2],
}

impl TriangleBuffers {
    fn new(
        ctx: &GpuContext,
        hits: &PhotonHits,
        triangle_count: u32,
        max_stretch: f64,
        vertex_area: VertexArea,
    ) -> Result<Self, MethodError> {
        let device = &ctx.device;
        // Both sized by the photon hit image (the resolution parameter): bound whole,
        // summed with every live resource, refused naming it.
        let raise = "lower resolution";
        let param = |e: GpuError| MethodError::Param {
            method: NAME,
            message: e.to_string(),
        };
        let tri_area_bytes = triangle_count.max(1) as u64 * 4;
        let irradiance_bytes = hits.texels() as u64 * 16;
        let memory = [
            ctx.reserve_storage(
                &format!("resolution: the caustic triangle areas ({triangle_count} x 4 bytes)"),
                tri_area_bytes,
                raise,
            )
            .map_err(param)?,
            ctx.reserve_storage(
                &format!(
                    "resolution: the caustic vertex irradiances ({} x 16 bytes)",
                    hits.texels()
                ),
                irradiance_bytes,
                raise,
            )
            .map_err(param)?,
        ];
        Ok(ctx.checked("caustic-triangles setup", || {
            let uniform = TriUniform {
                layers: hits.layers,
                resolution: hits.resolution,
                max_stretch: max_stretch as f32,
                vertex_area: match vertex_area {
                    VertexArea::Fan => 0,
                    VertexArea::Third => 1,
                },
            };
            Self {
                uniform: uniform_buffer(device, "caustic triangles params", &uniform),
                tri_area: storage_buffer(device, "caustic triangle areas", tri_area_bytes, false),
                vertex_irradiance: storage_buffer(
                    device,
                    "caustic vertex irradiance",
                    irradiance_bytes,
                    false,
                ),
                tri_counters: storage_buffer(device, "caustic triangle counters", 4 * 8, true),
                _memory: memory,
            }
        })?)
    }

    fn bytes(&self) -> u64 {
        self.uniform.size()
            + self.tri_area.size()
            + self.vertex_irradiance.size()
            + self.tri_counters.size()
    }
}

impl CausticTriangles {
    /// Builds the photon hit images (one per light and caustic generator), their caustic
    /// cube maps and the reconstruction passes.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &CausticTrianglesParams,
    ) -> Result<Self, MethodError> {
        // §3, §4.1: the photon hit images; §4.2: the cube maps they are reconstructed into.
        let pairs = PhotonHits::for_scene(ctx, renderer, NAME, &params.hits)?
            .into_iter()
            .map(|hits| Reconstruction::new(ctx, renderer, params, hits))
            .collect::<Result<Vec<_>, _>>()?;
        let bytes = pairs.iter().map(|p| p.bytes).sum();
        Ok(Self { pairs, bytes })
    }

    /// The (light, generator) pairs' reconstructions.
    pub fn pairs(&self) -> &[Reconstruction] {
        &self.pairs
    }

    /// The first pair's photon hit image (the one of a scene with one light and one
    /// generator).
    pub fn photon_hits(&self) -> &PhotonHits {
        &self.pairs[0].hits
    }

    /// The first pair's caustic cube map.
    pub fn caustic_map(&self) -> &CausticMap {
        &self.pairs[0].map
    }

    /// The first pair's per-vertex irradiance ([`Reconstruction::read_vertex_irradiance`]).
    pub fn read_vertex_irradiance(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>, MethodError> {
        self.pairs[0].read_vertex_irradiance(ctx)
    }
}

impl Reconstruction {
    fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &CausticTrianglesParams,
        hits: PhotonHits,
    ) -> Result<Self, MethodError> {
        let map = CausticMap::for_raster(ctx, renderer, NAME, &hits, &params.hits, params.raster)?;
        let n = hits.resolution;
        let triangle_count = hits.layers * (n - 1) * (n - 1) * 2;
        let b = TriangleBuffers::new(
            ctx,
            &hits,
            triangle_count,
            params.max_stretch,
            params.vertex_area,
        )?;
        // The discard rule and each triangle's receiver area, then ΔΦ/ΔA per vertex (§5).
        let areas_shader =
            Shader::new(ctx, "caustic-triangles areas.wgsl", pass_source(AREAS_WGSL))?;
        // One shader, one bind group; its two kernels are timed as two passes.
        let areas = ComputePass::builder(ctx, &format!("{NAME}/triangle_areas"), &areas_shader)
            .frame(renderer)
            .bind(
                1,
                &[
                    ("tri", &b.uniform),
                    ("hits", &hits.hits),
                    ("tri_area", &b.tri_area),
                    ("vertex_irradiance", &b.vertex_irradiance),
                    ("tri_counters", &b.tri_counters),
                ],
            )
            .kernels(&["triangle_areas", "vertex_irradiance_pass"])
            .build()?;
        let draw = match params.raster {
            Raster::Hardware => hardware_draw(ctx, renderer, params, &hits, &map, &b)?,
            Raster::Compute => TriangleDraw::Compute(compute_draw(
                ctx,
                renderer,
                params,
                &hits,
                &map,
                &b,
                triangle_count,
            )?),
        };
        let mut bytes = b.bytes() + hits.bytes() + map.bytes();
        if let TriangleDraw::Compute(c) = &draw {
            bytes += c.bytes();
        }
        Ok(Self {
            hits,
            map,
            areas,
            draw,
            buffers: b,
            triangle_count,
            bytes,
        })
    }

    /// The pair's photon hit image.
    pub fn photon_hits(&self) -> &PhotonHits {
        &self.hits
    }

    /// The pair's caustic cube map.
    pub fn caustic_map(&self) -> &CausticMap {
        &self.map
    }

    /// Per-vertex irradiance (W/m², rgb; w = 1 for an orphan), one per photon-image
    /// texel, read back for tests and figures.
    pub fn read_vertex_irradiance(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>, MethodError> {
        let bytes = caustics_gpu::readback::read_buffer_bytes(
            ctx,
            &self.buffers.vertex_irradiance,
            self.buffers.vertex_irradiance.size(),
            "caustic vertex irradiance",
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// What the triangles pass reads on either path (triangles.wgsl and
/// triangles_compute.wgsl declare these alike).
fn triangle_inputs<'a>(
    hits: &'a PhotonHits,
    map: &'a CausticMap,
    b: &'a TriangleBuffers,
) -> [(&'static str, &'a dyn Bindable); 5] {
    [
        ("cm", map.uniform()),
        ("tri", &b.uniform),
        ("hits", &hits.hits),
        ("tri_area", &b.tri_area),
        ("vertex_irradiance", &b.vertex_irradiance),
    ]
}

/// The paper's path: the kept triangles drawn into the six faces, additively (§4.2),
/// and with `splat_orphans` the orphans' one-texel splats after them.
fn hardware_draw(
    ctx: &GpuContext,
    renderer: &Renderer,
    params: &CausticTrianglesParams,
    hits: &PhotonHits,
    map: &CausticMap,
    b: &TriangleBuffers,
) -> Result<TriangleDraw, MethodError> {
    let triangles_shader = Shader::new(
        ctx,
        "caustic-triangles triangles.wgsl",
        pass_source(TRIANGLES_WGSL),
    )?;
    // No culling (the builder's default): triangles folded over a caustic curve face the
    // other way, and both count.
    let triangles = RasterPass::builder(
        ctx,
        &format!("{NAME}/triangles"),
        &triangles_shader,
        "vs_triangle",
    )
    .frame(renderer)
    .bind(1, &triangle_inputs(hits, map, b))
    .fragment("fs_triangle", &[Some(additive_hdr_target())])
    .build()?;
    let orphans = if params.splat_orphans {
        let shader = Shader::new(ctx, "caustic-triangles orphans.wgsl", orphans_source())?;
        Some(
            RasterPass::builder(ctx, &format!("{NAME}/orphan_splats"), &shader, "vs_orphan")
                .frame(renderer)
                .bind(
                    1,
                    &[
                        ("cm", map.uniform()),
                        ("hits", &hits.hits),
                        ("vertex_irradiance", &b.vertex_irradiance),
                    ],
                )
                .fragment("fs_splat", &[Some(additive_hdr_target())])
                .constants(&[("ORPHAN_KERNEL_PX", f64::from(orphan_kernel_px(params)))])
                .build()?,
        )
    } else {
        None
    };
    Ok(TriangleDraw::Hardware { triangles, orphans })
}

/// `raster=compute`: the kernels of triangles_compute.wgsl, their accumulator, the list
/// of large footprints and the counts.
fn compute_draw(
    ctx: &GpuContext,
    renderer: &Renderer,
    params: &CausticTrianglesParams,
    hits: &PhotonHits,
    map: &CausticMap,
    b: &TriangleBuffers,
    triangle_count: u32,
) -> Result<ComputeDraw, MethodError> {
    let accumulator = AtlasAccumulator::new(ctx, NAME, map)?;
    // Room for a large footprint per 16 triangles (they are the few near the centre or
    // across faces); past it the triangle's own invocation walks the footprint, slower
    // but with the same sums (`raster_footprints_walked_by_lane` counts them).
    let large_entries = u64::from(triangle_count / 16).max(1024);
    let large_bytes = large_entries * 8;
    let memory = ctx
        .reserve_storage(
            &format!(
                "resolution: the caustic triangles' list of large footprints ({large_entries} x 8 bytes)"
            ),
            large_bytes,
            "lower resolution",
        )
        .map_err(|e| MethodError::Param {
            method: NAME,
            message: e.to_string(),
        })?;
    let (large, raster_counts) = ctx.checked("caustic-triangles compute setup", || {
        (
            storage_buffer(
                &ctx.device,
                "caustic triangles large footprints",
                large_bytes,
                false,
            ),
            storage_buffer(
                &ctx.device,
                "caustic triangles raster counts",
                RASTER_COUNTS_BYTES,
                true,
            ),
        )
    })?;
    let shader = Shader::new(
        ctx,
        "caustic-triangles triangles_compute.wgsl",
        triangles_compute_source(),
    )?;
    let mut kernels = vec!["rasterize", "rasterize_large", "resolve"];
    if params.splat_orphans {
        kernels.push("orphan_splats");
    }
    let mut entries = triangle_inputs(hits, map, b).to_vec();
    entries.extend([
        ("accum", &accumulator.buffer as &dyn Bindable),
        ("atlas_out", &map.atlas.view),
        ("large", &large),
        ("raster_counts", &raster_counts),
    ]);
    let pass = ComputePass::builder(ctx, &format!("{NAME}/triangles"), &shader)
        .frame(renderer)
        .bind(1, &entries)
        .kernels(&kernels)
        .constants(&[
            ("small_texels", f64::from(params.raster_small_footprint)),
            ("ORPHAN_KERNEL_PX", f64::from(orphan_kernel_px(params))),
        ])
        .build()?;
    Ok(ComputeDraw {
        pass,
        accumulator,
        large,
        raster_counts,
        splat_orphans: params.splat_orphans,
        _memory: memory,
    })
}

impl CausticsMethod for CausticTriangles {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        for pair in &self.pairs {
            pair.record(frame)?;
        }
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let mut total = Counters::new();
        for pair in &self.pairs {
            photon_hits::add_counters(&mut total, pair.counters(ctx)?);
        }
        Ok(total)
    }

    fn gpu_memory_bytes(&self) -> u64 {
        self.bytes
    }
}

impl Reconstruction {
    fn record(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        // Everything before the lookup (hits, triangle areas, the caustic triangles and
        // orphans drawn into the light-space cube map) is independent of the camera: a
        // reused scoring sub-frame keeps it.
        if !frame.reuses_light_side() {
            self.record_light_side(frame)?;
        }
        self.map.record_lookup(frame)
    }

    fn record_light_side(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        self.hits.record(frame)?;
        frame
            .encoder
            .clear_buffer(&self.buffers.tri_counters, 0, None);
        self.areas
            .begin(frame)?
            .dispatch("triangle_areas", [self.triangle_count.div_ceil(64), 1, 1])?;
        self.areas
            .begin_as(frame, VERTEX_IRRADIANCE_PASS)?
            .dispatch(
                "vertex_irradiance_pass",
                [self.hits.texels().div_ceil(64), 1, 1],
            )?;
        match &self.draw {
            TriangleDraw::Hardware { triangles, orphans } => {
                {
                    let target = self.map.reconstruction_attachment();
                    let mut pass = triangles.begin(frame, &target, None)?;
                    for face in 0..6 {
                        self.map.set_face(&mut pass, face);
                        pass.draw(0..3 * self.triangle_count, face..face + 1);
                    }
                }
                if let Some(orphans) = orphans {
                    let target = self.map.added_attachment();
                    let mut pass = orphans.begin(frame, &target, None)?;
                    for face in 0..6 {
                        self.map.set_face(&mut pass, face);
                        pass.draw(0..6 * self.hits.texels(), face..face + 1);
                    }
                }
            }
            TriangleDraw::Compute(c) => {
                frame.encoder.clear_buffer(&c.raster_counts, 0, None);
                let mut pass = c.pass.begin(frame)?;
                pass.dispatch(
                    "rasterize",
                    groups_2d(u64::from(self.triangle_count).div_ceil(64)),
                )?;
                pass.dispatch("rasterize_large", [LARGE_WORKGROUPS, 1, 1])?;
                if c.splat_orphans {
                    pass.dispatch(
                        "orphan_splats",
                        groups_2d(u64::from(self.hits.texels()).div_ceil(64)),
                    )?;
                }
                pass.dispatch("resolve", AtlasAccumulator::resolve_groups(&self.map))?;
            }
        }
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let mut out = self.hits.counters(ctx)?;
        let c = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.buffers.tri_counters,
            self.buffers.tri_counters.size(),
            "caustic triangle counters",
        )?;
        out.insert("triangles".into(), self.triangle_count as u64);
        for ((_, name), v) in TRI_REASONS.iter().zip(&c) {
            out.insert((*name).into(), *v as u64);
        }
        out.insert(ORPHAN_COUNTER.1.into(), c[TRI_REASONS.len()] as u64);
        // The compute rasterizer's work only where it runs (the hardware path's is its
        // triangles pass's fragments).
        if let TriangleDraw::Compute(draw) = &self.draw {
            let w = caustics_gpu::readback::read_buffer_u32(
                ctx,
                &draw.raster_counts,
                RASTER_COUNTS_BYTES,
                "caustic triangle raster counts",
            )?;
            out.insert("raster_large_footprints".into(), u64::from(w[0]));
            out.insert("raster_footprints_walked_by_lane".into(), u64::from(w[1]));
            out.insert(
                "raster_texels_covered".into(),
                u64::from(w[2]) | (u64::from(w[3]) << 32),
            );
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_gpu::layout::wgsl_u32_constant;
    use caustics_gpu::shader;
    use caustics_method::params::parse;

    #[test]
    fn shaders_validate() -> Result<(), String> {
        shader::validate_wgsl("orphans.wgsl", &orphans_source())?;
        shader::validate_wgsl("areas.wgsl", &pass_source(AREAS_WGSL))?;
        shader::validate_wgsl("triangles.wgsl", &pass_source(TRIANGLES_WGSL))?;
        shader::validate_wgsl("triangles_compute.wgsl", &triangles_compute_source())
    }

    #[test]
    fn tri_uniform_matches_its_wgsl() {
        caustics_gpu::assert_wgsl_layout!(
            pass_source(AREAS_WGSL),
            TriUniform {
                layers,
                resolution,
                max_stretch,
                vertex_area
            }
        );
    }

    /// Every triangle counter `Reconstruction::counters` reports has a doc in the
    /// method's list, and every doc of its own list is of one it reports.
    #[test]
    fn every_triangle_counter_is_documented() {
        let mut names: Vec<&str> = TRI_REASONS.iter().map(|(_, n)| *n).collect();
        names.extend([
            "triangles",
            ORPHAN_COUNTER.1,
            "raster_texels_covered",
            "raster_large_footprints",
            "raster_footprints_walked_by_lane",
        ]);
        if let Err(e) = caustics_method::CounterDoc::check(TRIANGLE_COUNTER_DOCS, &names) {
            panic!("{e}");
        }
        assert_eq!(
            CausticTriangles::COUNTERS.len(),
            photon_hits::COUNTER_DOCS.len() + TRIANGLE_COUNTER_DOCS.len()
        );
    }

    #[test]
    fn counter_names_follow_the_wgsl_constants() {
        for (index, (constant, _)) in TRI_REASONS.iter().enumerate() {
            assert_eq!(
                wgsl_u32_constant(&pass_source(AREAS_WGSL), constant).ok(),
                Some(index as u32),
                "{constant}"
            );
        }
        assert_eq!(
            wgsl_u32_constant(&pass_source(AREAS_WGSL), ORPHAN_COUNTER.0).ok(),
            Some(TRI_REASONS.len() as u32)
        );
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"resolution": 1}), "resolution"),
            (serde_json::json!({"cube_size": 8}), "cube_size"),
            (
                serde_json::json!({"distance_map_size": 9000}),
                "distance_map_size",
            ),
            (
                serde_json::json!({"distance_tolerance": 2.0}),
                "distance_tolerance",
            ),
            (serde_json::json!({"max_stretch": 0.5}), "max_stretch"),
            (serde_json::json!({"max_stretch": 1e308}), "max_stretch"),
            (serde_json::json!({"distance_test": "yes"}), "distance_test"),
            (serde_json::json!({"raster": "gpu"}), "raster"),
            (
                serde_json::json!({"raster_small_footprint": 9000}),
                "raster_small_footprint",
            ),
            (serde_json::json!({"kernel_px": 4}), "known parameters"),
            (serde_json::json!({"orphan_kernel_px": 4}), "splat_orphans"),
            (
                serde_json::json!({"orphan_kernel_px": 65}),
                "orphan_kernel_px",
            ),
            (
                serde_json::json!({"orphan_kernel_px": 32, "splat_orphans": true, "cube_size": 16}),
                "cube_size",
            ),
        ] {
            let msg = parse::<CausticTrianglesParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        let p = parse::<CausticTrianglesParams>(NAME, &serde_json::Value::Null).expect("defaults");
        assert_eq!(p, CausticTrianglesParams::default());
        assert_eq!((p.hits.resolution, p.max_stretch), (128, 1000.0));
        // The orphans' default kernel is one texel; 0 is splatting's, four hit-image
        // texels wide.
        assert_eq!(orphan_kernel_px(&p), 1);
        let auto = parse::<CausticTrianglesParams>(
            NAME,
            &serde_json::json!({"orphan_kernel_px": 0, "splat_orphans": true}),
        )
        .expect("the splatting kernel");
        assert_eq!(orphan_kernel_px(&auto), 4 * 512 / 128);
    }
}
