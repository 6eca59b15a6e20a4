//! One work unit of photons: emission, specular transport, connections to the eye.
//!
//! A photon follows L S* and stops at its first diffuse hit (the project has no
//! diffuse bounces). In caustic mode it counts only after ≥ 1 specular event (L S+ D E
//! and, in a medium, L S+ M E); a photon whose first hit is diffuse is dropped. In
//! direct mode (L D E) only a first hit that is diffuse counts.
//!
//! Dielectrics choose reflection with probability R (exact unpolarized Fresnel, TIR
//! included) and refraction otherwise, so the photon power is unchanged (all orders
//! of internal reflection are traced); mirrors scale it by their reflectance. Paths
//! stop after [`MAX_SPECULAR`] specular events.
//!
//! Shading normals (DESIGN.md "Shading normals in light transport"): specular
//! directions are taken about the shading normal ns, which differs from the geometric
//! normal ng on triangle objects (interpolated vertex normals, a heightfield's
//! analytic normal; elsewhere ns = ng). Light transport with shading normals is not
//! symmetric (Veach 1997, §5.3; pbrt-v3 §16.1.3), so each specular vertex multiplies
//! the photon power, on top of the reflectance or the Fresnel choice, by the adjoint
//! factor of [`shading_factor`], for reflection and refraction alike; and the photon
//! is dropped exactly where ns and ng disagree about the side of ωi (where it came
//! from) or of ωo (where it goes). The η² of refraction is a separate matter: photons
//! carry flux, which crossing an interface keeps (times 1 − R), and they are turned
//! into radiance only at the diffuse receiver (`sensor.rs`), so no η² enters.
//!
//! With a medium (filling the whole scene, inside dielectrics too, DESIGN "homogeneous
//! everywhere"), each segment attenuates the photon by exp(−σt·ℓ) and the eye
//! connection by exp(−σt·d). For the volume image one point per caustic segment is
//! drawn by free-flight sampling with the mean extinction σ̄, truncated to the segment
//! (ℓ = ∞ for photons leaving the scene), and connected to the eye with the
//! Henyey–Greenstein phase function; the RGB weight T(s)·σs / p(s) keeps it unbiased.

use caustics_scene::{Material, Medium};
use glam::Vec3A as Vec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

use crate::emission::Emitter;
use crate::eps;
use crate::geometry::{Geometry, Hit};
use crate::optics::{fresnel, henyey_greenstein, reflect, refract};
use crate::sensor::Sensor;

/// Most specular events on one photon path.
pub(crate) const MAX_SPECULAR: u32 = 64;

/// One contribution to an image: pixel index and RGB radiance (before dividing by
/// the number of photons).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Splat {
    pub(crate) pixel: u32,
    pub(crate) rgb: [f32; 3],
}

/// What one work unit produced.
#[derive(Default, Debug)]
pub(crate) struct UnitOutput {
    pub(crate) surface: Vec<Splat>,
    pub(crate) volume: Vec<Splat>,
    pub(crate) direct: Vec<Splat>,
    /// Photon power reaching diffuse surfaces through ≥ 1 specular event and passing
    /// the filter of [`Tracer::power_filter`] (the energy test hook).
    pub(crate) power: [f64; 3],
}

/// A filter on (object index, point) for the power hook.
pub(crate) type PowerFilter<'a> = &'a (dyn Fn(usize, glam::Vec3) -> bool + Sync);

/// Everything a unit needs, borrowed from the [`crate::Reference`].
pub(crate) struct Tracer<'a> {
    pub(crate) geometry: &'a Geometry,
    pub(crate) materials: &'a [Material],
    pub(crate) medium: Option<&'a Medium>,
    pub(crate) sensor: &'a Sensor,
    pub(crate) caustic: &'a Emitter,
    pub(crate) direct: Option<&'a Emitter>,
    pub(crate) power_filter: Option<PowerFilter<'a>>,
    /// Skip the eye connections (power hook only).
    pub(crate) connect: bool,
}

/// A small deterministic RNG for one unit: xoshiro256++ seeded through SplitMix64
/// from a hash of (seed, stream, unit).
pub(crate) struct UnitRng(Xoshiro256PlusPlus);

impl UnitRng {
    pub(crate) fn new(seed: u64, stream: u64, unit: u64) -> UnitRng {
        let mut h = seed ^ 0x9E37_79B9_7F4A_7C15;
        for v in [stream, unit] {
            h = splitmix(h ^ splitmix(v.wrapping_add(0x632B_E59B_D9B4_E019)));
        }
        UnitRng(Xoshiro256PlusPlus::seed_from_u64(h))
    }

    /// Uniform in [0, 1) with 24 random bits.
    #[inline]
    pub(crate) fn next(&mut self) -> f32 {
        (self.0.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The adjoint shading-normal factor of a specular vertex at `hit` for a photon that
/// arrived from `wi` and leaves along `wo` (unit vectors, both pointing away from the
/// surface): |ωi·ns|·|ωo·ng| / (|ωo·ns|·|ωi·ng|) (Veach 1997, §5.3, the adjoint BSDF
/// with shading normals; pbrt-v3's `CorrectShadingNormal`). `None` where ns and ng
/// disagree about the side of ωi or of ωo (a zero dot product counts as
/// disagreeing), and the photon is dropped. 1 where ns = ng. For a mirror
/// |ωi·ns| = |ωo·ns|, leaving |ωo·ng| / |ωi·ng|: the reflected beam's cross-section
/// over the incident one.
#[inline]
fn shading_factor(wi: Vec3, wo: Vec3, hit: &Hit) -> Option<f32> {
    let (i_s, i_g) = (wi.dot(hit.ns), wi.dot(hit.ng));
    let (o_s, o_g) = (wo.dot(hit.ns), wo.dot(hit.ng));
    if !(i_s * i_g > 0.0 && o_s * o_g > 0.0) {
        return None;
    }
    let k = (i_s * o_g / (o_s * i_g)).abs();
    // Finite for agreeing sides unless a product underflows; drop rather than splat NaN.
    k.is_finite().then_some(k)
}

#[inline]
fn exp3(v: Vec3) -> Vec3 {
    Vec3::new(v.x.exp(), v.y.exp(), v.z.exp())
}

impl Tracer<'_> {
    /// Traces unit `unit` of `count` photons (and as many direct photons if asked).
    /// `out` is cleared first; its buffers are reused (no allocation per unit once
    /// they have grown).
    pub(crate) fn run_unit(&self, seed: u64, unit: u64, count: u32, out: &mut UnitOutput) {
        out.surface.clear();
        out.volume.clear();
        out.direct.clear();
        out.power = [0.0; 3];
        if !self.caustic.is_empty() {
            let mut rng = UnitRng::new(seed, 0, unit);
            for _ in 0..count {
                self.trace(self.caustic, true, &mut rng, out);
            }
        }
        if let Some(direct) = self.direct.filter(|e| !e.is_empty()) {
            let mut rng = UnitRng::new(seed, 1, unit);
            for _ in 0..count {
                self.trace(direct, false, &mut rng, out);
            }
        }
    }

    fn trace(&self, emitter: &Emitter, caustic: bool, rng: &mut UnitRng, out: &mut UnitOutput) {
        let u = [rng.next(), rng.next(), rng.next(), rng.next()];
        let photon = emitter.sample(u, || rng.next());
        let (mut o, mut d, mut power) = (
            Vec3::from(photon.origin),
            Vec3::from(photon.dir),
            Vec3::from(photon.power),
        );
        if power.max_element() <= 0.0 {
            return;
        }
        let mut specular = 0u32;
        loop {
            let hit = self.geometry.intersect(o, d, f32::INFINITY);
            if let Some(m) = self.medium {
                let len = hit.map_or(f32::INFINITY, |h| h.t);
                if caustic && specular > 0 {
                    // Drawn even without connections, so the power hook and the
                    // images see the same photons.
                    let u = rng.next();
                    if self.connect {
                        self.scatter(m, o, d, len, power, u, &mut out.volume);
                    }
                }
                if hit.is_some() {
                    power *= exp3(-Vec3::from(m.sigma_t()) * len);
                }
            }
            let Some(hit) = hit else { return };
            match &self.materials[hit.object as usize] {
                Material::Diffuse { albedo } => {
                    if caustic == (specular > 0) {
                        self.land(&hit, d, power, (*albedo).into(), caustic, out);
                    }
                    return;
                }
                _ if !caustic || specular >= MAX_SPECULAR => return,
                Material::Mirror { reflectance } => {
                    let r = reflect(d, hit.ns);
                    let Some(k) = shading_factor(-d, r, &hit) else {
                        return;
                    };
                    power *= Vec3::from(*reflectance) * k;
                    d = r;
                }
                Material::Dielectric { ior } => {
                    let entering = d.dot(hit.ng) < 0.0;
                    let (n, n1, n2) = if entering {
                        (hit.ns, 1.0, *ior)
                    } else {
                        (-hit.ns, *ior, 1.0)
                    };
                    let (r, cos_t) = fresnel(-d.dot(n), n1, n2);
                    // Drawn before any drop, so a dropped photon leaves the random
                    // stream of the next ones as it was.
                    let new_d = if rng.next() < r {
                        reflect(d, n)
                    } else {
                        refract(d, n, n1 / n2, cos_t)
                    };
                    let Some(k) = shading_factor(-d, new_d, &hit) else {
                        return;
                    };
                    power *= k;
                    d = new_d;
                }
            }
            if power.max_element() <= 0.0 {
                return;
            }
            specular += 1;
            o = eps::offset_point_a(hit.p, hit.ng, d);
        }
    }

    /// A photon of `power` arriving along `d` at the diffuse `hit`: the power hook and
    /// the connection to the eye (module docs of [`crate::sensor`]).
    fn land(
        &self,
        hit: &Hit,
        d: Vec3,
        power: Vec3,
        albedo: Vec3,
        caustic: bool,
        out: &mut UnitOutput,
    ) {
        if caustic
            && let Some(filter) = self.power_filter
            && filter(hit.object as usize, hit.p.into())
        {
            for (acc, v) in out.power.iter_mut().zip(power.to_array()) {
                *acc += v as f64;
            }
        }
        if !self.connect {
            return;
        }
        let Some(proj) = self.sensor.project(hit.p) else {
            return;
        };
        let cos_x = proj.to_eye.dot(hit.ng);
        // The camera must see the side the light arrived on.
        if cos_x * d.dot(hit.ng) >= 0.0 || cos_x.abs() < eps::MIN_COS {
            return;
        }
        let origin = eps::offset_point_a(hit.p, hit.ng, proj.to_eye);
        let dist = (self.sensor.eye - origin).length();
        if self
            .geometry
            .occluded(origin, proj.to_eye, dist * (1.0 - eps::SHADOW_SHORTEN))
        {
            return;
        }
        let mut v = power * albedo * (std::f32::consts::FRAC_1_PI * cos_x.abs() * proj.importance);
        if let Some(m) = self.medium {
            v *= exp3(-Vec3::from(m.sigma_t()) * proj.dist);
        }
        let splat = Splat {
            pixel: proj.pixel,
            rgb: v.to_array(),
        };
        if caustic {
            out.surface.push(splat);
        } else {
            out.direct.push(splat);
        }
    }

    /// One single-scattering point on the caustic segment from `o` along `d` of
    /// length `len` (∞ if the photon leaves the scene), connected to the eye.
    #[allow(clippy::too_many_arguments)]
    fn scatter(
        &self,
        m: &Medium,
        o: Vec3,
        d: Vec3,
        len: f32,
        power: Vec3,
        u: f32,
        out: &mut Vec<Splat>,
    ) {
        if m.sigma_s.max_element() <= 0.0 {
            return;
        }
        let sigma_t = Vec3::from(m.sigma_t());
        let mean = sigma_t.element_sum() / 3.0;
        let (s, pdf) = if mean > 0.0 {
            // Free flight with rate σ̄, truncated to [0, len].
            let keep = if len.is_finite() {
                1.0 - (-mean * len).exp()
            } else {
                1.0
            };
            let s = -(1.0 - u * keep).ln() / mean;
            (s, mean * (-mean * s).exp() / keep)
        } else {
            return;
        };
        if !(s.is_finite() && pdf > 0.0) {
            return;
        }
        let x = o + s * d;
        let Some(proj) = self.sensor.project(x) else {
            return;
        };
        if self
            .geometry
            .occluded(x, proj.to_eye, proj.dist * (1.0 - eps::SHADOW_SHORTEN))
        {
            return;
        }
        let phase = henyey_greenstein(d.dot(proj.to_eye), m.g);
        let t = exp3(-sigma_t * (s + proj.dist));
        let v = power * t * Vec3::from(m.sigma_s) * (phase * proj.importance / pdf);
        if v.is_finite() {
            out.push(Splat {
                pixel: proj.pixel,
                rgb: v.to_array(),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(ns: Vec3, ng: Vec3) -> Hit {
        Hit {
            t: 1.0,
            p: Vec3::ZERO,
            ng,
            ns: ns.normalize(),
            object: 0,
        }
    }

    #[test]
    fn shading_factor_is_one_without_shading_normals() {
        let h = hit(Vec3::Y, Vec3::Y);
        let wi = Vec3::new(0.3, 0.8, -0.1).normalize();
        let wo = Vec3::new(-0.6, -0.5, 0.2).normalize();
        assert_eq!(shading_factor(wi, wo, &h), Some(1.0));
        assert_eq!(shading_factor(wi, reflect(-wi, Vec3::Y), &h), Some(1.0));
    }

    /// A mirror's factor is the ratio of the beams' cross-sections |ωo·ng| / |ωi·ng|;
    /// a side on which ns and ng disagree drops the photon.
    #[test]
    fn shading_factor_of_a_mirror_and_the_wrong_sides() {
        let ng = Vec3::Y;
        let ns = Vec3::new(0.2, 1.0, 0.0).normalize();
        let h = hit(ns, ng);
        let wi = Vec3::new(-0.5, 0.6, 0.0).normalize();
        let wo = reflect(-wi, ns);
        let k = shading_factor(wi, wo, &h).expect("both sides agree");
        assert!((k - wo.dot(ng) / wi.dot(ng)).abs() < 1e-6, "{k}");
        assert!((k - 1.0).abs() > 0.05, "the tilt must matter: {k}");
        // ωo grazing the facet from below while above per ns: dropped.
        let low = Vec3::new(1.0, -0.05, 0.0).normalize();
        assert!(low.dot(ns) > 0.0 && low.dot(ng) < 0.0);
        assert_eq!(shading_factor(wi, low, &h), None);
        // The same for ωi.
        assert_eq!(shading_factor(low, wo, &h), None);
    }
}
