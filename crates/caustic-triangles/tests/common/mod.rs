//! What the caustic-triangles test files share: the method built directly (the tests
//! read its hits and per-vertex irradiance back) and the analytic Fresnel factor.

use caustic_triangles::{CausticTriangles, CausticTrianglesParams};
use caustics_gpu::RendererOptions;
use caustics_scene::Scene;
use caustics_testing::Gpu;

/// The uploaded scene with small shadow maps, and the method built directly, after one
/// frame.
pub(crate) fn run_concrete(
    scene: Scene,
    params: &CausticTrianglesParams,
) -> (Gpu, CausticTriangles) {
    let options = RendererOptions {
        shadow_resolution: 256,
        cube_shadow_resolution: 128,
    };
    let gpu = Gpu::with_options(scene, options);
    let mut m = CausticTriangles::new(&gpu.ctx, &gpu.renderer, params).expect("method");
    gpu.frame(&mut m);
    (gpu, m)
}
