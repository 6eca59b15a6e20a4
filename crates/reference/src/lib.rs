//! The independent CPU reference of caustics-bench: a light tracer that renders the
//! DESIGN.md **surface caustic image** (paths L S+ D E), the **volume caustic image**
//! (L S+ M E, scenes with a medium) and optionally the **direct image** (L D E), each
//! in radiance (W·m⁻²·sr⁻¹, pixel = average over its area, row 0 at the top), with a
//! per-pixel standard-error image from independent batches.
//!
//! Photons leave the lights aimed at the specular objects (see `emission.rs`
//! for the weights), follow dielectrics (exact unpolarized Fresnel, Snell, TIR) and
//! mirrors (weighted by the adjoint shading-normal factor where interpolated or analytic
//! normals differ from the facets, `tracer.rs`), and at their first diffuse hit after
//! ≥ 1 specular event are connected to the pinhole (the formula and its derivation
//! are in `sensor.rs`). It knows no GPU and no method, so it stays an independent
//! check.
//!
//! ```
//! use caustics_reference::{Reference, ReferenceOptions};
//! use caustics_scene::Scene;
//! use std::path::Path;
//!
//! let json = r#"{
//!   "name": "tiny",
//!   "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
//!              "fov_y_deg": 40, "width": 32, "height": 24},
//!   "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
//!   "materials": {"glass": {"type": "dielectric", "ior": 1.5},
//!                 "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
//!   "objects": [
//!     {"shape": {"type": "sphere", "center": [0, 1.5, 0], "radius": 1}, "material": "glass"},
//!     {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]},
//!      "material": "floor"}
//!   ]
//! }"#;
//! let scene = Scene::from_json_str(json, Path::new("tiny.json"))?;
//! let reference = Reference::new(&scene)?;
//! let opts = ReferenceOptions { photons: 10_000, ..Default::default() };
//! let result = reference.render(&opts, &|_done| {})?;
//! assert_eq!(result.caustic.pixels.len(), 32 * 24);
//! assert!(result.photons >= 10_000);
//! assert!(result.volume.is_none());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Dependencies: `rayon` runs the work units in parallel (work stealing, scoped, the
//! standard choice); `obvhs` is the mesh BVH and the ray–triangle test (see `bvh.rs`
//! for why; heightfields use the same test on their own grid, `heightfield.rs`);
//! `rand_xoshiro` gives xoshiro256++, a small fast generator with SplitMix64 seeding,
//! so each work unit gets an independent stream from a hash of (seed, unit).

/// Version of the light transport a reference image holds: bumped whenever a change
/// moves what an image converges to, so that no cache serves an image the current
/// tracer would not make (the harness's reference cache keys on it). 1: until the
/// adjoint shading-normal factor; 2: with it (`tracer.rs`, DESIGN "Conventions").
pub const TRANSPORT_VERSION: u32 = 2;

mod accumulate;
mod bvh;
mod emission;
pub mod eps;
mod geometry;
mod heightfield;
mod optics;
mod sensor;
mod tracer;

use std::time::Instant;

use caustics_scene::{Material, Medium, Scene, Vec3};
use rayon::prelude::*;

use crate::accumulate::{Accumulator, Plan, UNIT_PHOTONS};
use crate::emission::{Emitter, Target};
use crate::geometry::Geometry;
use crate::sensor::Sensor;
use crate::tracer::{PowerFilter, Tracer, UnitOutput};

pub use eps::EPSILON_POLICY;

/// Most batches accepted (each holds up to a full-resolution `f64` image in memory).
pub const MAX_BATCHES: u32 = 1024;

/// Environment variable that sets the reference's memory budget, in MiB (read by the
/// harness with [`memory_budget_from_env`]).
pub const MEMORY_BUDGET_ENV: &str = "CAUSTICS_CPU_MEMORY_MIB";

/// Memory budget where the machine's memory cannot be read: 8 GiB.
pub const FALLBACK_MEMORY_BUDGET_BYTES: u64 = 8 << 30;

/// The default memory budget of a render: three quarters of the machine's physical
/// memory (`MemTotal` of `/proc/meminfo`; the rest is left to the system and the GPU
/// driver), else [`FALLBACK_MEMORY_BUDGET_BYTES`].
pub fn default_memory_budget() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib.saturating_mul(1024) / 4 * 3)
        })
        .filter(|&b| b > 0)
        .unwrap_or(FALLBACK_MEMORY_BUDGET_BYTES)
}

/// The memory budget [`MEMORY_BUDGET_ENV`] sets (MiB), else [`default_memory_budget`].
pub fn memory_budget_from_env() -> Result<u64, ReferenceError> {
    match std::env::var(MEMORY_BUDGET_ENV) {
        Err(_) => Ok(default_memory_budget()),
        Ok(text) => {
            caustics_scene::parse_mib(&text).ok_or(ReferenceError::BadMemoryBudget { text })
        }
    }
}

/// Errors of the reference renderer.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ReferenceError {
    /// `photons` was 0.
    #[error("photons must be at least 1, got 0")]
    NoPhotons,
    /// `batches` was below 2 (no standard error from fewer) or above [`MAX_BATCHES`].
    #[error("batches must be in 2..={max}, got {batches}", max = MAX_BATCHES)]
    BadBatches {
        /// The value given.
        batches: u32,
    },
    /// `render_for` was given a time that is not a finite number ≥ 0.
    #[error("seconds must be a finite number >= 0, got {seconds}")]
    BadSeconds {
        /// The value given.
        seconds: f64,
    },
    /// [`MEMORY_BUDGET_ENV`] is not a whole number of MiB.
    #[error("{MEMORY_BUDGET_ENV}={text:?}: expected a whole number of MiB from 1 to {}", u64::MAX >> 20)]
    BadMemoryBudget {
        /// The value given.
        text: String,
    },
    /// The render would need more memory than its budget: refused before the images
    /// are allocated, or stopped when the batch sums outgrow it.
    #[error(
        "{what}: {needed} needed, past the reference's memory budget, {budget} (set {MEMORY_BUDGET_ENV} in MiB to change it); {raise}",
        needed = caustics_scene::format_bytes(*needed),
        budget = caustics_scene::format_bytes(*budget)
    )]
    OverMemoryBudget {
        /// What needs it.
        what: String,
        /// Bytes needed.
        needed: u64,
        /// The budget, bytes.
        budget: u64,
        /// How to stay within it.
        raise: &'static str,
    },
    /// The scene holds something the reference cannot render.
    #[error("unsupported scene content: {0}")]
    Unsupported(String),
    /// An object reaches beyond [`caustics_scene::MAX_COORDINATE`] (or has a non-finite
    /// vertex): its BVH and intersection math would overflow `f32`. Scenes loaded from
    /// files never do (the loader refuses them); this guards scenes built in code.
    #[error(
        "object {object} ({kind}) reaches {reach} m from the origin: expected within ±{max:e} m",
        max = caustics_scene::MAX_COORDINATE
    )]
    OutOfRange {
        /// Index of the object in the scene.
        object: usize,
        /// Its shape kind (`mesh`, `sphere`, …).
        kind: &'static str,
        /// The largest |coordinate| it reaches (∞ or NaN for a non-finite vertex).
        reach: f32,
    },
}

/// How much to trace.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceOptions {
    /// Photons to trace (rounded up to whole work units: the exact count is in
    /// [`ReferenceResult::photons`]).
    pub photons: u64,
    /// Independent batches behind the standard-error images (default 16, ≥ 2).
    pub batches: u32,
    /// Seed of the random streams (default 1).
    pub seed: u64,
    /// Also render the direct image (L D E), emitting as many photons again over the
    /// whole scene.
    pub direct: bool,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions {
            photons: 1 << 20,
            batches: 16,
            seed: 1,
            direct: false,
        }
    }
}

/// An RGB radiance image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, radiance in W·m⁻²·sr⁻¹ per channel.
    pub pixels: Vec<[f32; 3]>,
}

impl ReferenceImage {
    /// The pixel at column `x`, row `y` (row 0 at the top).
    ///
    /// # Panics
    /// If (x, y) is outside the image.
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// What a render produced.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceResult {
    /// The surface caustic image (L S+ D E).
    pub caustic: ReferenceImage,
    /// Per-pixel standard error of `caustic`.
    pub caustic_stderr: ReferenceImage,
    /// The volume caustic image (L S+ M E): `Some` iff the scene has a medium.
    pub volume: Option<ReferenceImage>,
    /// Per-pixel standard error of `volume`.
    pub volume_stderr: Option<ReferenceImage>,
    /// The direct image (L D E), if asked for.
    pub direct: Option<ReferenceImage>,
    /// Photons traced for the caustic images (as many again for the direct image).
    pub photons: u64,
    /// Wall time of the render in seconds.
    pub seconds: f64,
}

/// A scene prepared for light tracing: geometry with its BVH, emitters, camera.
pub struct Reference {
    /// What a render's images and batch sums may hold, bytes.
    memory_budget_bytes: u64,
    geometry: Geometry,
    materials: Vec<Material>,
    medium: Option<Medium>,
    sensor: Sensor,
    caustic: Emitter,
    direct: Emitter,
}

impl Reference {
    /// Prepares `scene`: intersection structures (a grid per heightfield, a BVH
    /// over mesh triangles) and the emission setup.
    pub fn new(scene: &Scene) -> Result<Self, ReferenceError> {
        if scene.camera.width == 0 || scene.camera.height == 0 {
            return Err(ReferenceError::Unsupported(
                "a camera image with no pixels".into(),
            ));
        }
        check_range(scene)?;
        Ok(Reference {
            memory_budget_bytes: default_memory_budget(),
            geometry: Geometry::new(scene),
            materials: scene
                .objects
                .iter()
                .map(|o| scene.material(o).clone())
                .collect(),
            medium: scene.medium.clone(),
            sensor: Sensor::new(&scene.camera),
            caustic: Emitter::new(scene, Target::Specular),
            direct: Emitter::new(scene, Target::Scene),
        })
    }

    /// The same, with renders bounded by `bytes` of memory for their images and batch
    /// sums (default [`default_memory_budget`]).
    pub fn with_memory_budget(mut self, bytes: u64) -> Self {
        self.memory_budget_bytes = bytes;
        self
    }

    /// Traces `opts.photons` photons (rounded up to whole work units; the exact count
    /// is in the result), calling `progress(photons_done)` from time to time.
    pub fn render(
        &self,
        opts: &ReferenceOptions,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<ReferenceResult, ReferenceError> {
        check(opts)?;
        let plan = Plan::for_photons(opts.photons, opts.batches);
        Ok(self.run(plan, None, opts, progress, None, true)?.0)
    }

    /// Traces until `seconds` have passed (whole rounds: one unit more in every
    /// batch), returning how many photons were traced; re-rendering with that photon
    /// count gives the same image bit for bit. At least one round is traced.
    pub fn render_for(
        &self,
        seconds: f64,
        opts: &ReferenceOptions,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<ReferenceResult, ReferenceError> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(ReferenceError::BadSeconds { seconds });
        }
        check(&ReferenceOptions {
            photons: 1,
            ..opts.clone()
        })?;
        let plan = Plan {
            unit: UNIT_PHOTONS,
            rounds: u64::MAX,
            batches: opts.batches,
        };
        Ok(self.run(plan, Some(seconds), opts, progress, None, true)?.0)
    }

    /// Test hook: the mean power (W, RGB) per traced sample of the caustic photons
    /// landing on diffuse surfaces after ≥ 1 specular event where `filter(object,
    /// point)` holds, for the same photons as [`Reference::render`] with `opts`. The
    /// mean over photons is an unbiased estimate of that power.
    #[doc(hidden)]
    pub fn caustic_power(
        &self,
        opts: &ReferenceOptions,
        filter: &(dyn Fn(usize, Vec3) -> bool + Sync),
    ) -> Result<[f64; 3], ReferenceError> {
        check(opts)?;
        let plan = Plan::for_photons(opts.photons, opts.batches);
        let opts = ReferenceOptions {
            direct: false,
            ..opts.clone()
        };
        Ok(self.run(plan, None, &opts, &|_| {}, Some(filter), false)?.1)
    }

    fn run(
        &self,
        plan: Plan,
        seconds: Option<f64>,
        opts: &ReferenceOptions,
        progress: &(dyn Fn(u64) + Sync),
        power_filter: Option<PowerFilter<'_>>,
        connect: bool,
    ) -> Result<(ReferenceResult, [f64; 3]), ReferenceError> {
        let start = Instant::now();
        let tracer = Tracer {
            geometry: &self.geometry,
            materials: &self.materials,
            medium: self.medium.as_ref(),
            sensor: &self.sensor,
            caustic: &self.caustic,
            direct: opts.direct.then_some(&self.direct),
            power_filter,
            connect,
        };
        let pixels = if connect { self.sensor.pixels() } else { 0 };
        let volume = self.medium.is_some();
        // Refused before anything image-sized is allocated; the batch sums, which grow
        // with the caustic's area, are checked as they grow.
        let fixed = Accumulator::fixed_bytes(plan.batches, pixels, volume, opts.direct);
        let raise = "lower camera.width and camera.height, or --batches";
        if fixed > self.memory_budget_bytes {
            return Err(ReferenceError::OverMemoryBudget {
                what: format!(
                    "the images of a {}x{} render ({} batches{}{})",
                    self.sensor.width,
                    self.sensor.height,
                    plan.batches,
                    if volume { ", volume" } else { "" },
                    if opts.direct { ", direct" } else { "" }
                ),
                needed: fixed,
                budget: self.memory_budget_bytes,
                raise,
            });
        }
        let mut acc = Accumulator::new(plan.batches, pixels, volume, opts.direct);
        let b = plan.batches as u64;
        // Rounds per group: enough units to keep every thread busy.
        let group = (2 * rayon::current_num_threads() as u64).div_ceil(b).max(1);
        let mut rounds = 0u64;
        // Splat buffers, reused by every group.
        let mut outs: Vec<UnitOutput> = Vec::new();
        while rounds < plan.rounds {
            let n = group.min(plan.rounds - rounds);
            let first = rounds * b;
            outs.resize_with((n * b) as usize, UnitOutput::default);
            outs.par_iter_mut()
                .enumerate()
                .for_each(|(i, out)| tracer.run_unit(opts.seed, first + i as u64, plan.unit, out));
            acc.add(first, &outs);
            let held = fixed + acc.stored_bytes();
            if held > self.memory_budget_bytes {
                return Err(ReferenceError::OverMemoryBudget {
                    what: format!(
                        "the batch sums of {} batches after {} photons (each batch stores the pixels its photons reached)",
                        plan.batches,
                        (rounds + n) * b * plan.unit as u64
                    ),
                    needed: held,
                    budget: self.memory_budget_bytes,
                    raise,
                });
            }
            rounds += n;
            progress(rounds * b * plan.unit as u64);
            if seconds.is_some_and(|s| start.elapsed().as_secs_f64() >= s) {
                break;
            }
        }
        let done = Plan { rounds, ..plan };
        let per_batch = rounds * plan.unit as u64;
        let image = |pixels: Vec<[f32; 3]>| ReferenceImage {
            width: self.sensor.width,
            height: self.sensor.height,
            pixels,
        };
        let (caustic, caustic_stderr) = acc.surface.finish(per_batch);
        let (volume, volume_stderr) = match &acc.volume {
            Some(v) => {
                let (m, e) = v.finish(per_batch);
                (Some(image(m)), Some(image(e)))
            }
            None => (None, None),
        };
        let n = done.photons() as f64;
        let direct = acc.direct.as_ref().map(|d| {
            image(
                d.chunks_exact(3)
                    .map(|p| [(p[0] / n) as f32, (p[1] / n) as f32, (p[2] / n) as f32])
                    .collect(),
            )
        });
        let power = acc.power.map(|p| p / n);
        Ok((
            ReferenceResult {
                caustic: image(caustic),
                caustic_stderr: image(caustic_stderr),
                volume,
                volume_stderr,
                direct,
                photons: done.photons(),
                seconds: start.elapsed().as_secs_f64(),
            },
            power,
        ))
    }
}

fn check(opts: &ReferenceOptions) -> Result<(), ReferenceError> {
    if opts.photons == 0 {
        return Err(ReferenceError::NoPhotons);
    }
    if !(2..=MAX_BATCHES).contains(&opts.batches) {
        return Err(ReferenceError::BadBatches {
            batches: opts.batches,
        });
    }
    Ok(())
}

/// Refuses an object beyond [`caustics_scene::MAX_COORDINATE`] before the BVH is built
/// (obvhs panics on the NaN costs of overflowing boxes).
fn check_range(scene: &Scene) -> Result<(), ReferenceError> {
    for (object, o) in scene.objects.iter().enumerate() {
        let reach = match &o.shape {
            // Per vertex: an Aabb's min/max would skip a NaN.
            caustics_scene::Shape::Mesh(m) => m.positions.iter().fold(0.0f32, |r, p| {
                let a = p.abs().max_element();
                if p.is_finite() {
                    r.max(a)
                } else {
                    f32::INFINITY
                }
            }),
            shape => {
                let b = shape.bounds();
                b.min.abs().max(b.max.abs()).max_element()
            }
        };
        if !reach.is_finite() || reach > caustics_scene::MAX_COORDINATE {
            return Err(ReferenceError::OutOfRange {
                object,
                kind: o.shape.kind(),
                reach,
            });
        }
    }
    Ok(())
}
