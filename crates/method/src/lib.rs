//! The method contract of caustics-bench (DESIGN "The method contract").
//!
//! A method is built from a scene already uploaded to the GPU (the shared
//! [`Renderer`]) and its own typed parameters; per frame it records its named passes
//! into the frame ([`Frame::render_pass`] / [`Frame::compute_pass`] wrap them in the
//! harness's profiler) and writes the shared HDR targets: surface caustic radiance
//! and volume caustic radiance. It reports counters and the GPU memory it owns, and
//! declares what it supports so that the harness skips, with the reason, a scene it
//! cannot render. The harness, not the method, owns timing, fill counting and scoring.

use std::collections::BTreeMap;

use caustics_gpu::{
    Frame, GpuContext, GpuError, PassProfiler, Renderer, ScoreAccumulator, ScoredImages,
    subpixel_offsets,
};
use caustics_scene::Scene;

/// A method instance bound to one scene.
pub trait CausticsMethod {
    /// Records the method's passes for one frame. In count frames
    /// (`frame.counting()`), camera-resolution pipelines must use their fill-counting
    /// variant (a `caustics_gpu::pass::RasterPass` built `.counted()` picks it). When
    /// `frame.reuses_light_side()` (scoring sub-frames), record only the camera-side
    /// passes and keep what the light-side passes left in the previous frame; the
    /// method's tests check the image is the same (`Gpu::assert_light_side_reuse_is_exact`).
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError>;

    /// Counters of the last frame (beams, triangles, photons, overflow, ...). Called
    /// once after the measured frames; may read small GPU buffers back.
    fn counters(&self, ctx: &GpuContext) -> Result<Counters, MethodError>;

    /// Bytes of GPU memory the method owns (buffers and textures it allocated).
    fn gpu_memory_bytes(&self) -> u64;
}

/// Named integer counters, sorted by name for stable result files.
pub type Counters = BTreeMap<String, u64>;

/// What a method can render (DESIGN: declare support, never produce a wrong number).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// Writes the surface caustic image (L S+ D E).
    pub surface: bool,
    /// Writes the volume caustic image (L S+ M E).
    pub volume: bool,
    /// Handles mirrors.
    pub reflection: bool,
    /// Handles dielectrics.
    pub refraction: bool,
    /// Follows light through more than one specular object in sequence.
    pub multiple_bounces: bool,
    /// Directional lights.
    pub directional_light: bool,
    /// Point lights.
    pub point_light: bool,
    /// Spot lights.
    pub spot_light: bool,
    /// Sphere area lights (Lambertian spheres of given radiance).
    pub sphere_light: bool,
    /// Environment lights (radiance by direction from infinitely far away).
    pub environment_light: bool,
    /// For a method without `volume`: where its paper leaves participating media out
    /// (the sentence, cited), given with the decline of a scene with a medium.
    pub no_medium_in_paper: &'static str,
}

impl Capabilities {
    /// Human-readable list, for `caustics list`.
    pub fn describe(&self) -> String {
        let flags = [
            (self.surface, "surface"),
            (self.volume, "volume"),
            (self.reflection, "reflection"),
            (self.refraction, "refraction"),
            (self.multiple_bounces, "multiple bounces"),
            (self.directional_light, "directional light"),
            (self.point_light, "point light"),
            (self.spot_light, "spot light"),
            (self.sphere_light, "sphere light"),
            (self.environment_light, "environment light"),
        ];
        flags
            .iter()
            .filter(|(on, _)| *on)
            .map(|(_, n)| *n)
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The generic checks every method shares: light kinds, medium, material kinds.
    /// Method-specific limits go in [`MethodInfo::check_scene`].
    pub fn check(&self, scene: &Scene) -> Result<(), Unsupported> {
        use caustics_scene::{Light, Material};
        for (i, l) in scene.lights.iter().enumerate() {
            let (ok, kind) = match l {
                Light::Directional { .. } => (self.directional_light, "directional"),
                Light::Point { .. } => (self.point_light, "point"),
                Light::Spot { .. } => (self.spot_light, "spot"),
                Light::Sphere { .. } if !self.sphere_light => {
                    return Err(Unsupported(format!(
                        "lights[{i}] is a sphere area light: this method's light leaves one point (its photons, beams or wavefront start there), so an extended light needs representative point lights (`--representative-lights N`, or an experiment group's `representative_lights`); pinhole renders sphere lights (Wand & Straßer §5: \"extended light sources at no additional costs\")"
                    )));
                }
                Light::Sphere { .. } => (true, "sphere"),
                Light::Environment { .. } if !self.environment_light => {
                    return Err(Unsupported(format!(
                        "lights[{i}] is an environment light: this method's light leaves one point or one direction (its photons, beams or wavefront start there), so an environment needs representative directional lights (`--representative-lights N`, or an experiment group's `representative_lights`); pinhole renders environment maps (Wand & Straßer's Fig. 6)"
                    )));
                }
                Light::Environment { .. } => (true, "environment"),
            };
            if !ok {
                return Err(Unsupported(format!(
                    "lights[{i}] is a {kind} light, which this method does not support"
                )));
            }
        }
        if scene.medium.is_some() && !self.volume {
            let mut why = String::from(
                "the scene has a participating medium, and this method renders neither volume caustics nor extinction (its surface caustic would be unattenuated)",
            );
            if !self.no_medium_in_paper.is_empty() {
                why.push_str(": ");
                why.push_str(self.no_medium_in_paper);
            }
            return Err(Unsupported(why));
        }
        for (i, o) in scene.objects.iter().enumerate() {
            let name = &scene.materials[o.material].name;
            match scene.material(o) {
                Material::Mirror { .. } if !self.reflection => {
                    return Err(Unsupported(format!(
                        "objects[{i}] is a mirror ({name:?}); this method handles no reflection"
                    )));
                }
                Material::Dielectric { .. } if !self.refraction => {
                    return Err(Unsupported(format!(
                        "objects[{i}] is a dielectric ({name:?}); this method handles no refraction"
                    )));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Why a method cannot render a scene.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Unsupported(pub String);

/// Errors of a method crate.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    /// A parameter is unknown, of the wrong type or out of range.
    #[error("method {method}: parameter {message}")]
    Param {
        /// Method name.
        method: &'static str,
        /// What is wrong, naming the parameter and what was expected.
        message: String,
    },
    /// The scene cannot be rendered by this method.
    #[error("method {method} cannot render scene {scene}: {reason}")]
    Unsupported {
        /// Method name.
        method: &'static str,
        /// Scene name.
        scene: String,
        /// Why.
        reason: Unsupported,
    },
    /// A GPU failure.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

pub mod params;

pub use params::{MethodParams, ParamSpec, ParamValue, ParsedParams, Range, above, closed};

/// A method as the registry knows it: its name, paper, capabilities, typed parameters
/// and how to build it. Implemented once per method crate (on a marker type);
/// [`registry_entry`] turns it into the harness's [`MethodInfo`].
pub trait Method: 'static {
    /// Its parameters, declared with [`method_params!`].
    type Params: MethodParams;
    /// Registry name (`--method`).
    const NAME: &'static str;
    /// One line on what it is.
    const SUMMARY: &'static str;
    /// The paper it implements.
    const SOURCE: &'static str;
    /// What it supports.
    const CAPABILITIES: Capabilities;
    /// Every counter [`CausticsMethod::counters`] reports, each with what it counts (a
    /// numbered family once, as `<prefix>_N`: see [`CounterDoc`]). The method's GPU test
    /// checks that every counter it reports is documented here.
    const COUNTERS: &'static [CounterDoc];

    /// Scene checks beyond [`Capabilities::check`], given the (valid) parameters.
    fn check_scene(_scene: &Scene, _params: &Self::Params) -> Result<(), Unsupported> {
        Ok(())
    }

    /// Builds an instance for the renderer's scene.
    fn create(
        ctx: &GpuContext,
        renderer: &Renderer,
        params: &Self::Params,
    ) -> Result<Box<dyn CausticsMethod>, MethodError>;
}

/// What one counter of a method counts, for `caustics list` and the report's glossary.
///
/// A numbered family (`beams_level_0`, `beams_level_1`, ...) is documented once, with
/// a name ending in `_N` (`beams_level_N`): see [`CounterDoc::matches`].
#[derive(Clone, Copy, Debug)]
pub struct CounterDoc {
    /// The counter's name as [`CausticsMethod::counters`] reports it, or a family's
    /// prefix followed by `_N`.
    pub name: &'static str,
    /// One line: what is counted, in which pass of which frame.
    pub doc: &'static str,
}

impl CounterDoc {
    /// Whether `counter` is the counter this documents: the same name, or, for a
    /// family `<prefix>_N`, `<prefix>_` followed by one or more ASCII digits.
    pub fn matches(&self, counter: &str) -> bool {
        if counter == self.name {
            return true;
        }
        let Some(prefix) = self.name.strip_suffix('N') else {
            return false;
        };
        prefix.ends_with('_')
            && counter
                .strip_prefix(prefix)
                .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    }

    /// Checks a list of docs against the counter names a method can report: every
    /// name has a doc, and every doc is of a reported name (none is stale). The error
    /// names each counter or doc at fault.
    pub fn check<S: AsRef<str>>(docs: &[CounterDoc], reported: &[S]) -> Result<(), String> {
        let mut faults = Vec::new();
        for name in reported.iter().map(AsRef::as_ref) {
            if !docs.iter().any(|d| d.matches(name)) {
                faults.push(format!("counter {name} has no doc"));
            }
        }
        for d in docs {
            if !reported.iter().any(|n| d.matches(n.as_ref())) {
                faults.push(format!("{} is documented but never reported", d.name));
            }
        }
        if faults.is_empty() {
            Ok(())
        } else {
            Err(faults.join("; "))
        }
    }

    /// `a` then `b`, as one array of `N` = `a.len() + b.len()` docs: a method's list
    /// from a shared crate's and its own (`const COUNTERS: &[CounterDoc] =
    /// &CounterDoc::concat::<{ SHARED.len() + OWN.len() }>(SHARED, OWN);`).
    ///
    /// # Panics
    /// At compile time, where `N` is not `a.len() + b.len()`.
    pub const fn concat<const N: usize>(a: &[CounterDoc], b: &[CounterDoc]) -> [CounterDoc; N] {
        assert!(a.len() + b.len() == N, "N must be a.len() + b.len()");
        let mut out = [CounterDoc { name: "", doc: "" }; N];
        let mut i = 0;
        while i < a.len() {
            out[i] = a[i];
            i += 1;
        }
        while i < N {
            out[i] = b[i - a.len()];
            i += 1;
        }
        out
    }
}

/// Builds a method instance for the renderer's scene from parsed parameters.
pub type CreateFn =
    fn(&GpuContext, &Renderer, &ParsedParams) -> Result<Box<dyn CausticsMethod>, MethodError>;

/// Everything the harness's registry knows of a method (made by [`registry_entry`]).
pub struct MethodInfo {
    /// Registry name (`--method`).
    pub name: &'static str,
    /// One line on what it is.
    pub summary: &'static str,
    /// The paper it implements.
    pub source: &'static str,
    /// What it supports.
    pub capabilities: Capabilities,
    /// Its parameters with defaults (the paper's), types, ranges and docs.
    pub params: fn() -> Vec<ParamSpec>,
    /// What each counter it reports counts ([`Method::COUNTERS`]).
    pub counters: &'static [CounterDoc],
    /// Parses and checks parameters once (a JSON object; `null` = defaults), without
    /// touching the GPU, so a bad `--param` fails before any work or any write.
    pub parse: fn(&serde_json::Value) -> Result<ParsedParams, MethodError>,
    /// Scene checks beyond the generic ones, given parsed parameters.
    pub check_scene: fn(&Scene, &ParsedParams) -> Result<(), Unsupported>,
    /// Builds an instance for a scene.
    pub create: CreateFn,
}

impl MethodInfo {
    /// Generic capability checks, then the method's own.
    pub fn supports(&self, scene: &Scene, params: &ParsedParams) -> Result<(), Unsupported> {
        self.capabilities.check(scene)?;
        (self.check_scene)(scene, params)
    }

    /// The doc of the counter `name` as the method reports it (`beams_level_2` finds
    /// the family `beams_level_N`); `None` where the method does not document it.
    pub fn counter_doc(&self, name: &str) -> Option<&'static str> {
        self.counters
            .iter()
            .find(|d| d.name == name)
            .or_else(|| self.counters.iter().find(|d| d.matches(name)))
            .map(|d| d.doc)
    }
}

/// The registry entry of `M`: one generic function instead of per-method glue.
pub fn registry_entry<M: Method>() -> MethodInfo {
    MethodInfo {
        name: M::NAME,
        summary: M::SUMMARY,
        source: M::SOURCE,
        capabilities: M::CAPABILITIES,
        params: M::Params::specs,
        counters: M::COUNTERS,
        parse: parse_erased::<M>,
        check_scene: check_erased::<M>,
        create: create_erased::<M>,
    }
}

fn parse_erased<M: Method>(v: &serde_json::Value) -> Result<ParsedParams, MethodError> {
    Ok(ParsedParams::new(
        M::NAME,
        params::parse::<M::Params>(M::NAME, v)?,
    ))
}

fn check_erased<M: Method>(scene: &Scene, p: &ParsedParams) -> Result<(), Unsupported> {
    match p.get::<M::Params>(M::NAME) {
        Ok(p) => M::check_scene(scene, p),
        Err(e) => Err(Unsupported(e.to_string())),
    }
}

fn create_erased<M: Method>(
    ctx: &GpuContext,
    renderer: &Renderer,
    p: &ParsedParams,
) -> Result<Box<dyn CausticsMethod>, MethodError> {
    M::create(ctx, renderer, p.get::<M::Params>(M::NAME)?)
}

/// How the sub-frames of a scoring frame get their light-side work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightSide {
    /// Rendered once, in a whole frame at the pixel centre before the sub-frames, and
    /// kept by every sub-frame ([`Frame::reuses_light_side`]):
    /// the image scored is the timed frame's light (its photons, beams, wavefront)
    /// seen through a box-filtered camera. What `caustics run` does.
    Reuse,
    /// Rendered again in every sub-frame, each a whole frame. For a method whose light
    /// side does not depend on the camera the image is the same as with
    /// [`LightSide::Reuse`] (each method's tests check this); adaptive beams refine for
    /// each shifted camera.
    RenderEach,
}

/// Renders the scoring frame of `method` (DESIGN "Measuring honestly"): the frame
/// again at each of the `grid × grid` sub-pixel camera offsets of
/// [`subpixel_offsets`], the three radiance targets averaged on the GPU; nothing is
/// timed or counted. `accumulator` is allocated once per run; the camera is back at the
/// pixel centre when this returns.
///
/// With [`LightSide::Reuse`] a whole frame at the pixel centre comes first (not
/// averaged), and every sub-frame records only the camera-side passes (camera
/// G-buffer, direct light, the method's camera-side passes), so the light-side work
/// (the larger part of most methods' frames) is done once rather than `grid²` times.
/// With [`LightSide::RenderEach`] each sub-frame is a whole frame, so a method must
/// give the same image for the same offset whatever it rendered before.
pub fn render_scoring_frame(
    ctx: &GpuContext,
    renderer: &Renderer,
    method: &mut dyn CausticsMethod,
    accumulator: &mut ScoreAccumulator,
    grid: u32,
    light_side: LightSide,
) -> Result<ScoredImages, MethodError> {
    let offsets = subpixel_offsets(grid);
    let reuse = light_side == LightSide::Reuse;
    let mut profiler = PassProfiler::unmeasured(offsets.len() as u32 + u32::from(reuse));
    let rendered = (|| {
        if reuse {
            renderer.set_subpixel_offset(&ctx.queue, [0.0, 0.0]);
            let mut frame = renderer.begin_scoring_subframe(&mut profiler, false)?;
            method.record(&mut frame)?;
            frame.submit(ctx)?;
        }
        for offset in &offsets {
            renderer.set_subpixel_offset(&ctx.queue, *offset);
            let mut frame = renderer.begin_scoring_subframe(&mut profiler, reuse)?;
            method.record(&mut frame)?;
            accumulator.record(&mut frame)?;
            frame.submit(ctx)?;
        }
        Ok::<_, MethodError>(())
    })();
    renderer.set_subpixel_offset(&ctx.queue, [0.0, 0.0]);
    rendered?;
    Ok(accumulator.read_mean(ctx)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BEAMS: CounterDoc = CounterDoc {
        name: "beams",
        doc: "beams",
    };
    const LEVELS: CounterDoc = CounterDoc {
        name: "beams_level_N",
        doc: "beams per level",
    };

    #[test]
    fn extended_lights_are_declined_with_the_reason() {
        let json = r#"{"name": "s", "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "fov_y_deg": 40, "width": 8, "height": 6},
            "lights": [{"type": "point", "position": [0, 5, 0], "intensity": [1, 1, 1]},
                       {"type": "sphere", "position": [1, 5, 0], "radius": 0.2, "radiance": [1, 1, 1]}],
            "materials": {"floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
            "objects": [{"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "floor"}]}"#;
        let scene = Scene::from_json_str(json, std::path::Path::new("s.json")).expect("valid");
        let every_kind = Capabilities {
            surface: true,
            directional_light: true,
            point_light: true,
            spot_light: true,
            ..Default::default()
        };
        let why = every_kind.check(&scene).expect_err("a sphere light").0;
        assert!(why.contains("lights[1] is a sphere area light"), "{why}");
        let with_spheres = Capabilities {
            sphere_light: true,
            ..every_kind
        };
        assert_eq!(with_spheres.check(&scene), Ok(()));
    }

    #[test]
    fn check_finds_undocumented_and_stale_counters() {
        let docs = [
            CounterDoc {
                name: "beams",
                doc: "d",
            },
            CounterDoc {
                name: "beams_level_N",
                doc: "d",
            },
        ];
        assert!(CounterDoc::check(&docs, &["beams", "beams_level_0", "beams_level_12"]).is_ok());
        let e = CounterDoc::check(&docs, &["beams", "candidates"]).expect_err("faults");
        assert!(e.contains("counter candidates has no doc"), "{e}");
        assert!(
            e.contains("beams_level_N is documented but never reported"),
            "{e}"
        );
    }

    #[test]
    fn counter_doc_matches_exact_names_and_numbered_families() {
        assert!(BEAMS.matches("beams"));
        assert!(!BEAMS.matches("beams_level_0"));
        assert!(!BEAMS.matches("beam"));
        for n in ["beams_level_0", "beams_level_7", "beams_level_12"] {
            assert!(LEVELS.matches(n), "{n}");
        }
        assert!(LEVELS.matches("beams_level_N"), "the family's own name");
        for n in [
            "beams_level_",
            "beams_level_x",
            "beams_level_1a",
            "beams_level_-1",
            "beams_level",
            "beams_levels_1",
            "beams_level_1_2",
            "other_level_1",
        ] {
            assert!(!LEVELS.matches(n), "{n}");
        }
        // Only a name ending in `_N` is a family.
        let plain = CounterDoc {
            name: "kernel_pxN",
            doc: "",
        };
        assert!(!plain.matches("kernel_px1"));
    }

    #[test]
    fn method_info_finds_a_counters_doc_by_name_or_family() {
        fn refused() -> MethodError {
            MethodError::Param {
                method: "test",
                message: String::new(),
            }
        }
        let info = MethodInfo {
            name: "test",
            summary: "",
            source: "",
            capabilities: Capabilities::default(),
            params: Vec::new,
            counters: &[LEVELS, BEAMS],
            parse: |_| Err(refused()),
            check_scene: |_, _| Ok(()),
            create: |_, _, _| Err(refused()),
        };
        assert_eq!(info.counter_doc("beams"), Some("beams"));
        assert_eq!(info.counter_doc("beams_level_3"), Some("beams per level"));
        assert_eq!(info.counter_doc("beams_level_x"), None);
        assert_eq!(info.counter_doc("photons"), None);
    }

    #[test]
    fn concat_keeps_both_lists_in_order() {
        const A: &[CounterDoc] = &[BEAMS];
        const B: &[CounterDoc] = &[LEVELS, BEAMS];
        const ALL: [CounterDoc; 3] = CounterDoc::concat::<{ A.len() + B.len() }>(A, B);
        let names: Vec<_> = ALL.iter().map(|d| d.name).collect();
        assert_eq!(names, ["beams", "beams_level_N", "beams"]);
    }
}
