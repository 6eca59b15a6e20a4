//! The pinhole camera as a sensor: where a point projects and the importance of a
//! connection to the eye.
//!
//! # The connection formula
//!
//! Put the image plane at distance 1 in front of the pinhole (DESIGN.md "Camera",
//! [`caustics_scene::Camera::ray_through_pixel`]). Its pixels are squares of side
//! s = 2·tan(fov_y/2)/height, area A_pix = s². A pixel's value is the average radiance
//! over its area (box filter):
//!
//! I_j = (1/A_pix) ∫_pixel L(u) du.
//!
//! A point u of the plane at angle θ_c from the optical axis lies at distance
//! 1/cos θ_c from the eye and sees the ray at angle θ_c, so du = dω / cos³θ_c.
//! A surface element dA at x, at distance d, with normal at angle θ_x to the direction
//! to the eye, subtends dω = cos θ_x dA / d². Hence
//!
//! I_j = ∫_A L(x→eye) · V(x) · cos θ_x / (A_pix · cos³θ_c · d²) · 1[x projects into j] dA.
//!
//! A Lambertian point reflects L = (ρ/π)·E(x), and photons of power Φ_k estimate the
//! irradiance measure (E dA ≈ Σ Φ_k δ(x − x_k)), so each photon landing at x_k adds
//!
//! ΔI_j = Φ_k · (ρ/π) · cos θ_x · V · T / (A_pix · cos³θ_c · d²)
//!
//! (T the medium's transmittance to the eye). For a single scattering point in a
//! medium, dω dt = dV / d² and the photon flux per unit length replaces E dA: a point
//! drawn at distance s on a photon segment with pdf p(s) adds
//! Φ·T_photon(s)·σ_s·f_HG(cos)·T_eye / (p(s) · A_pix · cos³θ_c · d²).
//!
//! Check: a uniformly lit floor facing the camera gives back I_j = ρ/π·E exactly,
//! because ∫ cos θ_x / (cos³θ_c d²) dA over a pixel's footprint is A_pix.
//! [`Sensor::project`] returns the factor 1/(A_pix·cos³θ_c·d²).

use caustics_scene::Camera;
use glam::Vec3A as Vec3;

use crate::eps;

/// A point's projection into the image.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projection {
    /// Row-major pixel index (row 0 at the top).
    pub(crate) pixel: u32,
    /// Distance from the point to the eye.
    pub(crate) dist: f32,
    /// Unit direction from the point to the eye.
    pub(crate) to_eye: Vec3,
    /// 1 / (A_pix · cos³θ_c · d²), see the module docs.
    pub(crate) importance: f32,
}

/// The camera of a scene, ready to project points.
#[derive(Clone, Debug)]
pub(crate) struct Sensor {
    pub(crate) eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// 1 / (tan(fov/2) · aspect) and 1 / tan(fov/2).
    scale_x: f32,
    scale_y: f32,
    inv_pixel_area: f32,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl Sensor {
    /// The sensor of `camera`.
    pub(crate) fn new(camera: &Camera) -> Sensor {
        let tan_half = (0.5 * camera.fov_y_rad()).tan();
        let s = 2.0 * tan_half / camera.height as f32;
        Sensor {
            eye: camera.eye.into(),
            forward: camera.forward().into(),
            right: camera.right().into(),
            up: camera.image_up().into(),
            scale_x: 1.0 / (tan_half * camera.aspect()),
            scale_y: 1.0 / tan_half,
            inv_pixel_area: 1.0 / (s * s),
            width: camera.width,
            height: camera.height,
        }
    }

    /// Number of pixels.
    pub(crate) fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Projects `x`; `None` if it is behind the camera or outside the image.
    #[inline]
    pub(crate) fn project(&self, x: Vec3) -> Option<Projection> {
        let v = x - self.eye;
        let z = v.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let inv_z = 1.0 / z;
        let ndc_x = v.dot(self.right) * inv_z * self.scale_x;
        let ndc_y = v.dot(self.up) * inv_z * self.scale_y;
        let px = 0.5 * (ndc_x + 1.0) * self.width as f32;
        let py = 0.5 * (1.0 - ndc_y) * self.height as f32;
        if !(px >= 0.0 && py >= 0.0 && px < self.width as f32 && py < self.height as f32) {
            return None;
        }
        let (i, j) = (
            (px as u32).min(self.width - 1),
            (py as u32).min(self.height - 1),
        );
        let dist = v.length();
        let inv_dist = 1.0 / dist;
        let cos_c = z * inv_dist;
        if cos_c < eps::MIN_COS {
            return None;
        }
        Some(Projection {
            pixel: j * self.width + i,
            dist,
            to_eye: -v * inv_dist,
            // 1 / (A_pix · cos³θ_c · d²) with cos θ_c = z / d.
            importance: self.inv_pixel_area * dist * (inv_z * inv_z * inv_z),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3 as SceneVec3;

    fn camera() -> Camera {
        Camera {
            eye: SceneVec3::new(0.3, 2.0, 3.0),
            target: SceneVec3::new(0.0, 0.0, 0.0),
            up: SceneVec3::Y,
            fov_y_deg: 50.0,
            width: 64,
            height: 48,
            exposure: None,
        }
    }

    #[test]
    fn projection_inverts_ray_through_pixel() {
        let cam = camera();
        let s = Sensor::new(&cam);
        for (i, j) in [(0u32, 0u32), (10, 40), (63, 47), (31, 24)] {
            let (o, d) = cam.ray_through_pixel(i as f32 + 0.5, j as f32 + 0.5);
            let p = s.project((o + 2.5 * d).into()).expect("in view");
            assert_eq!(p.pixel, j * cam.width + i);
            assert!((p.dist - 2.5).abs() < 1e-4);
        }
    }

    /// ∫ importance·cos θ_x over a plane facing the camera, sampled finely, is 1 per
    /// pixel: the identity behind the flat-floor check in the module docs.
    #[test]
    fn importance_integrates_to_one_per_pixel() {
        let cam = Camera {
            eye: SceneVec3::new(0.0, 5.0, 0.0),
            target: SceneVec3::ZERO,
            up: SceneVec3::Z,
            fov_y_deg: 60.0,
            width: 8,
            height: 6,
            exposure: None,
        };
        let s = Sensor::new(&cam);
        let n = 800;
        let half = 5.0 * (30f32.to_radians()).tan() * 8.0 / 6.0 + 0.5;
        let da = (2.0 * half / n as f32).powi(2);
        let mut sum = vec![0.0f64; 48];
        for a in 0..n {
            for b in 0..n {
                let x = Vec3::new(
                    -half + (a as f32 + 0.5) * 2.0 * half / n as f32,
                    0.0,
                    -half + (b as f32 + 0.5) * 2.0 * half / n as f32,
                );
                if let Some(p) = s.project(x) {
                    sum[p.pixel as usize] += (p.importance * p.to_eye.y * da) as f64;
                }
            }
        }
        for v in sum {
            assert!((v - 1.0).abs() < 0.02, "{v}");
        }
    }
}
