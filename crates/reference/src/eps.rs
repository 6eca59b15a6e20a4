//! The epsilon policy, in one place.
//!
//! Geometry is intersected in `f32` (scenes are metres-sized, at most tens of metres
//! across, where an `f32` ulp is ≤ 2 µm). Robustness comes from three rules:
//!
//! 1. **Offset origins, never `t_min` hacks.** A ray leaving a surface starts at the hit
//!    point moved along the *geometric* normal, to the side the new direction goes, by
//!    [`RAY_OFFSET`] · (1 + max |coordinate|): a relative offset that stays many ulps
//!    above the rounding error of the hit point anywhere in the scene. Rays then accept
//!    any hit with t > [`T_MIN`].
//! 2. **Shadow rays stop short.** A connection of length d to the eye is tested for
//!    occluders on (`T_MIN`, d · (1 − [`SHADOW_SHORTEN`])).
//! 3. **Robust quadrics.** Spheres and cylinders are solved with the
//!    closest-point form of the quadratic (Ray Tracing Gems, ch. 7), which keeps full
//!    `f32` precision for rays that start far away (directional photons start outside
//!    the scene bounds).
//!
//! Radiometric sums are kept in `f64` (per-batch images); per-photon weights are `f32`.

/// Relative offset of a ray origin from the surface it leaves (see the module docs).
pub const RAY_OFFSET: f32 = 2e-5;

/// Smallest accepted hit distance (metres) for rays leaving an offset origin.
pub const T_MIN: f32 = 1e-6;

/// Relative shortening of a shadow (eye-connection) ray, so the eye itself or the
/// surface at the far end are never counted as occluders.
pub const SHADOW_SHORTEN: f32 = 1e-4;

/// Smallest |cos| between a connection and a surface (or the camera axis) that is
/// connected: below it the geometry term is numerically meaningless and its
/// contribution vanishes anyway (a grazing view of the surface).
pub const MIN_COS: f32 = 1e-6;

/// The offset of [`RAY_OFFSET`] for a point `p`: `RAY_OFFSET · (1 + max |p_i|)`.
#[inline]
pub fn offset_for(p: glam::Vec3) -> f32 {
    RAY_OFFSET * (1.0 + p.abs().max_element())
}

/// Moves `p` off the surface with geometric normal `ng` to the side of `dir`.
#[inline]
pub fn offset_point(p: glam::Vec3, ng: glam::Vec3, dir: glam::Vec3) -> glam::Vec3 {
    let o = offset_for(p);
    if ng.dot(dir) >= 0.0 {
        p + o * ng
    } else {
        p - o * ng
    }
}

/// [`offset_point`] for SIMD vectors.
#[inline]
pub(crate) fn offset_point_a(p: glam::Vec3A, ng: glam::Vec3A, dir: glam::Vec3A) -> glam::Vec3A {
    let o = RAY_OFFSET * (1.0 + p.abs().max_element());
    if ng.dot(dir) >= 0.0 {
        p + o * ng
    } else {
        p - o * ng
    }
}

/// The same policy as one string, for logs and result files.
pub const EPSILON_POLICY: &str = "f32 geometry; ray origins offset along the geometric normal by 2e-5*(1+max|p|) m to the outgoing side; t_min 1e-6 m; eye connections shortened by 1e-4 relative; robust closest-point quadrics; f64 per-batch accumulation";
