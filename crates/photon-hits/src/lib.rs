//! Photon hit location images, shared by `caustic-triangles` and `splatting`
//! (Umenhoffer, Patow, Szirmay-Kalos, "Caustic Triangles on the GPU", §3–§4).
//!
//! Three pieces, each used by both methods so that they differ only in how the hits
//! are reconstructed:
//!
//! * **Photon tracing** ([`PhotonHits`], `trace.wgsl`, §4.1): the scene is rasterized
//!   from the light ([`GBufferPass::light_gbuffer`]) over a view fitted to the caustic
//!   generator (orthographic for a directional light, one perspective face aimed at the
//!   generator for a point/spot light outside it, the light's cube otherwise). For each
//!   texel whose first surface is the generator, a compute pass reflects or refracts
//!   the light ray, finds a closed refractor's exit point in the generator's own
//!   distance map and the diffuse receiver in the distance map of the receivers around
//!   the generator's centre (layered distance maps, §3, [`caustics_gpu::impostor`]),
//!   and stores the landing point, the receiver's normal, the texel's flux (the power
//!   through the texel × Fresnel transmittances or the mirror's reflectance), the
//!   receiver's and the specular path's ids, and why a texel is invalid. One storage
//!   buffer, allocated once; nothing is read back on the hot path.
//! * **The caustic cube map** ([`CausticMap`], §4.2): six faces (a 3×2 atlas, the
//!   impostors' face order and texel convention) around the same centre, into which a
//!   method adds irradiance on the receiver (rgb, W/m²) and luminance × distance from
//!   the centre (alpha), with additive blending.
//! * **The camera pass** (`lookup.wgsl`, §4.3): each camera G-buffer pixel on a
//!   diffuse surface looks the map up in the direction from the centre and takes a
//!   texel's light only where the texel's (flux-weighted mean) distance matches the
//!   pixel's distance within `distance_tolerance`: the paper's way to stop light
//!   reconstructed on one surface from leaking onto a surface hidden behind it.
//!   `distance_test = false` turns the test off, to show the leak.
//!
//! Scope: any lights, any specular objects (each a mirror of any shape, a closed
//! dielectric (sphere or mesh) with two refractions, or an open dielectric
//! quad/heightfield with one), diffuse receivers of any shape. As in the paper (§4.1),
//! each caustic generator is rendered from each light: one hit image, distance maps
//! and caustic cube map per (light, generator) pair ([`PhotonHits::for_scene`]), whose
//! camera passes add up. Light passing from one generator to another (a chain, the
//! ball over the water) is dropped where it meets the second by default; with
//! `bounces` > 0 it is traced on exactly through the scene's BVH until a diffuse
//! surface takes it (§4.1: the ray "is traced, possibly multiple times, until a diffuse
//! or glossy surface is found") and lands in the first generator's caustic map.
//!
//! **Light paths.** The default path has one specular event per interface, the path
//! whose power §4.1 gives as "the power going through a pixel of the light's camera
//! and the Fresnel factors along the path (or the complement of the Fresnel if
//! refraction happens)": light reflected inside a refractor (total internal or
//! Fresnel) is dropped, so is the Fresnel reflection off the first interface, and so
//! is a ray that meets a mirror generator a second time (the ring's opposite wall).
//! (The paper's ray "is traced, possibly multiple times, until a diffuse or glossy
//! surface is found", which leaves open whether it follows total internal reflection;
//! the default does not.) Two parameters
//! extend it ([`PhotonHitConfig::bounces`], [`PhotonHitConfig::reflections`]):
//! each further path gets a *sheet* of the hit image of its own (the light leaving a
//! closed refractor after j internal reflections is sheet j; the reflection off the
//! first interface is the last sheet), so every sheet is one smooth specular path,
//! triangles form within a sheet only and both methods reconstruct all sheets into
//! the one cube map. A mirror path does not branch: its further reflections stay in
//! sheet 0 with path ids of their own. An open refractor (water) has no inside to
//! reflect in; `bounces` does not apply to it. Light leaving a closed refractor that
//! meets the generator again outside (a concave mesh) is not refracted again.
//!
//! **Silhouettes.** The paper's hit image stops at the last texel whose centre sees the
//! generator: the light through the part of the next texel that still meets it is
//! dropped, and a reconstruction ends a texel short of the silhouette's landing. Where
//! the reflection turns fast near an edge (the ring's rim) that last row spreads over
//! tens of centimetres of floor, a dark scalloped wedge. With
//! [`PhotonHitConfig::silhouette_hits`] each texel beside the generator is traced from
//! the generator's exact edge, found by bisecting its ray towards a neighbour that meets
//! it against the scene's BVH and analytic shapes ([`caustics_gpu::triangle_bvh`]),
//! and carries the share of its light on the generator's side (`photon_hits_silhouette`).

mod accumulator;
mod cube_map;

pub use accumulator::{ATLAS_WORDS_PER_TEXEL, AtlasAccumulator, accumulator_wgsl};
pub use cube_map::{CausticMap, face_origin};

use bytemuck::{Pod, Zeroable};
use caustics_gpu::buffers::{storage_buffer, uniform_buffer};
use caustics_gpu::impostor::{DistanceImpostor, IMPOSTOR_TRACE_WGSL, ImpostorPass, objects_bounds};
use caustics_gpu::limits::Reservation;
use caustics_gpu::pass::{ComputePass, Shader};
use caustics_gpu::wgpu;
use caustics_gpu::{
    Frame, GBuffer, GpuContext, GpuError, GpuScene, LightProjection, LightView, Renderer, shader,
};
use caustics_method::params::{above, closed};
use caustics_method::{Capabilities, CounterDoc, Counters, MethodError, Unsupported};
use caustics_scene::{Material, Scene, Shape, Vec3};

/// Types shared by every photon-hit pass (`PhotonHit`, `CausticMapUniform`).
pub const TYPES_WGSL: &str = include_str!("types.wgsl");
/// The photon tracing pass.
pub const TRACE_WGSL: &str = include_str!("trace.wgsl");
/// The camera pass.
pub const LOOKUP_WGSL: &str = include_str!("lookup.wgsl");
/// A hit drawn as a box kernel into the caustic cube map (`splat_vertex`, `fs_splat`):
/// splatting's reconstruction, and caustic-triangles' for hits that join no triangle.
/// The including pass binds `cm: CausticMapUniform`.
pub const SPLAT_KERNEL_WGSL: &str = include_str!("splat_kernel.wgsl");

/// A photon-hit pass's full WGSL: the shared GPU files, the impostor search, the
/// photon-hit types, then the pass.
pub fn compose(pass: &str) -> String {
    shader::compose_method(&format!("{IMPOSTOR_TRACE_WGSL}\n{TYPES_WGSL}\n{pass}"))
}

/// Group of the tracing pass that holds the scene's triangle BVH (silhouette hits).
const BVH_GROUP: u32 = 2;

/// The tracing pass: the photon-hit types and the scene's BVH (the exact rays of
/// silhouette hits) before trace.wgsl.
fn trace_source() -> String {
    compose(&format!(
        "{}\n{TRACE_WGSL}",
        caustics_gpu::triangle_bvh::wgsl(BVH_GROUP)
    ))
}

/// Index of the silhouette hits' counter (trace.wgsl `HIT_EDGE`, after the reasons).
const COUNTER_EDGE: usize = 7;

/// Bytes of one `PhotonHit` (types.wgsl; the layout test checks the two agree).
pub const HIT_BYTES: u64 = std::mem::size_of::<PhotonHit>() as u64;

/// Relative tolerance of the distance-map searches: a secant result further than
/// this × the map's reach from the stored surface is a jump across a depth
/// discontinuity, not a hit.
const SEARCH_TOLERANCE: f32 = 2e-3;

/// Why texels are invalid: the counter at index `HIT_*` of types.wgsl and its name
/// (a test checks each constant's value is its index here).
const HIT_REASONS: [(&str, &str); 7] = [
    ("HIT_VALID", "photon_hits"),
    ("HIT_NOT_GENERATOR", "photons_missing_generator"),
    ("HIT_TIR", "photons_total_internal_reflection"),
    ("HIT_NO_EXIT", "photons_no_exit"),
    ("HIT_SECOND_BOUNCE", "photons_second_bounce"),
    ("HIT_NO_RECEIVER", "photons_no_receiver"),
    ("HIT_SPECULAR_RECEIVER", "photons_specular_receiver"),
];

/// What each photon-tracing counter counts, the counters both `caustic-triangles` and
/// `splatting` report ([`PhotonHits::counters`], summed over the (light, generator)
/// pairs). Each hit-image texel of each sheet gets exactly one outcome in the last
/// frame's `trace_photons` pass, so `photon_hits` and the `photons_*` counters add up
/// to `photon_texels`.
#[rustfmt::skip]
pub const COUNTER_DOCS: &[CounterDoc] = &[
    CounterDoc { name: "photon_texels", doc: "texels of the photon hit location image: light-view texels x faces x sheets (one sheet per specular path: bounces, reflections), summed over every (light, generator) pair" },
    CounterDoc { name: "photon_hits", doc: "hit-image texels (all sheets) whose light lands on a diffuse receiver in the last frame's trace_photons pass; includes photon_hits_fresnel_reflection and photon_hits_bounce_N" },
    CounterDoc { name: "photon_hits_fresnel_reflection", doc: "those of photon_hits in the Fresnel-reflection sheet: light reflected off a dielectric generator's first interface (reflections = true)" },
    CounterDoc { name: "photon_hits_bounce_N", doc: "those of photon_hits whose light took N further specular events on the generator: it left a closed refractor after N internal reflections (sheet N), or reflected N more times off a mirror (bounces >= N)" },
    CounterDoc { name: "photons_missing_generator", doc: "hit-image texels (every sheet) whose light meets nothing, or another object first, in the light G-buffer: no caustic path through this generator" },
    CounterDoc { name: "photons_total_internal_reflection", doc: "texels of a sheet whose light is totally internally reflected where that sheet's path refracts out (a closed refractor's exit, an open one met from below): none of it lands from there (with bounces it goes on inside, to the next sheet)" },
    CounterDoc { name: "photons_no_exit", doc: "texels of a closed refractor whose exit point the search in the generator's distance map did not find (that sheet and every later one)" },
    CounterDoc { name: "photons_second_bounce", doc: "texels whose light, reflected off a mirror generator, meets that mirror again once its bounces further reflections are spent (the ring's opposite wall): dropped" },
    CounterDoc { name: "photons_no_receiver", doc: "texels whose light, leaving the generator, finds no surface in the receivers' distance map (it leaves the scene)" },
    CounterDoc { name: "photon_hits_silhouette", doc: "texels whose centre misses the generator beside one that meets it, traced from the generator's exact edge between them (silhouette_hits): landed with the share of the texel's light on the generator's side, a hit at the silhouette's landing; not among photon_hits, and no longer among photons_missing_generator (a silhouette texel whose light lands nowhere is counted with the other reasons)" },
    CounterDoc { name: "photons_specular_receiver", doc: "texels whose light lands on another specular object (or where the receivers' distance map names no object): dropped, not traced on to the receivers behind it (with bounces > 0: those whose chain ends on no diffuse surface within bounces specular events, or at a shading normal that turns the light back)" },
    CounterDoc { name: "photon_hits_chained", doc: "those of photon_hits whose light met another specular object after the generator and was traced on exactly through it (bounces > 0: a chain, the ball's light through the water)" },
];

/// Most further specular events [`PhotonHitConfig::bounces`] allows (the counters
/// buffer has one valid-hit counter per bounce order).
pub const MAX_BOUNCES: u32 = 8;

/// Index of the first counter after the `HIT_*` reasons: the Fresnel reflection's
/// valid hits (trace.wgsl `COUNTER_REFLECTED`), then one per bounce order.
const COUNTER_REFLECTED: usize = 8;
/// Index of the chained hits' counter (trace.wgsl `COUNTER_CHAINED`), after the orders.
const COUNTER_CHAINED: usize = COUNTER_REFLECTED + 1 + MAX_BOUNCES as usize;
const COUNTERS: usize = COUNTER_CHAINED + 1;

caustics_method::method_params! {
    /// The settings shared by both photon-hit methods, a parameter group of each
    /// (defaults: Umenhoffer et al. §6 where they give them).
    pub struct PhotonHitConfig {
        /// photon hit location image, texels per side (paper: 128)
        resolution: u32 = 128 => closed(2.0, 1024.0);
        /// caustic cube map, texels per face side (paper: 512)
        cube_size: u32 = 512 => closed(16.0, 2048.0);
        /// distance maps of the generator and the receivers, texels per face side
        distance_map_size: u32 = 256 => closed(16.0, 2048.0);
        /// accept caustic light only where the stored distance matches (§4.3; false shows light leaks)
        distance_test: bool = true;
        /// distance test: |stored - actual| <= tolerance x actual
        distance_tolerance: f64 = 0.05 => above(0.0, 1.0);
        /// further specular events followed: internal reflections in a closed refractor (Fresnel and total), further reflections off a mirror, and as many events on other specular objects the light meets after the generator (a chain, traced exactly through the scene's BVH) (default 0: one event per interface, light meeting another specular object is dropped)
        bounces: u32 = 0 => closed(0.0, 8.0);
        /// also follow the Fresnel reflection off a dielectric's first interface (paper: false)
        reflections: bool = false;
        /// trace the texels beside the generator's silhouette from its exact edge, with the share of their light on the generator's side, so the reconstruction reaches the silhouette's landing instead of stopping a texel short of it (the ring's rim row; paper: false, the texel is dropped)
        silhouette_hits: bool = false;
    }
}

/// How light passes the caustic generator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeneratorKind {
    /// Reflected once.
    Mirror,
    /// Refracted in and out of a closed dielectric (sphere, mesh).
    ClosedRefractor,
    /// Refracted once into an open dielectric (quad, heightfield: water).
    OpenRefractor,
}

/// The scene's caustic generators (every specular object) and their kinds, or why the
/// scene is out of reach.
pub fn caustic_generators(scene: &Scene) -> Result<Vec<(usize, GeneratorKind)>, Unsupported> {
    let mut generators = Vec::new();
    let mut receivers = 0;
    for (i, o) in scene.objects.iter().enumerate() {
        let kind = match (scene.material(o), &o.shape) {
            (Material::Diffuse { .. }, _) => {
                receivers += 1;
                continue;
            }
            (Material::Mirror { .. }, _) => GeneratorKind::Mirror,
            (Material::Dielectric { .. }, Shape::Sphere { .. } | Shape::Mesh(_)) => {
                GeneratorKind::ClosedRefractor
            }
            (Material::Dielectric { .. }, Shape::Quad { .. } | Shape::Heightfield(_)) => {
                GeneratorKind::OpenRefractor
            }
            (Material::Dielectric { .. }, other) => {
                return Err(Unsupported(format!(
                    "objects[{i}] is a dielectric {}; photon hits refract through closed spheres and meshes or open quads and heightfields",
                    other.kind()
                )));
            }
        };
        generators.push((i, kind));
    }
    if receivers == 0 {
        return Err(Unsupported("the scene has no diffuse receiver".into()));
    }
    if generators.is_empty() {
        return Err(Unsupported("the scene has no specular object".into()));
    }
    Ok(generators)
}

/// Kernel side (cube-map texels) per hit-image texel spacing of [`auto_kernel_px`].
///
/// Chosen from the `splatting-kernel` experiment (bench/experiments, results in
/// results/reproduce/splatting-kernel): kernels of 1-32 texels at hit images of 64²,
/// 128² and 256² (cube faces of 512²) on every built-in scene splatting renders, scored
/// against the CPU reference at 128×96 with 16 samples per pixel. The kernel with the
/// lowest mean HDR-FLIP over the scenes was 32 texels at 64² hits (0.322), 16 at 128²
/// (0.290), 8 at 256² (0.266): in each case 4 × cube_size / resolution, a kernel four
/// hit-image texels wide. The lowest geometric-mean relMSE was at 24, 12 and 8 texels,
/// within 15 % of the default's (0.0107 against 0.0123 at 64², 0.0045 against 0.0048
/// at 128²). Smaller kernels leave the photons' dots (the old fixed 4 texels at 128²
/// hits: water_pool HDR-FLIP 0.358 against 0.133 at 16), larger ones blur the foci.
/// Measured at 128×96 (re-run after each kernel texel took its own footprint and
/// distance, which gave the ring back the 16 % its large kernels lost to the distance
/// test; the choice stood): at larger camera resolutions a blur shows more, and a
/// smaller kernel may win there.
pub const KERNEL_PER_HIT_TEXEL: u32 = 4;

/// The kernel splatting's `kernel_px = 0` and caustic-triangles' `orphan_kernel_px = 0`
/// stand for: [`KERNEL_PER_HIT_TEXEL`] × cube_size / resolution, rounded, within 1..=64
/// and the cube face.
pub fn auto_kernel_px(hits: &PhotonHitConfig) -> u32 {
    let k = (KERNEL_PER_HIT_TEXEL * hits.cube_size + hits.resolution / 2) / hits.resolution;
    k.clamp(1, 64.min(hits.cube_size))
}

/// What both photon-hit methods render: every reflecting or refracting generator seen
/// by every light of any kind, surface caustics only (Umenhoffer et al. §3, §4.1).
pub const CAPABILITIES: Capabilities = Capabilities {
    surface: true,
    volume: false,
    reflection: true,
    refraction: true,
    // With `bounces`: several specular events on the one generator.
    multiple_bounces: true,
    directional_light: true,
    point_light: true,
    spot_light: true,
    sphere_light: false,
    environment_light: false,
    // Photon hits are where light paths end on diffuse surfaces: nothing scatters or is
    // absorbed on the way.
    no_medium_in_paper: "Umenhoffer, Patow & Szirmay-Kalos render surface caustics from the terminal hits of light paths (§1: \u{201c}Light paths starting at the light sources and visiting specular reflectors and refractors until they arrive at diffuse surfaces need to be simulated to create caustic effects\u{201d}; §2: \u{201c}the second projects caustic patterns onto the receiver surfaces\u{201d}): no scattering or absorption along the path",
};

/// Scene checks shared by both methods.
pub fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    caustic_generators(scene).map(|_| ())
}

/// Matches `TraceUniform` in trace.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TraceUniform {
    faces: u32,
    resolution: u32,
    generator: u32,
    flags: u32,
    center: [f32; 4],
    generator_center: [f32; 4],
    view: [f32; 4],
    paths: [u32; 4],
    clip_to_world: [[[f32; 4]; 4]; 6],
}

/// The sheets of the hit image (one per specular path a texel's light may take, see
/// the crate doc) for a generator of `kind` under `config`: (sheets, the Fresnel
/// reflection's sheet).
fn sheets(kind: GeneratorKind, config: &PhotonHitConfig) -> (u32, Option<u32>) {
    let transmitted = match kind {
        GeneratorKind::ClosedRefractor => 1 + config.bounces,
        GeneratorKind::Mirror | GeneratorKind::OpenRefractor => 1,
    };
    match kind {
        GeneratorKind::Mirror => (1, None),
        _ if config.reflections => (transmitted + 1, Some(transmitted)),
        _ => (transmitted, None),
    }
}

/// The scene's caustic generator as the photon passes see it.
struct Generator {
    /// Object index.
    index: usize,
    kind: GeneratorKind,
    /// Centre of its bounds: the distance maps' and the cube map's reference point (m).
    center: Vec3,
    /// Farthest vertex from `center` (m).
    radius: f32,
    /// Every other object (the receivers' distance map).
    receivers: Vec<usize>,
}

impl Generator {
    /// Object `index` of kind `kind` as a generator, or why `method` cannot use it.
    fn locate(
        gpu_scene: &GpuScene,
        method: &'static str,
        index: usize,
        kind: GeneratorKind,
    ) -> Result<Self, MethodError> {
        let scene = &gpu_scene.scene;
        let unsupported = |reason| MethodError::Unsupported {
            method,
            scene: scene.name.clone(),
            reason,
        };
        let center = objects_bounds(gpu_scene, &[index])
            .map(|b| b.center())
            .ok_or_else(|| {
                unsupported(Unsupported(format!("objects[{index}] has no triangles")))
            })?;
        let radius = gpu_scene.meshes[index]
            .positions
            .iter()
            .map(|p| (*p - center).length())
            .fold(0.0f32, f32::max);
        // Every other object: the diffuse ones receive the light, another generator
        // stops it (the paper traces on through the other's distance map; here light
        // passing from one generator to another is dropped as photons_specular_receiver
        // rather than let through to the receivers behind it).
        let receivers = (0..scene.objects.len()).filter(|&i| i != index).collect();
        Ok(Self {
            index,
            kind,
            center,
            radius,
            receivers,
        })
    }

    /// The tracing pass's uniform for a light view of `faces` faces of `resolution`².
    fn trace_uniform(
        &self,
        view: &LightView,
        tan_half: f32,
        config: &PhotonHitConfig,
        light: usize,
        faces: u32,
        maps: &DistanceMaps,
    ) -> TraceUniform {
        let (sheets, reflected) = sheets(self.kind, config);
        let flags = u32::from(self.kind == GeneratorKind::ClosedRefractor)
            | (u32::from(view.projection == LightProjection::Orthographic) << 1)
            | (u32::from(config.silhouette_hits) << 2);
        let mut clip_to_world = [[[0.0; 4]; 4]; 6];
        for (m, face) in clip_to_world.iter_mut().zip(&view.faces) {
            *m = face.view_proj.inverse().to_cols_array_2d();
        }
        let generator_reach = maps.generator.as_ref().map_or(0.0, |m| m.reach);
        TraceUniform {
            faces,
            resolution: config.resolution,
            generator: self.index as u32,
            flags,
            center: self.center.extend(maps.receivers.reach).to_array(),
            generator_center: self.center.extend(generator_reach).to_array(),
            view: [view.texel_size, tan_half, 0.0, SEARCH_TOLERANCE],
            paths: [
                config.bounces,
                sheets,
                reflected.unwrap_or(u32::MAX),
                light as u32,
            ],
            clip_to_world,
        }
    }
}

/// The layered distance maps of §3 around the generator's centre: the generator's own
/// (the exit point of a closed refractor; none for an open one) and the receivers'.
struct DistanceMaps {
    pass: ImpostorPass,
    generator: Option<DistanceImpostor>,
    receivers: DistanceImpostor,
}

impl DistanceMaps {
    fn new(
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        g: &Generator,
        size: u32,
    ) -> Result<Self, GpuError> {
        let pass = ImpostorPass::new(ctx)?;
        let around =
            |objects: &[usize]| pass.impostor_around(ctx, gpu_scene, objects, g.center, size);
        let generator = match g.kind {
            GeneratorKind::OpenRefractor => None,
            _ => Some(around(&[g.index])?),
        };
        let receivers = around(&g.receivers)?;
        Ok(Self {
            pass,
            generator,
            receivers,
        })
    }

    /// Rebuilt every frame, as for a dynamic scene.
    fn record(&self, frame: &mut Frame<'_>, name: &str) -> Result<(), GpuError> {
        let scene = frame.renderer.scene();
        for map in self.generator.iter().chain([&self.receivers]) {
            self.pass.record(frame, name, scene, map)?;
        }
        Ok(())
    }

    fn bytes(&self) -> u64 {
        self.generator.as_ref().map_or(0, DistanceImpostor::bytes) + self.receivers.bytes()
    }
}

/// The photon hit location image of a scene and the passes that fill it.
pub struct PhotonHits {
    gbuffer_name: String,
    maps_name: String,
    light_gbuffer: GBuffer,
    maps: DistanceMaps,
    trace: ComputePass,
    /// `array<PhotonHit>`, one per texel of every face of the light view and every
    /// sheet (sheet-major, then faces, then rows, then columns).
    pub hits: wgpu::Buffer,
    counters: wgpu::Buffer,
    /// Layers of the hit image: faces of the light view × sheets. Triangles and
    /// neighbours never cross a layer.
    pub layers: u32,
    /// Faces of the light view (1, or 6 for a light inside the generator's bounds).
    pub faces: u32,
    /// Sheets: specular paths a texel's light may take (1 on the default path).
    pub sheets: u32,
    /// Valid-hit counters to report beyond the reasons: (counter index, name).
    order_counters: Vec<(usize, String)>,
    /// Texels per side of each face.
    pub resolution: u32,
    /// The distance maps' reference point: the generator's centre (m).
    pub center: Vec3,
    /// How far from `center` a receiver can lie (m).
    pub reach: f32,
    /// The generator (object index).
    pub generator: usize,
    /// The light (index into the scene's lights).
    pub light: usize,
    /// The texel size of the light view (m, or tan units for perspective faces).
    pub texel_size: f32,
    bytes: u64,
    /// The hit images' bytes in the device's memory ledger (the textures hold theirs).
    _hits_memory: Reservation,
}

impl PhotonHits {
    /// The hit images of the renderer's scene: one per light and caustic generator
    /// (§4.1: "each caustics generator is rendered from the point of view of each light
    /// source"), light-major. Pass names start with `method` ("<method>/trace_photons",
    /// the same for every pair, so a pass's time is that of all of them).
    pub fn for_scene(
        ctx: &GpuContext,
        renderer: &Renderer,
        method: &'static str,
        config: &PhotonHitConfig,
    ) -> Result<Vec<Self>, MethodError> {
        let scene = &renderer.scene().scene;
        let generators = caustic_generators(scene).map_err(|reason| MethodError::Unsupported {
            method,
            scene: scene.name.clone(),
            reason,
        })?;
        let mut out = Vec::new();
        for light in 0..scene.lights.len() {
            for &(index, kind) in &generators {
                out.push(Self::new(
                    ctx, renderer, method, config, light, index, kind,
                )?);
            }
        }
        Ok(out)
    }

    /// Builds the light G-buffer, the two distance maps and the tracing pass of light
    /// `light` and generator `index` (of kind `kind`).
    fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        method: &'static str,
        config: &PhotonHitConfig,
        light: usize,
        index: usize,
        kind: GeneratorKind,
    ) -> Result<Self, MethodError> {
        let gpu_scene = renderer.scene();
        let scene = &gpu_scene.scene;
        let g = Generator::locate(gpu_scene, method, index, kind)?;
        // The paper renders the generator from the light: every texel looks at it.
        let view = LightView::fit_sphere(
            &scene.lights[light],
            g.center,
            g.radius,
            &scene.bounds(),
            config.resolution,
        );
        let tan_half = view.tan_half_fov;
        let device = &ctx.device;
        // The hit images (one per face and sheet) against the device's largest storage
        // binding and the memory budget, before the light G-buffer and maps are made.
        let (sheet_count, _) = sheets(kind, config);
        let faces = view.faces.len() as u64;
        let texels = faces * u64::from(sheet_count) * u64::from(config.resolution).pow(2);
        let limit = |e: GpuError| MethodError::Param {
            method,
            message: e.to_string(),
        };
        let raise = format!(
            "lower resolution (at most {} hits per generator on this device; every face and sheet is an image of resolution^2)",
            ctx.limits.storage_elements(HIT_BYTES)
        );
        let what = format!(
            "resolution: the photon hit images ({faces} face(s) x {sheet_count} sheet(s) x {r}x{r} hits of {HIT_BYTES} bytes)",
            r = config.resolution
        );
        let hits_memory = ctx
            .reserve_storage(&what, texels * HIT_BYTES, &raise)
            .map_err(limit)?;
        // The light G-buffer (resolution² a face) and the distance maps
        // (distance_map_size² a face) are textures: their sides are checked here, naming
        // the parameter; their bytes are reserved as they are made.
        let r = config.resolution;
        ctx.limits
            .texture(
                &format!("resolution: the light G-buffer ({r}x{r} a face)"),
                r,
                r,
                "lower resolution",
            )
            .map_err(limit)?;
        let d = config.distance_map_size;
        ctx.limits
            .texture(
                &format!("distance_map_size: the distance maps ({d}x{d} a face)"),
                d,
                d,
                "lower distance_map_size",
            )
            .map_err(limit)?;
        let (light_gbuffer, maps, uniform, hits, counters) =
            ctx.checked("photon hits setup", || -> Result<_, GpuError> {
                // §4.1: the first surface the light meets in each texel of its view.
                let light_gbuffer = renderer.gbuffer_pass().light_gbuffer(ctx, &view)?;
                // §3: where a refracted ray leaves the generator and lands on a receiver.
                let maps = DistanceMaps::new(ctx, gpu_scene, &g, config.distance_map_size)?;
                let faces = light_gbuffer.layers();
                let uniform = g.trace_uniform(&view, tan_half, config, light, faces, &maps);
                let texels = (faces * uniform.paths[1]) as u64
                    * config.resolution as u64
                    * config.resolution as u64;
                Ok((
                    light_gbuffer,
                    maps,
                    uniform_buffer(device, "photon trace params", &uniform),
                    storage_buffer(device, "photon hits", texels * HIT_BYTES, false),
                    storage_buffer(device, "photon trace counters", 4 * COUNTERS as u64, true),
                ))
            })??;
        // §4.1: each texel's light reflected or refracted through the generator onto
        // the receiver it lands on.
        let shader = Shader::new(ctx, "photon-hits trace.wgsl", trace_source())?;
        // Built once per scene and shared; the ledger counts it with the scene.
        let bvh = gpu_scene.triangle_bvh(ctx)?;
        let light_views = [
            &light_gbuffer.position,
            &light_gbuffer.normal,
            &light_gbuffer.ids,
        ]
        .map(|t| t.array_view());
        // An open refractor has no generator map; the shader never reads it then.
        let generator_map = maps.generator.as_ref().unwrap_or(&maps.receivers);
        let trace = ComputePass::builder(ctx, &format!("{method}/trace_photons"), &shader)
            .frame(renderer)
            .bind(
                1,
                &[
                    ("tu", &uniform),
                    ("light_position", &light_views[0]),
                    ("light_normal", &light_views[1]),
                    ("light_ids", &light_views[2]),
                    ("generator_map", &generator_map.normal_distance.view),
                    ("generator_ids", &generator_map.object_ids.view),
                    ("receiver_map", &maps.receivers.normal_distance.view),
                    ("receiver_ids", &maps.receivers.object_ids.view),
                    ("hits", &hits),
                    ("trace_counters", &counters),
                ],
            )
            .bind(
                BVH_GROUP,
                &[("bvh_nodes", &bvh.nodes), ("bvh_triangles", &bvh.triangles)],
            )
            .kernels(&["trace_photons"])
            .build()?;
        let bytes =
            light_gbuffer.bytes() + maps.bytes() + hits.size() + counters.size() + uniform.size();
        let (sheets, reflected) = sheets(g.kind, config);
        let faces = light_gbuffer.layers();
        let bounce_orders = match g.kind {
            GeneratorKind::OpenRefractor => 0,
            _ => config.bounces,
        };
        let order_counters = reflected
            .map(|_| {
                (
                    COUNTER_REFLECTED,
                    "photon_hits_fresnel_reflection".to_string(),
                )
            })
            .into_iter()
            .chain((1..=bounce_orders).map(|k| {
                (
                    COUNTER_REFLECTED + k as usize,
                    format!("photon_hits_bounce_{k}"),
                )
            }))
            .chain(
                config
                    .silhouette_hits
                    .then(|| (COUNTER_EDGE, "photon_hits_silhouette".to_string())),
            )
            .chain(
                (config.bounces > 0).then(|| (COUNTER_CHAINED, "photon_hits_chained".to_string())),
            )
            .collect();
        Ok(Self {
            gbuffer_name: format!("{method}/light_gbuffer"),
            maps_name: format!("{method}/distance_maps"),
            layers: faces * sheets,
            faces,
            sheets,
            order_counters,
            reach: maps.receivers.reach,
            light_gbuffer,
            maps,
            trace,
            hits,
            counters,
            resolution: config.resolution,
            center: g.center,
            generator: g.index,
            light,
            texel_size: view.texel_size,
            bytes,
            _hits_memory: hits_memory,
        })
    }

    /// Texels of the photon hit image (all faces and sheets).
    pub fn texels(&self) -> u32 {
        self.layers * self.resolution * self.resolution
    }

    /// Texels of the light view (all faces): one tracing invocation each.
    pub fn light_texels(&self) -> u32 {
        self.faces * self.resolution * self.resolution
    }

    /// Records the light G-buffer, the two distance maps (rebuilt every frame, as
    /// for a dynamic scene) and the tracing pass.
    pub fn record(&self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        renderer.gbuffer_pass().record(
            frame,
            &self.gbuffer_name,
            renderer.scene(),
            &self.light_gbuffer,
        )?;
        self.maps.record(frame, &self.maps_name)?;
        frame.encoder.clear_buffer(&self.counters, 0, None);
        let mut pass = self.trace.begin(frame)?;
        pass.dispatch("trace_photons", [self.light_texels().div_ceil(64), 1, 1])?;
        Ok(())
    }

    /// Counters of the last frame: texels, valid hits and why the others are invalid.
    pub fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let c = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.counters,
            self.counters.size(),
            "photon trace counters",
        )?;
        let mut out = Counters::new();
        out.insert("photon_texels".into(), self.texels() as u64);
        for ((_, name), v) in HIT_REASONS.iter().zip(&c) {
            out.insert((*name).into(), *v as u64);
        }
        for (index, name) in &self.order_counters {
            out.insert(name.clone(), c[*index] as u64);
        }
        Ok(out)
    }

    /// Reads the hit image back (tests and figures; never on the hot path).
    pub fn read_hits(&self, ctx: &GpuContext) -> Result<Vec<PhotonHit>, MethodError> {
        let bytes = caustics_gpu::readback::read_buffer_bytes(
            ctx,
            &self.hits,
            self.hits.size(),
            "photon hits",
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Bytes of GPU memory owned.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

/// Adds `more` into `total`, counter by counter (the (light, generator) pairs' counts).
pub fn add_counters(total: &mut Counters, more: Counters) {
    for (name, v) in more {
        *total.entry(name).or_insert(0) += v;
    }
}

/// `PhotonHit` of types.wgsl, as read back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct PhotonHit {
    /// Landing point (m) and its distance from the map centre (0: invalid).
    pub position: [f32; 4],
    /// Receiver normal towards the arriving light; w: texel footprint (m²).
    pub normal: [f32; 4],
    /// Flux (W) per channel; w unused.
    pub flux: [f32; 4],
    /// Receiver object (`u32::MAX` if invalid), path id, invalid reason, unused.
    pub ids: [u32; 4],
}

impl PhotonHit {
    /// Whether the texel holds a photon landing on a receiver.
    pub fn valid(&self) -> bool {
        self.ids[0] != u32::MAX
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_method::MethodParams;

    #[test]
    fn shaders_validate() -> Result<(), String> {
        let kernel_user = format!(
            "@group(1) @binding(0) var<uniform> cm: CausticMapUniform;\n{SPLAT_KERNEL_WGSL}"
        );
        shader::validate_wgsl("splat_kernel.wgsl", &compose(&kernel_user))?;
        shader::validate_wgsl("trace.wgsl", &trace_source())?;
        shader::validate_wgsl("lookup.wgsl", &compose(LOOKUP_WGSL))
    }

    #[test]
    fn structs_match_their_wgsl() {
        caustics_gpu::assert_wgsl_layout!(
            trace_source(),
            TraceUniform {
                faces,
                resolution,
                generator,
                flags,
                center,
                generator_center,
                view,
                paths,
                clip_to_world
            }
        );
        caustics_gpu::assert_wgsl_layout!(
            trace_source(),
            PhotonHit {
                position,
                normal,
                flux,
                ids
            }
        );
    }

    #[test]
    fn counter_names_follow_the_wgsl_constants() {
        for (index, (constant, _)) in HIT_REASONS.iter().enumerate() {
            assert_eq!(
                caustics_gpu::layout::wgsl_u32_constant(TYPES_WGSL, constant).ok(),
                Some(index as u32),
                "{constant}"
            );
        }
    }

    /// Every counter [`PhotonHits::counters`] can report has a doc, and every doc is
    /// of one it reports.
    #[test]
    fn every_counter_is_documented() {
        let mut names: Vec<String> = HIT_REASONS.iter().map(|(_, n)| (*n).into()).collect();
        names.push("photon_texels".into());
        names.push("photon_hits_fresnel_reflection".into());
        names.push("photon_hits_silhouette".into());
        names.push("photon_hits_chained".into());
        names.extend((1..=MAX_BOUNCES).map(|k| format!("photon_hits_bounce_{k}")));
        if let Err(e) = caustics_method::CounterDoc::check(COUNTER_DOCS, &names) {
            panic!("{e}");
        }
    }

    #[test]
    fn counters_buffer_follows_the_wgsl_constants() {
        let wgsl = trace_source();
        let constant = |name| caustics_gpu::layout::wgsl_u32_constant(&wgsl, name).ok();
        assert_eq!(
            constant("COUNTER_REFLECTED"),
            Some(COUNTER_REFLECTED as u32)
        );
        assert_eq!(
            constant("COUNTER_BOUNCE"),
            Some(COUNTER_REFLECTED as u32 + 1)
        );
        assert!(HIT_REASONS.len() <= COUNTER_REFLECTED);
        // The silhouette hits' counter: the slot after the reasons, before the orders.
        assert_eq!(constant("HIT_EDGE"), Some(COUNTER_EDGE as u32));
        assert!(HIT_REASONS.len() <= COUNTER_EDGE && COUNTER_EDGE < COUNTER_REFLECTED);
        assert_eq!(constant("COUNTER_CHAINED"), Some(COUNTER_CHAINED as u32));
        // Every order of a path fits below the reflection's path id.
        assert!(MAX_BOUNCES < constant("PATH_REFLECTED").unwrap_or(0));
        assert_eq!(
            PhotonHitConfig::specs()
                .iter()
                .find(|s| s.name == "bounces")
                .and_then(|s| s.range),
            Some(closed(0.0, MAX_BOUNCES as f64))
        );
    }

    #[test]
    fn sheets_follow_the_light_paths() {
        let paper = PhotonHitConfig::default();
        let extended = PhotonHitConfig {
            bounces: 2,
            reflections: true,
            ..paper.clone()
        };
        use GeneratorKind::*;
        for (kind, config, want) in [
            (ClosedRefractor, &paper, (1, None)),
            (ClosedRefractor, &extended, (4, Some(3))),
            (OpenRefractor, &paper, (1, None)),
            (OpenRefractor, &extended, (2, Some(1))),
            (Mirror, &extended, (1, None)),
        ] {
            assert_eq!(sheets(kind, config), want, "{kind:?} {config:?}");
        }
    }

    #[test]
    fn bad_config_names_the_parameter() {
        let good = PhotonHitConfig {
            resolution: 128,
            distance_map_size: 256,
            cube_size: 512,
            distance_test: true,
            distance_tolerance: 0.05,
            bounces: 0,
            reflections: false,
            silhouette_hits: false,
        };
        assert!(good.check().is_ok());
        for (bad, needle) in [
            (
                PhotonHitConfig {
                    resolution: 1,
                    ..good
                },
                "resolution",
            ),
            (
                PhotonHitConfig {
                    distance_map_size: 8,
                    ..good
                },
                "distance_map_size",
            ),
            (
                PhotonHitConfig {
                    cube_size: 4096,
                    ..good
                },
                "cube_size",
            ),
            (
                PhotonHitConfig {
                    distance_tolerance: 0.0,
                    ..good
                },
                "distance_tolerance",
            ),
            (
                PhotonHitConfig {
                    bounces: MAX_BOUNCES + 1,
                    ..good
                },
                "bounces",
            ),
        ] {
            let msg = bad.check().expect_err(needle);
            assert!(msg.contains(needle), "{msg}");
        }
    }
}
