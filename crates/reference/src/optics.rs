//! Specular optics and the phase function: exact unpolarized Fresnel, Snell,
//! mirror reflection, Henyey–Greenstein.

use glam::Vec3A as Vec3;

/// Reflects `d` (pointing toward the surface) about the unit normal `n`.
#[inline]
pub(crate) fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Exact unpolarized Fresnel reflectance (mean of s and p) for light going from a
/// medium of index `n1` into `n2`, with `cos_i` = |cos| of the incidence angle.
/// Returns (R, cos_t); R = 1 and cos_t = 0 under total internal reflection.
#[inline]
pub(crate) fn fresnel(cos_i: f32, n1: f32, n2: f32) -> (f32, f32) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = n1 / n2;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // rs = (a − b)/(a + b), rp = (c − e)/(c + e), over one division.
    let (a, b) = (n1 * cos_i, n2 * cos_t);
    let (c, e) = (n2 * cos_i, n1 * cos_t);
    let (sa, sc) = ((a - b) * (c + e), (c - e) * (a + b));
    let den = (a + b) * (c + e);
    if den <= 0.0 {
        // Grazing incidence (cos_i = 0): everything is reflected.
        return (1.0, cos_t);
    }
    (0.5 * (sa * sa + sc * sc) / (den * den), cos_t)
}

/// Refracts the unit direction `d` through a surface with unit normal `n` facing the
/// incoming side (d·n < 0), relative index `eta` = n1/n2 and transmitted cosine `cos_t`
/// (from [`fresnel`]).
#[inline]
pub(crate) fn refract(d: Vec3, n: Vec3, eta: f32, cos_t: f32) -> Vec3 {
    let cos_i = -d.dot(n);
    (eta * d + (eta * cos_i - cos_t) * n).normalize()
}

/// Henyey–Greenstein phase function (sr⁻¹) for the cosine between the propagation
/// direction of the light and the scattered direction.
#[inline]
pub(crate) fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * std::f32::consts::PI * denom * denom.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_normal_incidence_and_tir() {
        let (r, c) = fresnel(1.0, 1.0, 1.5);
        assert!((r - 0.04).abs() < 1e-6 && (c - 1.0).abs() < 1e-6);
        // Inside glass beyond the critical angle (41.8°): total internal reflection.
        let (r, _) = fresnel(45f32.to_radians().cos(), 1.5, 1.0);
        assert_eq!(r, 1.0);
        // Reciprocity: R is the same from both sides for the matching angles.
        let (r1, ct) = fresnel(0.7, 1.0, 1.5);
        let (r2, _) = fresnel(ct, 1.5, 1.0);
        assert!((r1 - r2).abs() < 1e-6);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3::Y;
        let d = Vec3::new(0.5, -(0.75f32).sqrt(), 0.0);
        let (_, ct) = fresnel(-d.dot(n), 1.0, 1.5);
        let t = refract(d, n, 1.0 / 1.5, ct);
        assert!((t.x - 0.5 / 1.5).abs() < 1e-6 && t.y < 0.0);
    }

    #[test]
    fn hg_is_normalized() {
        for g in [-0.5f32, 0.0, 0.7] {
            let n = 20000;
            let s: f32 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                    henyey_greenstein(c, g) * 2.0 * std::f32::consts::PI * 2.0 / n as f32
                })
                .sum();
            assert!((s - 1.0).abs() < 1e-3, "g = {g}: {s}");
        }
    }
}
