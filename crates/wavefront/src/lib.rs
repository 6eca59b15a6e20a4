//! `wavefront`: Wallace's WebGL caustics (2016) as a caustics-bench method.
//!
//! The light is a wavefront mesh: each vertex is a light ray, each triangle the bundle
//! of rays between its vertices. The rays are traced through the refractor to the
//! receivers (`trace.wgsl`), triangles that stay on one receiver are flagged
//! (`classify.wgsl`; flags, not a compacted list, so that the draw order and with it
//! the additive blend are the same every frame: the image is deterministic), and the
//! refracted mesh is drawn from the camera with brightness = flux density × (area before)/(area after), the two areas taken from screen-space
//! derivatives of the old and new positions (`splat.wgsl`). Flux density is the
//! light's irradiance per unit area of the plane perpendicular to a directional
//! light (or its intensity per steradian for a point/spot light) times the Fresnel
//! transmittance of each interface, so the result is absolute radiance
//! ρ/π · E in DESIGN units. For flat water it is exactly ρ/π · T(θ) · E · cos θ.
//!
//! Supports one caustic generator: a dielectric heightfield or quad (refracted once,
//! Wallace's water) or sphere (refracted on entry and exit), or a mirror sphere, quad
//! or open cylinder (reflected once, Wallace's "reflection off the top of the water"
//! and Wand's ring); one light of any kind; analytic diffuse receivers (quads,
//! spheres, cylinders). It does not follow chains of specular events (a ray that meets
//! a specular surface again is dropped), meshes or media: such scenes are skipped with
//! the reason. Like the original, it ignores the light reflected at dielectric
//! interfaces and point-samples triangles thinner than a pixel (noisy cusps).

mod sources;

use bytemuck::{Pod, Zeroable};
use caustics_gpu::pass::{ComputePass, RasterPass, Shader};
use caustics_gpu::textures::{additive_hdr_target, load_attachment};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{Frame, GpuContext, Renderer, shader};
use caustics_method::params::{above, closed};
use caustics_method::{
    Capabilities, CausticsMethod, Counters, Method, MethodError, Unsupported, method_params,
};
use caustics_scene::{Material, Scene, Shape};

pub use sources::{Source, WavefrontMesh};

/// Types shared by the three passes (`Traced`, `TraceParams`).
const TYPES_WGSL: &str = include_str!("types.wgsl");
const TRACE_WGSL: &str = include_str!("trace.wgsl");
const CLASSIFY_WGSL: &str = include_str!("classify.wgsl");
const SPLAT_WGSL: &str = include_str!("splat.wgsl");

/// A pass's full WGSL: shared GPU files, wavefront's types, then the pass.
fn pass_source(pass: &str) -> String {
    shader::compose_method(&format!("{TYPES_WGSL}\n{pass}"))
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
    }
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
        multiple_bounces: false,
        directional_light: true,
        point_light: true,
        spot_light: true,
    };

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

/// The one specular object `wavefront` traces light through (the caustic
/// generator), or why the scene is out of reach: a dielectric heightfield, quad or
/// sphere, or a mirror sphere, quad or open cylinder; every other object an analytic
/// diffuse receiver.
pub fn caustic_generator(scene: &Scene) -> Result<usize, Unsupported> {
    if scene.lights.len() != 1 {
        return Err(Unsupported(format!(
            "needs exactly one light, the scene has {}",
            scene.lights.len()
        )));
    }
    let mut generator = None;
    for (i, o) in scene.objects.iter().enumerate() {
        let material = scene.material(o);
        if !material.is_specular() {
            match &o.shape {
                Shape::Mesh(_) => {
                    return Err(Unsupported(format!(
                        "objects[{i}] is a mesh; wavefront traces analytic shapes only"
                    )));
                }
                Shape::Heightfield(_) => {
                    return Err(Unsupported(format!(
                        "objects[{i}] is a diffuse heightfield; wavefront receivers must be analytic"
                    )));
                }
                _ => continue,
            }
        }
        let supported = matches!(
            (material, &o.shape),
            (
                Material::Dielectric { .. },
                Shape::Heightfield(_) | Shape::Quad { .. } | Shape::Sphere { .. }
            ) | (
                Material::Mirror { .. },
                Shape::Sphere { .. } | Shape::Quad { .. } | Shape::Cylinder { .. }
            )
        );
        if !supported {
            return Err(Unsupported(format!(
                "objects[{i}] is a specular {} ({}); wavefront traces dielectric heightfields, quads and spheres and mirror spheres, quads and cylinders",
                shape_name(&o.shape),
                if matches!(material, Material::Mirror { .. }) {
                    "mirror"
                } else {
                    "dielectric"
                }
            )));
        }
        if let Some(first) = generator {
            return Err(Unsupported(format!(
                "objects[{first}] and objects[{i}] are both specular; wavefront follows one specular event (no chains)"
            )));
        }
        generator = Some(i);
    }
    generator.ok_or_else(|| Unsupported("the scene has no specular object".into()))
}

fn shape_name(s: &Shape) -> &'static str {
    match s {
        Shape::Sphere { .. } => "sphere",
        Shape::Quad { .. } => "quad",
        Shape::Heightfield(_) => "heightfield",
        Shape::Cylinder { .. } => "cylinder",
        Shape::Mesh(_) => "mesh",
    }
}

fn check_scene(scene: &Scene) -> Result<(), Unsupported> {
    let g = caustic_generator(scene)?;
    let shape = &scene.objects[g].shape;
    if !matches!(shape, Shape::Heightfield(_)) {
        let (center, radius) = sources::bounding_sphere(shape);
        if sources::ray_lattice(center, radius, &scene.lights[0], 2).is_none() {
            return Err(Unsupported(format!(
                "the light is inside the bounding sphere of the generator objects[{g}], which wavefront's ray lattice must see from outside"
            )));
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
}

/// Matches `SplatParams` in splat.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SplatParams {
    tolerance: f32,
    _pad: [f32; 3],
}

/// Kept and dropped triangle counts (matches `Counters` in classify.wgsl).
const COUNTERS_INIT: [u32; 4] = [0; 4];

/// `wavefront` bound to one scene.
pub struct Wavefront {
    trace: ComputePass,
    classify: ComputePass,
    splat: RasterPass,
    counters: wgpu::Buffer,
    counters_init: wgpu::Buffer,
    source_count: u32,
    triangle_count: u32,
    bytes: u64,
}

/// The buffers the three passes share.
struct Buffers {
    trace_params: wgpu::Buffer,
    splat_params: wgpu::Buffer,
    sources: wgpu::Buffer,
    triangles: wgpu::Buffer,
    traced: wgpu::Buffer,
    keep: wgpu::Buffer,
    counters: wgpu::Buffer,
    counters_init: wgpu::Buffer,
}

impl Buffers {
    fn new(
        device: &wgpu::Device,
        mesh: &WavefrontMesh,
        trace: &TraceParams,
        splat: &SplatParams,
    ) -> Self {
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let storage = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let uniform = wgpu::BufferUsages::UNIFORM;
        Self {
            trace_params: init("wavefront trace params", bytemuck::bytes_of(trace), uniform),
            splat_params: init("wavefront splat params", bytemuck::bytes_of(splat), uniform),
            sources: init(
                "wavefront sources",
                bytemuck::cast_slice(&mesh.sources),
                wgpu::BufferUsages::STORAGE,
            ),
            triangles: init(
                "wavefront triangles",
                bytemuck::cast_slice(&mesh.triangles),
                wgpu::BufferUsages::STORAGE,
            ),
            // One `Traced` (64 bytes) per source, one flag per triangle.
            traced: storage("wavefront traced vertices", trace.source_count as u64 * 64),
            keep: storage(
                "wavefront keep flags",
                trace.triangle_count.max(1) as u64 * 4,
            ),
            counters: init(
                "wavefront counters",
                bytemuck::cast_slice(&COUNTERS_INIT),
                wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
            ),
            counters_init: init(
                "wavefront counters reset",
                bytemuck::cast_slice(&COUNTERS_INIT),
                wgpu::BufferUsages::COPY_SRC,
            ),
        }
    }

    fn bytes(&self) -> u64 {
        [
            &self.trace_params,
            &self.splat_params,
            &self.sources,
            &self.triangles,
            &self.traced,
            &self.keep,
            &self.counters,
            &self.counters_init,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }
}

impl Wavefront {
    /// Builds the wavefront of the scene's caustic generator and Wallace's three
    /// passes: trace the rays, flag the triangles that stay on one receiver, draw them
    /// with the area ratio as brightness.
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
        let generator = caustic_generator(scene).map_err(unsupported)?;
        let mesh = sources::for_shape(
            &scene.objects[generator].shape,
            &gpu_scene.meshes[generator],
            &scene.lights[0],
            params.grid,
        )
        .ok_or_else(|| {
            unsupported(Unsupported(
                "cannot build a wavefront for this refractor and light".into(),
            ))
        })?;
        let trace_params = TraceParams {
            specular_object: generator as u32,
            light_index: 0,
            source_count: mesh.sources.len() as u32,
            triangle_count: (mesh.triangles.len() / 3) as u32,
        };
        let splat_params = SplatParams {
            tolerance: params.tolerance as f32,
            _pad: [0.0; 3],
        };
        let b = ctx.checked("wavefront setup", || {
            Buffers::new(&ctx.device, &mesh, &trace_params, &splat_params)
        })?;

        // Pass 1: one light ray per wavefront vertex, through the generator to a receiver.
        let shader = Shader::new(ctx, "wavefront trace.wgsl", pass_source(TRACE_WGSL))?;
        let trace = ComputePass::builder(ctx, "wavefront/trace_vertices", &shader)
            .frame(renderer)
            .bind(
                1,
                &[
                    ("tp", &b.trace_params),
                    ("sources", &b.sources),
                    ("traced", &b.traced),
                ],
            )
            .kernels(&["trace_vertices"])
            .build()?;

        // Pass 2: keep the triangles whose vertices land on one side of one receiver.
        let shader = Shader::new(ctx, "wavefront classify.wgsl", pass_source(CLASSIFY_WGSL))?;
        let classify = ComputePass::builder(ctx, "wavefront/classify_triangles", &shader)
            .frame(renderer)
            .bind(
                1,
                &[
                    ("tp", &b.trace_params),
                    ("traced", &b.traced),
                    ("triangles", &b.triangles),
                    ("keep", &b.keep),
                    ("counters", &b.counters),
                ],
            )
            .kernels(&["classify_triangles"])
            .build()?;

        // Pass 3: the kept triangles drawn from the camera, brightness = old/new area.
        // Folded triangles face away: both windings count (the builder culls nothing).
        let shader = Shader::new(ctx, "wavefront splat.wgsl", pass_source(SPLAT_WGSL))?;
        let splat = RasterPass::builder(ctx, "wavefront/splat", &shader, "vs_splat")
            .frame(renderer)
            .bind(
                1,
                &[
                    ("sp", &b.splat_params),
                    ("traced", &b.traced),
                    ("triangles", &b.triangles),
                    ("keep", &b.keep),
                ],
            )
            .fragment("fs_splat", &[Some(additive_hdr_target())])
            .counted()
            .build()?;

        Ok(Self {
            trace,
            classify,
            splat,
            bytes: b.bytes(),
            counters: b.counters,
            counters_init: b.counters_init,
            source_count: trace_params.source_count,
            triangle_count: trace_params.triangle_count,
        })
    }
}

impl CausticsMethod for Wavefront {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        let renderer = frame.renderer;
        frame.encoder.copy_buffer_to_buffer(
            &self.counters_init,
            0,
            &self.counters,
            0,
            self.counters.size(),
        );
        self.trace
            .begin(frame)?
            .dispatch("trace_vertices", [self.source_count.div_ceil(64), 1, 1])?;
        self.classify.begin(frame)?.dispatch(
            "classify_triangles",
            [self.triangle_count.div_ceil(64), 1, 1],
        )?;
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        let mut pass = self.splat.begin(frame, &attachments, None)?;
        pass.draw(0..3 * self.triangle_count, 0..1);
        Ok(())
    }

    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError> {
        let c = caustics_gpu::readback::read_buffer_u32(
            ctx,
            &self.counters,
            self.counters.size(),
            "wavefront counters",
        )?;
        let mut out = Counters::new();
        out.insert("source_vertices".into(), self.source_count as u64);
        out.insert("triangles".into(), self.triangle_count as u64);
        out.insert("kept_triangles".into(), c[0] as u64);
        out.insert("dropped_invalid_vertex".into(), c[1] as u64);
        out.insert("dropped_receiver_mismatch".into(), c[2] as u64);
        out.insert("dropped_face_mismatch".into(), c[3] as u64);
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
        shader::validate_wgsl("trace.wgsl", &pass_source(TRACE_WGSL))?;
        shader::validate_wgsl("classify.wgsl", &pass_source(CLASSIFY_WGSL))?;
        shader::validate_wgsl("splat.wgsl", &pass_source(SPLAT_WGSL))
    }

    #[test]
    fn gpu_structs_match_their_wgsl() {
        caustics_gpu::assert_wgsl_layout!(
            pass_source(TRACE_WGSL),
            Source {
                origin,
                dir_or_normal
            }
        );
        caustics_gpu::assert_wgsl_layout!(
            pass_source(TRACE_WGSL),
            TraceParams {
                specular_object,
                light_index,
                source_count,
                triangle_count
            }
        );
        caustics_gpu::assert_wgsl_layout!(pass_source(SPLAT_WGSL), SplatParams { tolerance });
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
            (serde_json::json!({"grd": 4}), "known parameters"),
        ] {
            let msg = parse::<WavefrontParams>(NAME, &json)
                .expect_err("must fail")
                .to_string();
            assert!(msg.contains(needle) && msg.contains(NAME), "{msg}");
        }
        use caustics_method::MethodParams;
        assert_eq!(
            serde_json::Value::Object(WavefrontParams::default().to_json()),
            serde_json::json!({"grid": 512, "tolerance": 2e-3})
        );
    }
}
