//! Test support for the method crates of caustics-bench (dev-only, never published).
//!
//! Each method crate owns the tests of its accuracy (`tests/accuracy.rs`): it renders a
//! small scene headless on whatever adapter the machine has (lavapipe on CI; without an
//! adapter a test fails with the install hint, it is never skipped), reads the caustic
//! targets back, and compares them with an analytic answer or with the independent CPU
//! reference at a stated bound. This crate is the plumbing they share, so that each test
//! reads as its scene, its method, its bound and why:
//!
//! - [`context`] opens the headless device; [`builtin`] / [`scene`] load a scene at a
//!   test's resolution; [`plane_hit`] finds what a pixel sees on a floor plane;
//! - [`Gpu`] uploads it and builds a method through its registry entry
//!   ([`Gpu::method`], JSON parameters, as the harness does) or directly; [`Gpu::measure`]
//!   records timed frames and one count frame ([`Measured`]: passes, times, pipeline
//!   statistics, fill counts, counters), and [`assert_counters_documented`] checks its
//!   counters against the method's docs; [`Gpu::surface`] & co. read the targets back;
//!   [`Gpu::scoring_frame`] averages sub-pixel offsets (DESIGN "Measuring honestly");
//! - [`reference`] renders the CPU reference at a fixed photon budget and seed, cached
//!   under the target folder by scene hash, resolution, photons, seed and the reference's
//!   own source;
//! - [`score`] takes every metric of caustics-metrics (flux ratio, relMSE after flux,
//!   HDR-FLIP, ...); [`compare`] does all of it for one method on one scene at the
//!   shared photon budget [`TEST_REFERENCE`], and [`Comparison::check`] holds it to
//!   [`Bounds`], refusing bounds too loose to see the image moved by one pixel;
//!   [`refracting_sphere`] is the method crates' comparison on the glass sphere (and why
//!   their bounds look alike);
//! - [`photon_hits`] holds the checks the two photon-hit methods share (light leak,
//!   determinism, parameter errors), each taking the method's registry entry;
//!   [`lights`] those of scenes with several lights (the caustic is the sum of each
//!   light's alone);
//! - [`Artifacts::ensure`] checks a bound and, when it fails, writes `<name>-actual`,
//!   `<name>-expected` and `<name>-difference` images and says where (STYLE 9).
//!
//! It depends on the shared crates only, never on the `caustics` harness (DESIGN
//! "Dependency direction": nothing depends on the harness).
//!
//! ```no_run
//! use caustics_testing::{Bounds, Gpu, TEST_REFERENCE, artifacts, builtin, compare};
//!
//! /// A method's test against the CPU reference (`info`: e.g. `caustics_method::registry_entry::<wavefront::Wavefront>()`).
//! fn close_to_the_reference(info: &caustics_method::MethodInfo) {
//!     let c = compare(info, builtin("sphere_on_plane", 96, 72), serde_json::json!({}), &TEST_REFERENCE, 4);
//!     // The bounds, and why each, beside them: ...
//!     let bounds = Bounds { flux: 0.85..1.02, rel_mse_after_flux: 5e-4, hdr_flip_after_flux: 0.47 };
//!     c.check(&artifacts!(), &bounds);
//! }
//!
//! /// A test of its own image and counters.
//! fn counts(info: &caustics_method::MethodInfo) {
//!     let gpu = Gpu::new(builtin("ring", 64, 48));
//!     let mut method = gpu.method(info, serde_json::json!({"grid": 16}));
//!     let measured = gpu.measure(method.as_mut(), 0, 1);
//!     let surface = gpu.surface();
//!     let mut expected = surface.clone();
//!     expected.set(10, 10, [0.25; 3]); // e.g. an analytic value
//!     let err = (surface.get(10, 10)[0] - 0.25).abs();
//!     artifacts!().ensure(err < 0.01, "surface", &surface, &expected, || {
//!         format!("{err} off at (10, 10); counters {:?}", measured.counters)
//!     });
//! }
//! # fn main() {}
//! ```

mod artifacts;
mod compare;
mod gpu;
pub mod lights;
pub mod photon_hits;
mod reference;
mod scenes;
mod score;

pub use artifacts::{Artifacts, target_dir};
pub use caustics_metrics::{Errors, HdrImage, ToneMap, luminance};
pub use caustics_reference::ReferenceOptions;
pub use compare::{
    Bounds, Comparison, TEST_REFERENCE, compare, refracting_sphere, refracting_sphere_with, shifted,
};
pub use gpu::{Gpu, Measured, Scored, assert_counters_documented, context};
pub use reference::{ReferenceImages, reference};
pub use scenes::{builtin, builtin_json, fresnel_reflectance, plane_hit, scene};
pub use score::{reference_tone, score};
