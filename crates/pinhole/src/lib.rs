//! `pinhole`: Wand & Straßer (2003), "Real-Time Caustics", as a caustics-bench method.
//!
//! The caustic generator is discretized into point samples ([`sampling`]), each a
//! pinhole camera that projects the light, held in a cube environment map
//! ([`light_map`]), onto the receivers. Per receiver pixel (camera G-buffer), a
//! fragment loop over the samples reflects (mirror) or refracts (glass sphere, in and
//! out) the vector from the receiver to the sample, looks up the map and adds
//!
//! ```text
//! E(x) += L_light(lookup) · R · cos θ_s · cos θ_x · A_s / (d² + ε)
//! ```
//!
//! with R the mirror's reflectance or the product of the two exact Fresnel
//! transmittances, A_s the area the sample stands for and ε = `epsilon_scale` · A_s
//! (the paper's "diameter of the sample's region, squared"); the pixel's radiance is
//! ρ/π · E, in DESIGN units. With `filtering` on, the lookup averages the map over
//! the footprint of the sample's patch, from differential point samples (principal
//! curvatures), as the paper does with `texldd`: mip level from the footprint's minor
//! axis and up to 16 probes along its major axis (footprint assembly, done in the
//! shader because lavapipe ignores explicit gradients on cube maps).
//!
//! What is exact and what is not:
//! * exact: the radiometry of one sample (the irradiance through a small mirror or
//!   lens patch, up to the ε term and first order in the patch size), the Fresnel
//!   terms, the visibility of the receiver→sample segment and of the sample→light
//!   segment (tested against the scene's analytic objects, which the paper omits);
//! * converging with the sample count: the sum over samples is a quadrature of the
//!   integral over the generator's surface; unfiltered it shows the discrete images of
//!   the light (the paper's aliasing), filtered it blurs each image over its patch;
//! * an approximation that stays: the light has a size. A point/spot light is a disc
//!   of radius ρ = D·tan(`light_angle`) facing the cube map's centre (the generator's
//!   centre, at distance D), with the radiance that sends the light's intensity to each
//!   sample; a directional light a cone of half angle `light_angle`. The caustic is the
//!   one of that extended light (blurred by about ρ), where the reference uses a true
//!   point. The map is parallax-corrected (lookup = where the ray meets the disc's
//!   plane, minus the centre), so one map serves every sample though the ring's light
//!   is close to the ring; the paper's "light far away" assumption is not needed.
//!   The map is the light's cube map in a frame aimed at the light, whose one
//!   non-empty face is stored and addressed in the shader ([`light_map`]).
//! * the footprint: the paper differences at distance r = half the sample spacing on
//!   one side; we take central differences at ±r, so the footprint spans the sample's
//!   whole patch and neighbouring footprints tile. `filtering=full` (default) moves the
//!   point and its normal, as the paper; `filtering=curvature` moves the normal only
//!   (zero footprint on a flat mirror); `filtering=off` point-samples level 0.
//!
//! A sphere light (`"type": "sphere"`) is the disc of its own radius r at its centre,
//! facing the generator (its half angle atan(r/D) replaces `light_angle`), of radiance
//! L/cos β: the sphere's, with its constant projected area. So pinhole renders extended
//! sphere lights at no extra cost, as the paper says of extended lights (§5).
//! An environment light (Fig. 6, "natural light") is its own lat-long map: the lookup
//! is the direction leaving the generator, the map is filtered over the same footprint
//! (in its (u, v), across the seam the short way), and the sky's visibility along that
//! direction is traced per pair (the paper tests no light visibility, §5); the sky
//! lights every side of a mirror, so the lit side is the receiver's ([`light_map`]).
//!
//! Supports lights of any kind, any number of them (one map each, both passes once per
//! light into the same caustic: [`Pinhole`]), and one caustic generator: a mirror of any shape
//! (sphere, open cylinder as Wand's ring, quad, triangle mesh, heightfield), a
//! dielectric sphere (in and out: two refractions, the special case whose exit point is
//! analytic), or an open dielectric surface (a heightfield, a quad, an open cylinder):
//! one refraction, the paper's "single refractive interaction in the light path, such
//! as underwater scenes" (§5). There the radiance on the receiver's side is (1 - F)·η²
//! times the light's (radiance scales with the squared index; the flux does not). Meshes
//! and heightfields are sampled on their triangles, with curvature from the triangles'
//! vertex normals ([`sampling`]); visibility is traced against the analytic objects and
//! the scene's triangle BVH (`caustics_gpu::triangle_bvh`), so any object may be a
//! receiver or an occluder. It renders one specular event per path, as the paper
//! (§5: "only one specular bounce can be handled. This seems to be an inherent
//! restriction"): a glass mesh (in and out) and a second specular object are declined
//! with that sentence; light reflected twice inside the ring is missing, and so, by
//! default (the paper's), is the light a dielectric reflects: `reflections` adds it,
//! each sample also a mirror of Fresnel reflectance F (one specular bounce, which the
//! technique handles); no volume caustics.

pub mod light_map;
pub mod sampling;

use bytemuck::{Pod, Zeroable};
use caustics_gpu::limits::Reservation;
use caustics_gpu::pass::{ComputePass, RasterPass, Shader};
use caustics_gpu::textures::{additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GpuContext, Renderer, shader};
use caustics_method::params::{above, closed};
use caustics_method::{
    Capabilities, CausticsMethod, CounterDoc, Counters, Method, MethodError, Unsupported,
    method_params,
};
use caustics_scene::{Light, Material, Scene, Shape, Vec3};
use serde::{Deserialize, Serialize};

pub use light_map::LightMap;
pub use sampling::{PointSample, Strategy};

const TYPES_WGSL: &str = include_str!("types.wgsl");
const PREPARE_WGSL: &str = include_str!("prepare.wgsl");
const GATHER_WGSL: &str = include_str!("gather.wgsl");

/// Group of both passes that holds the scene's triangle BVH (visibility).
const BVH_GROUP: u32 = 2;

/// A pass's full WGSL: shared GPU files, the scene's BVH, pinhole's types, then the pass.
fn pass_source(pass: &str) -> String {
    shader::compose_method(&format!(
        "{}\n{TYPES_WGSL}\n{pass}",
        caustics_gpu::triangle_bvh::wgsl(BVH_GROUP)
    ))
}

/// Registry name.
pub const NAME: &str = "pinhole";

/// How the projected light is filtered (§3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Filtering {
    /// Point lookups (bilinear on level 0): the paper's "no filtering".
    Off,
    /// Footprint from the change of the normal alone (zero on flat mirrors).
    Curvature,
    /// Footprint from the change of point and normal (the paper's finite differences).
    #[default]
    Full,
}

impl Filtering {
    /// `PINHOLE_FILTERING` of types.wgsl.
    fn code(self) -> u32 {
        match self {
            Filtering::Off => 0,
            Filtering::Curvature => 1,
            Filtering::Full => 2,
        }
    }
}

caustics_method::param_enum!(
    Strategy,
    [
        Strategy::Random,
        Strategy::Grid,
        Strategy::Quantized,
        Strategy::NeighborRemoval
    ]
);
caustics_method::param_enum!(
    Filtering,
    [Filtering::Off, Filtering::Curvature, Filtering::Full]
);

method_params! {
    /// Parameters of `pinhole` (defaults: the paper's choices).
    pub struct PinholeParams {
        /// random | grid | quantized | neighbor_removal (the paper's §3.2)
        sampling: Strategy = Strategy::NeighborRemoval;
        /// number of point samples on the generator (paper: 100, 1000, 10000; at most
        /// 100000: every receiver pixel loops over all of them, and the CPU sampler
        /// draws 8 candidates per sample)
        samples: u32 = 1000 => closed(1.0, 100_000.0);
        /// seed of the sample generator
        seed: u32 = 1 => closed(0.0, u32::MAX as f64);
        /// off | curvature | full: textureSampleGrad footprint of each sample's patch (§3.3)
        filtering: Filtering = Filtering::Full;
        /// angular radius (rad) of the light in the cube map, seen from the generator's
        /// centre (paper: 0.016; at most 0.5 rad = 29°: the one stored face holds cones
        /// under 45°, and a light that wide is no longer the paper's small source)
        light_angle: f64 = 0.016 => above(0.0, MAX_LIGHT_ANGLE as f64);
        /// cube map face size in texels (power of two, 8 to 2048: a 2048² R16F map with
        /// mips is 11 MB)
        cube_size: u32 = 256 => closed(8.0, 2048.0);
        /// eps = epsilon_scale x A_s is added to d^2 (paper: 1, the sample diameter
        /// squared; 0 would leave the 1/d² singularity unguarded, and beyond 100 the
        /// guard outweighs d² over the whole near field)
        epsilon_scale: f64 = 1.0 => above(0.0, 100.0);
        /// samples per gather instance (additive passes; 1 to 4096)
        samples_per_pass: u32 = 64 => closed(1.0, 4096.0);
        /// also project the Fresnel reflection off a dielectric generator: each sample a second pinhole, a mirror of reflectance F (one specular bounce, within the paper's technique; the paper does not; a second path per sample and pixel)
        reflections: bool = false;
    }
    check = |p: &PinholeParams| {
        if p.cube_size.is_power_of_two() {
            Ok(())
        } else {
            Err(format!(
                "cube_size: expected a power of two in [8, 2048], got {}",
                p.cube_size
            ))
        }
    };
}

impl Method for Pinhole {
    type Params = PinholeParams;
    const NAME: &'static str = NAME;
    const SUMMARY: &'static str = "reflector point samples as pinhole cameras projecting the light's cube map, 4 sampling strategies, curvature-based anisotropic filtering";
    const SOURCE: &'static str =
        "Wand & Straßer 2003, Real-Time Caustics (wand-strasser-2003-real-time-caustics.txt)";
    const CAPABILITIES: Capabilities = Capabilities {
        surface: true,
        volume: false,
        reflection: true,
        refraction: true,
        multiple_bounces: false,
        directional_light: true,
        point_light: true,
        spot_light: true,
        sphere_light: true,
        environment_light: true,
        no_medium_in_paper: "Wand & Stra\u{df}er leave volume caustics to future work (§5: \u{201c}The algorithm could also be combined with volume rendering (using textured slices) to obtain volumetric caustics.\u{201d}); the paper's gather has no extinction along the light path either",
    };
    const COUNTERS: &'static [CounterDoc] = COUNTER_DOCS;

    fn check_scene(scene: &Scene, _params: &PinholeParams) -> Result<(), Unsupported> {
        check_scene(scene)
    }

    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &PinholeParams,
    ) -> Result<Box<dyn CausticsMethod>, MethodError> {
        Ok(Box::new(Pinhole::new(ctx, renderer, params)?))
    }
}

/// Wand & Straßer's own words on the limit every decline of a second specular event
/// quotes (§5).
pub const ONE_BOUNCE: &str = "Wand & Straßer, §5: \"only one specular bounce can be handled. This seems to be an inherent restriction. Except from special cases, it seems not to be possible to handle multiple specular interactions on a light path with our technique\"";

/// How pinhole follows the light through the generator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeneratorMode {
    /// One reflection (a mirror of any shape).
    Mirror,
    /// In and out of a glass sphere: two refractions, the special case whose exit point
    /// is analytic.
    SphereRefraction,
    /// One refraction at an open dielectric surface (water, a glass quad): the paper's
    /// "single refractive interaction in the light path, such as underwater scenes"
    /// (§5).
    SurfaceRefraction,
}

impl GeneratorMode {
    /// `PINHOLE_MODE` of types.wgsl.
    fn code(self) -> u32 {
        match self {
            GeneratorMode::Mirror => 0,
            GeneratorMode::SphereRefraction => 1,
            GeneratorMode::SurfaceRefraction => 2,
        }
    }
}

/// The scene's one caustic generator and how its light is followed, or why `pinhole`
/// cannot render the scene. Any object may be a receiver or an occluder (visibility is
/// traced through the scene's analytic shapes and its triangle BVH).
pub fn caustic_generator(scene: &Scene) -> Result<(usize, GeneratorMode), Unsupported> {
    if scene.lights.is_empty() {
        return Err(Unsupported("the scene has no light".into()));
    }
    let mut generator = None;
    for (i, o) in scene.objects.iter().enumerate() {
        let material = scene.material(o);
        let mode = match (material, &o.shape) {
            (Material::Diffuse { .. }, _) => continue,
            (Material::Mirror { .. }, _) => GeneratorMode::Mirror,
            (Material::Dielectric { .. }, Shape::Sphere { .. }) => GeneratorMode::SphereRefraction,
            (
                Material::Dielectric { .. },
                Shape::Quad { .. } | Shape::Heightfield(_) | Shape::Cylinder { .. },
            ) => GeneratorMode::SurfaceRefraction,
            (Material::Dielectric { .. }, Shape::Mesh(_)) => {
                return Err(Unsupported(format!(
                    "objects[{i}] is a dielectric mesh, which light enters and leaves: two specular events per path ({ONE_BOUNCE}; the glass sphere is the special case pinhole handles, its exit point being analytic)"
                )));
            }
        };
        if let Some((first, _)) = generator {
            return Err(Unsupported(format!(
                "objects[{first}] and objects[{i}] are both specular; pinhole follows one specular object ({ONE_BOUNCE})"
            )));
        }
        generator = Some((i, mode));
    }
    generator.ok_or_else(|| Unsupported("the scene has no specular object".into()))
}

fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    let (g, _) = caustic_generator(scene)?;
    let bounds = scene.objects[g].shape.bounds();
    for (l, light) in scene.lights.iter().enumerate() {
        if let Light::Sphere {
            position, radius, ..
        } = *light
        {
            let d = position.distance(bounds.center());
            if d <= radius + bounds.bounding_sphere_radius() {
                return Err(Unsupported(format!(
                    "the sphere light lights[{l}] reaches into the generator's bounds: its disc in the map would hold the generator"
                )));
            }
            if (radius / d).atan() > MAX_LIGHT_ANGLE {
                return Err(Unsupported(format!(
                    "the sphere light lights[{l}] spans {:.3} rad around the map's axis seen from the generator: the map's one face holds up to {MAX_LIGHT_ANGLE} rad (the light_angle bound)",
                    (radius / d).atan()
                )));
            }
        }
        if let Light::Point { position, .. } | Light::Spot { position, .. } = *light
            && position.distance(bounds.center()) < 1e-3
        {
            return Err(Unsupported(format!(
                "lights[{l}] sits at the generator's centre, where the cube map is centred"
            )));
        }
    }
    Ok(())
}

/// Largest half angle of the light's disc in the map (rad): `light_angle`'s bound, and
/// a sphere light's atan(r/D).
const MAX_LIGHT_ANGLE: f32 = 0.5;

/// Matches `Sample` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSample {
    pos: [f32; 4],
    normal: [f32; 4],
    t1: [f32; 4],
    t2: [f32; 4],
    extra: [f32; 4],
}

/// Matches `Params` in types.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuParams {
    generator: u32,
    light_index: u32,
    sample_count: u32,
    batch_size: u32,
    map_center: [f32; 4],
    map_axis: [f32; 4],
    map_u: [f32; 4],
    map_v: [f32; 4],
    light_scale: [f32; 4],
    env_scale: [f32; 4],
}

/// The cube map's geometry for a light: centre, disc axis, disc radius (m; 0 for a
/// directional light), the map's cone half angle and the disc's radiance per unit
/// light power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightDisc {
    /// Centre of the cube map (point/spot: the generator's centre).
    pub center: Vec3,
    /// Unit axis of the light's cone in the map.
    pub axis: Vec3,
    /// Disc radius in metres (point/spot), 0 for a directional light.
    pub radius: f32,
    /// Half angle of the cone in the map (rad).
    pub alpha: f32,
    /// Radiance per W/sr (point/spot: 1/(π ρ²)) or per W/m² (directional: 1/Ω).
    pub radiance_per_power: f32,
}

impl LightDisc {
    /// The disc of `light` for a generator centred at `center`, `alpha` radians wide.
    pub fn new(light: &Light, center: Vec3, alpha: f32) -> Self {
        match *light {
            Light::Directional { direction, .. } => {
                let solid_angle = std::f32::consts::TAU * (1.0 - alpha.cos());
                Self {
                    center,
                    axis: -direction,
                    radius: 0.0,
                    alpha,
                    radiance_per_power: 1.0 / solid_angle,
                }
            }
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                let to = position - center;
                let d = to.length();
                let radius = d * alpha.tan();
                Self {
                    center,
                    axis: to / d,
                    radius,
                    alpha,
                    radiance_per_power: 1.0 / (std::f32::consts::PI * radius * radius),
                }
            }
            // A sphere light is the disc it shows: radius r, facing the generator
            // (`light_angle` does not apply); the disc's radiance I/(π r² cos β) with
            // I = π r² L is L/cos β, the cos β giving back the sphere's constant
            // projected area seen from any sample.
            Light::Sphere {
                position, radius, ..
            } => {
                let to = position - center;
                let d = to.length();
                Self {
                    center,
                    axis: to / d,
                    radius,
                    alpha: (radius / d).atan(),
                    radiance_per_power: 1.0 / (std::f32::consts::PI * radius * radius),
                }
            }
            // Declined by the capability check (no environment map yet): a black disc.
            Light::Environment { .. } => Self {
                center,
                axis: Vec3::Y,
                radius: 0.0,
                alpha,
                radiance_per_power: 0.0,
            },
        }
    }
}

/// What each counter of `pinhole` counts ([`Method::COUNTERS`]). The gather pass
/// counts only in the count frame (the last one), whose counts are reported.
#[rustfmt::skip]
const COUNTER_DOCS: &[CounterDoc] = &[
    CounterDoc { name: "samples", doc: "point samples on the caustic generator, each a pinhole camera projecting the light map (the samples parameter)" },
    CounterDoc { name: "passes", doc: "additive gather passes per frame (instances of a fullscreen triangle), each looping over samples_per_pass samples: samples / samples_per_pass, rounded up, per light" },
    CounterDoc { name: "camera_pixels", doc: "pixels of the camera image (width x height), each covered by every gather pass: set by the scene, not counted on the GPU" },
    CounterDoc { name: "receiver_fragments", doc: "gather fragments on a diffuse receiver pixel in the count frame, over all passes (pixels that see a diffuse surface x passes; the others are discarded)" },
    CounterDoc { name: "sample_pixel_pairs", doc: "(receiver pixel, sample) pairs the gather loop evaluated in the count frame: diffuse receiver pixels x samples x lights (with reflections each pair also evaluates the reflected path, counted once)" },
    CounterDoc { name: "texture_fetches", doc: "light-map probes taken in the count frame: 1 per lookup whose filter footprint is within a texel (always, with filtering off), up to 16 along an anisotropic filter footprint, none for a pair culled as facing away, without a path or outside the light map's face (both paths with reflections); the visibility test comes after the lookup, so an occluded pair's probes count" },
    CounterDoc { name: "visibility_tests", doc: "receiver-to-sample segments traced against the scene in the count frame: only the pairs whose lookup lands on the light (the others add nothing whether occluded or not); visibility_tests / sample_pixel_pairs is the share the gather pays a ray for" },
];

/// `pinhole` bound to one scene.
///
/// The paper's light is one environment map of the incoming light; with several
/// lights each gets its own map (the light's cube map in a frame aimed at it, or an
/// environment's lat-long map) and the two passes run once per light into the same
/// caustic: the maps' sum is the paper's one map, kept apart so each light's disc
/// keeps the map's whole resolution.
pub struct Pinhole {
    /// The passes of the scene's lights that are not environments, and of those that
    /// are (each pair specialized on it; built for the kinds the scene has).
    passes: [Option<Passes>; 2],
    /// One per scene light, in the scene's order.
    lights: Vec<PinholeLight>,
    counters: wgpu::Buffer,
    sample_count: u32,
    batches: u32,
    receiver_pixels_hint: u64,
    bytes: u64,
    /// The sample buffers, held in the device's memory ledger while the passes' bind
    /// groups use them.
    _memory: Reservation,
}

/// Both passes, specialized for one kind of light ([`specialization`]).
struct Passes {
    prepare: ComputePass,
    gather: RasterPass,
}

/// The pipeline-overridable constants of both passes (types.wgsl): what the gather's
/// loop would otherwise branch on per fragment.
fn specialization(
    mode: GeneratorMode,
    params: &PinholeParams,
    environment: bool,
) -> [(&'static str, f64); 4] {
    [
        ("PINHOLE_MODE", f64::from(mode.code())),
        ("PINHOLE_FILTERING", f64::from(params.filtering.code())),
        (
            "PINHOLE_REFLECTIONS",
            f64::from(u8::from(params.reflections)),
        ),
        ("PINHOLE_ENVIRONMENT", f64::from(u8::from(environment))),
    ]
}

/// One light's map, what each sample sees of it, and its groups of both passes.
struct PinholeLight {
    /// Whether it is an environment light (which pair of [`Pinhole::passes`] it uses).
    environment: bool,
    prepare_group: wgpu::BindGroup,
    gather_group: wgpu::BindGroup,
    /// The light map (in the device's memory ledger while the groups use it).
    _map: LightMap,
}

/// The GPU form of the samples, with ε and the finite-difference step filled in.
fn gpu_samples(samples: &[PointSample], epsilon_scale: f32) -> Vec<GpuSample> {
    samples
        .iter()
        .map(|s| {
            let p = &s.point;
            GpuSample {
                pos: p.position.extend(s.area).to_array(),
                normal: p.normal.extend(epsilon_scale * s.area).to_array(),
                t1: p.t1.extend(p.k1).to_array(),
                t2: p.t2.extend(p.k2).to_array(),
                extra: [0.5 * s.area.sqrt(), s.displacement, 0.0, 0.0],
            }
        })
        .collect()
}

/// The uniform of both passes for the scene light `light_index`: the generator, the
/// batching and the light map's frame.
fn gpu_params(
    params: &PinholeParams,
    generator: u32,
    sample_count: u32,
    light_index: usize,
    disc: &LightDisc,
) -> GpuParams {
    let (map_u, map_v) = caustics_scene::perpendicular_frame(disc.axis);
    GpuParams {
        generator,
        light_index: light_index as u32,
        sample_count,
        batch_size: params.samples_per_pass,
        map_center: disc.center.extend(0.0).to_array(),
        map_axis: disc.axis.extend(disc.radius).to_array(),
        map_u: map_u.extend(0.0).to_array(),
        map_v: map_v.extend(0.0).to_array(),
        light_scale: [disc.radiance_per_power, disc.alpha.cos(), 0.0, 0.0],
        env_scale: [0.0; 4],
    }
}

/// The buffers the passes share: the samples and the counters (every light's gather
/// adds to them).
struct Buffers {
    samples: wgpu::Buffer,
    counters: wgpu::Buffer,
}

/// One light's buffers: its uniform and the light each sample sees of it.
struct LightBuffers {
    params: wgpu::Buffer,
    sample_light: wgpu::Buffer,
}

impl Buffers {
    fn new(device: &wgpu::Device, samples: &[GpuSample]) -> Self {
        Self {
            samples: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pinhole samples"),
                contents: bytemuck::cast_slice(samples),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            // receiver fragments, pairs (lo, hi), texture fetches (lo, hi), visibility
            // tests (lo, hi): gather.wgsl.
            counters: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pinhole counters"),
                size: 32,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        }
    }

    fn bytes(&self) -> u64 {
        self.samples.size() + self.counters.size()
    }
}

impl LightBuffers {
    fn new(device: &wgpu::Device, params: &GpuParams, sample_count: u32) -> Self {
        Self {
            params: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pinhole params"),
                contents: bytemuck::bytes_of(params),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            sample_light: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pinhole sample light"),
                size: u64::from(sample_count) * 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
        }
    }

    fn bytes(&self) -> u64 {
        self.params.size() + self.sample_light.size()
    }
}

impl Pinhole {
    /// Samples the scene's generator, builds the light's map and the paper's two
    /// passes: the light seen from each sample, then the gather over all samples per
    /// receiver pixel.
    pub fn new(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &PinholeParams,
    ) -> Result<Self, MethodError> {
        let scene = &renderer.scene().scene;
        let unsupported = |reason| MethodError::Unsupported {
            method: NAME,
            scene: scene.name.clone(),
            reason,
        };
        let (generator, mode) = caustic_generator(scene).map_err(unsupported)?;
        check_scene(scene).map_err(unsupported)?;
        let gpu_scene = renderer.scene();
        let shape = &scene.objects[generator].shape;
        // Meshes and heightfields are sampled on the triangles the rasterizer draws and
        // the BVH traces, so a sample lies exactly on the surface visibility sees.
        let surface = match shape {
            Shape::Mesh(_) | Shape::Heightfield(_) => {
                sampling::Surface::triangles(&gpu_scene.meshes[generator])
            }
            _ => Ok(sampling::Surface::Analytic(shape)),
        }
        .map_err(|e| unsupported(Unsupported(e.to_string())))?;
        let samples = sampling::generate(
            &surface,
            params.sampling,
            params.samples as usize,
            params.seed as u64,
        )
        .map_err(|e| unsupported(Unsupported(e.to_string())))?;
        let centre = surface.bounds().center();
        let sample_count = samples.len() as u32;
        let bvh = gpu_scene.triangle_bvh(ctx)?;
        // The samples (80 bytes each) and the light each sees of each light (16 bytes),
        // bound whole.
        let sample_bytes = 80 + 16 * scene.lights.len() as u64;
        let samples_memory = ctx
            .reserve_storage(
                &format!(
                    "samples: the sample buffers ({sample_count} x {sample_bytes} bytes, {} lights)",
                    scene.lights.len()
                ),
                u64::from(sample_count) * sample_bytes,
                "lower samples",
            )
            .map_err(|e| MethodError::Param {
                method: NAME,
                message: e.to_string(),
            })?;
        let buffers = ctx.checked("pinhole setup", || {
            Buffers::new(
                &ctx.device,
                &gpu_samples(&samples, params.epsilon_scale as f32),
            )
        })?;

        let bvh_bindings: [(&str, &dyn caustics_gpu::pass::Bindable); 2] =
            [("bvh_nodes", &bvh.nodes), ("bvh_triangles", &bvh.triangles)];
        // Pass 1: the light's radiance seen from each sample (one-event generators).
        let prepare_shader = Shader::new(ctx, "pinhole prepare.wgsl", pass_source(PREPARE_WGSL))?;
        // Pass 2: every receiver pixel gathers the light through every sample, one
        // full-screen instance per batch of samples, added into the surface target.
        let gather_shader = Shader::new(ctx, "pinhole gather.wgsl", pass_source(GATHER_WGSL))?;
        // Both passes are specialized on the generator's mode, the filter, the
        // reflections and the kind of light: one pair for the scene's environment lights,
        // one for its other lights (the pipeline cache compiles each once per device).
        let build_passes = |environment: bool| -> Result<Passes, MethodError> {
            let constants = specialization(mode, params, environment);
            let prepare = ComputePass::builder(ctx, "pinhole/prepare_samples", &prepare_shader)
                .frame(renderer)
                .caller_group(1)
                .bind(BVH_GROUP, &bvh_bindings)
                .kernels(&["prepare_samples"])
                .constants(&constants)
                .build()?;
            let gather = RasterPass::builder(ctx, "pinhole/gather", &gather_shader, "vs_gather")
                .frame(renderer)
                .caller_group(1)
                .bind(BVH_GROUP, &bvh_bindings)
                .fragment("fs_gather", &[Some(additive_hdr_target())])
                .constants(&constants)
                .counted()
                .build()?;
            Ok(Passes { prepare, gather })
        };
        let mut passes: [Option<Passes>; 2] = [None, None];

        let mut bytes = buffers.bytes();
        let mut lights = Vec::with_capacity(scene.lights.len());
        for (index, light) in scene.lights.iter().enumerate() {
            let environment = matches!(light, Light::Environment { .. });
            let slot = &mut passes[usize::from(environment)];
            if slot.is_none() {
                *slot = Some(build_passes(environment)?);
            }
            let variant = slot.as_ref().expect("built just above");
            let (prepare_schema, gather_schema) = (
                variant.prepare.caller_schema(1)?,
                variant.gather.caller_schema(1)?,
            );
            let disc = LightDisc::new(light, centre, params.light_angle as f32);
            let mut gpu_params = gpu_params(params, generator as u32, sample_count, index, &disc);
            let (light_buffers, map) = ctx.checked("pinhole setup", || {
                // The light's map: an environment's own lat-long map, else the +Z face
                // of the light's cube map, each with its mip chain.
                let map = match light {
                    Light::Environment { map, scale } => {
                        let (texture, peak) = LightMap::environment(ctx, map)?;
                        gpu_params.env_scale = (*scale * peak).extend(0.0).to_array();
                        texture
                    }
                    _ => LightMap::new(ctx, params.cube_size, disc.alpha)?,
                };
                let light_buffers = LightBuffers::new(&ctx.device, &gpu_params, sample_count);
                Ok::<_, caustics_gpu::GpuError>((light_buffers, map))
            })??;
            let prepare_group = prepare_schema.bind(
                &ctx.device,
                &[
                    ("params", &light_buffers.params),
                    ("samples", &buffers.samples),
                    ("sample_light", &light_buffers.sample_light),
                ],
            )?;
            let gather_group = gather_schema.bind(
                &ctx.device,
                &[
                    ("params", &light_buffers.params),
                    ("samples", &buffers.samples),
                    ("sample_light", &light_buffers.sample_light),
                    ("counters", &buffers.counters),
                    ("light_map", &map.view),
                    ("light_sampler", &map.sampler),
                ],
            )?;
            bytes += light_buffers.bytes() + map.bytes;
            lights.push(PinholeLight {
                environment,
                prepare_group,
                gather_group,
                _map: map,
            });
        }

        let cam = &scene.camera;
        Ok(Self {
            passes,
            lights,
            bytes,
            _memory: samples_memory,
            counters: buffers.counters,
            sample_count,
            batches: sample_count.div_ceil(params.samples_per_pass),
            receiver_pixels_hint: cam.width as u64 * cam.height as u64,
        })
    }
}

impl CausticsMethod for Pinhole {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        frame.encoder.clear_buffer(&self.counters, 0, None);
        let variants = || {
            self.passes
                .iter()
                .zip([false, true])
                .filter_map(|(p, env)| {
                    let lights = self.lights.iter().filter(move |l| l.environment == env);
                    p.as_ref().map(|p| (p, lights))
                })
        };
        for (passes, lights) in variants() {
            let mut pass = passes.prepare.begin(frame)?;
            for light in lights {
                pass.set_bind_group(1, &light.prepare_group, &[]);
                pass.dispatch("prepare_samples", [self.sample_count.div_ceil(64), 1, 1])?;
            }
        }
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        for (passes, lights) in variants() {
            let mut pass = passes.gather.begin(frame, &attachments, None)?;
            for light in lights {
                pass.set_bind_group(1, &light.gather_group, &[]);
                pass.draw(0..3, 0..self.batches);
            }
        }
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let c = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.counters,
            self.counters.size(),
            "pinhole counters",
        )?;
        let wide = |lo: usize| c[lo] as u64 | (c[lo + 1] as u64) << 32;
        let mut out = Counters::new();
        out.insert("samples".into(), self.sample_count as u64);
        out.insert(
            "passes".into(),
            u64::from(self.batches) * self.lights.len() as u64,
        );
        out.insert("receiver_fragments".into(), c[0] as u64);
        out.insert("sample_pixel_pairs".into(), wide(1));
        out.insert("texture_fetches".into(), wide(3));
        out.insert("visibility_tests".into(), wide(5));
        out.insert("camera_pixels".into(), self.receiver_pixels_hint);
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
        shader::validate_wgsl("prepare.wgsl", &pass_source(PREPARE_WGSL))?;
        shader::validate_wgsl("gather.wgsl", &pass_source(GATHER_WGSL))
    }

    #[test]
    fn gpu_structs_match_their_wgsl() {
        let src = pass_source(GATHER_WGSL);
        caustics_gpu::assert_wgsl_layout!(src, GpuSample as "Sample" { pos, normal, t1, t2, extra });
        caustics_gpu::assert_wgsl_layout!(
            src,
            GpuParams as "Params" {
                generator,
                light_index,
                sample_count,
                batch_size,
                map_center,
                map_axis,
                map_u,
                map_v,
                light_scale,
                env_scale
            }
        );
    }

    #[test]
    fn the_gather_samples_its_light_map_filtered() -> Result<(), String> {
        // The reflection must bind the light map as filterable (it is read through a
        // trilinear sampler), or the gather's pipeline would not validate.
        let r = caustics_gpu::pass::Reflection::of("gather.wgsl", &pass_source(GATHER_WGSL))?;
        let ty = |name: &str| r.group(1).iter().find(|b| b.name == name).map(|b| b.ty);
        assert_eq!(
            ty("light_map"),
            Some(wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            })
        );
        assert_eq!(
            ty("light_sampler"),
            Some(wgpu::BindingType::Sampler(
                wgpu::SamplerBindingType::Filtering
            ))
        );
        Ok(())
    }

    #[test]
    fn bad_params_are_errors_naming_the_parameter() {
        for (json, needle) in [
            (serde_json::json!({"samples": 0}), "samples"),
            (serde_json::json!({"samples": 1_000_000}), "samples"),
            (
                serde_json::json!({"sampling": "poisson"}),
                "sampling: expected one of",
            ),
            (
                serde_json::json!({"filtering": "yes"}),
                "filtering: expected one of",
            ),
            (serde_json::json!({"light_angle": 0.0}), "light_angle"),
            (serde_json::json!({"light_angle": 1e308}), "light_angle"),
            (serde_json::json!({"cube_size": 300}), "cube_size"),
            (serde_json::json!({"cube_size": 4096}), "cube_size"),
            (serde_json::json!({"epsilon_scale": -1.0}), "epsilon_scale"),
            (serde_json::json!({"epsilon_scale": 0.0}), "epsilon_scale"),
            (serde_json::json!({"epsilon_scale": 1e9}), "epsilon_scale"),
            (serde_json::json!({"seed": -1}), "seed"),
            (serde_json::json!({"seed": 1.5}), "seed"),
            (
                serde_json::json!({"samples_per_pass": 0}),
                "samples_per_pass",
            ),
            (
                serde_json::json!({"samples_per_pass": 5000}),
                "samples_per_pass",
            ),
            (serde_json::json!({"sample": 10}), "known parameters"),
        ] {
            let msg = parse::<PinholeParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{json}: {msg}");
        }
        let ok = parse::<PinholeParams>(
            NAME,
            &serde_json::json!({"sampling": "quantized", "samples": 100, "filtering": "off"}),
        )
        .expect("valid");
        assert_eq!(ok.sampling, Strategy::Quantized);
        assert_eq!(ok.filtering, Filtering::Off);
        assert_eq!(
            parse::<PinholeParams>(NAME, &serde_json::Value::Null).expect("defaults"),
            PinholeParams::default()
        );
    }

    #[test]
    fn defaults_keep_their_json_form() {
        use caustics_method::MethodParams;
        assert_eq!(
            serde_json::Value::Object(PinholeParams::default().to_json()),
            serde_json::json!({
                "sampling": "neighbor_removal",
                "samples": 1000,
                "seed": 1,
                "filtering": "full",
                "light_angle": 0.016,
                "cube_size": 256,
                "epsilon_scale": 1.0,
                "samples_per_pass": 64,
                "reflections": false
            })
        );
    }

    #[test]
    fn point_light_disc_sends_the_intensity() {
        // Radiance × disc area = 1 W/sr per unit intensity, seen face on.
        let light = Light::Point {
            position: Vec3::new(0.85, 1.0, 0.0),
            intensity: Vec3::ONE,
        };
        let d = LightDisc::new(&light, Vec3::new(0.0, 0.25, 0.0), 0.016);
        let area = std::f32::consts::PI * d.radius * d.radius;
        assert!((d.radiance_per_power * area - 1.0).abs() < 1e-5);
        assert!((d.axis.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn scene_support_is_declared() {
        let load =
            |name: &str| Scene::load(&caustics_scene::resolve(name).expect(name)).expect(name);
        assert_eq!(
            caustic_generator(&load("ring")),
            Ok((0, GeneratorMode::Mirror))
        );
        assert_eq!(
            caustic_generator(&load("sphere_on_plane")),
            Ok((0, GeneratorMode::SphereRefraction))
        );
        // The paper's "underwater scenes": one refraction at the water surface.
        assert_eq!(
            caustic_generator(&load("water_pool")),
            Ok((0, GeneratorMode::SurfaceRefraction))
        );
        // Two refractions through a glass mesh, two specular objects: the paper's
        // one-bounce limit, quoted.
        for (name, needle) in [
            ("glass_cushion", "dielectric mesh"),
            ("bumpy_glass", "dielectric mesh"),
            ("two_lenses", "both specular"),
            ("sphere_over_water", "both specular"),
        ] {
            let why = caustic_generator(&load(name)).expect_err(name).0;
            assert!(
                why.contains(needle) && why.contains("only one specular bounce can be handled"),
                "{name}: {why}"
            );
        }
    }
}
