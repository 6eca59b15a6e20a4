//! Photon emission: where photons start, where they go, and the power each carries.
//!
//! Caustic photons are only useful if they meet a specular object first, so emission
//! is restricted to the specular objects' bounding volumes (`Target::Specular`):
//!
//! - **directional** light of irradiance E: a point is drawn uniformly on a union of
//!   discs in the plane ⟂ to the light (one disc per specular object: the exact
//!   silhouette disc of a sphere, else the disc bounding the projected corners of its
//!   box), a mixture with probability ∝ area; the photon weight is E / pdf(x) with
//!   pdf(x) = (number of discs holding x) / (Σ areas), so every ray through the union
//!   (and so every L S+ D E path) is counted exactly once: unbiased;
//! - **point/spot** light of intensity I: a direction is drawn uniformly in a union of
//!   cones (per specular object, the narrower of the cone subtending its bounding
//!   sphere and the cone through its box corners; the whole sphere of directions if
//!   the light is inside), weight I·spot(ω) / pdf(ω), pdf(ω) = (cones holding ω) / ΣΩ.
//!
//! The direct image (`Target::Scene`) emits over the whole scene instead: the disc of
//! the scene's bounding sphere, or all directions (a spot: its cone).
//!
//! Several lights: one is picked per photon with probability ∝ its total sampled
//! power, and the weight is divided by that probability.

use std::f32::consts::{PI, TAU};

use caustics_scene::{Aabb, Light, Scene, Shape, Vec3, perpendicular_frame};

/// What emission aims at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Target {
    /// The specular objects' bounding volumes (caustic paths only).
    Specular,
    /// The whole scene (direct lighting).
    Scene,
}

/// A photon leaving a light: origin, unit direction, power in W (RGB) for one sample.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Photon {
    pub(crate) origin: Vec3,
    pub(crate) dir: Vec3,
    pub(crate) power: Vec3,
}

#[derive(Clone, Debug)]
struct Disc {
    center: Vec3,
    radius: f32,
}

#[derive(Clone, Debug)]
struct Cone {
    axis: Vec3,
    b1: Vec3,
    b2: Vec3,
    cos_max: f32,
}

impl Cone {
    fn solid_angle(&self) -> f32 {
        TAU * (1.0 - self.cos_max)
    }
}

#[derive(Clone, Debug)]
enum Sampler {
    Directional {
        dir: Vec3,
        b1: Vec3,
        b2: Vec3,
        irradiance: Vec3,
        /// Distance along `dir` of a plane before the whole scene (photons start there).
        start: f32,
        discs: Vec<Disc>,
        /// Cumulative disc areas.
        cdf: Vec<f32>,
    },
    Point {
        position: Vec3,
        intensity: Vec3,
        light: Light,
        cones: Vec<Cone>,
        /// Cumulative solid angles.
        cdf: Vec<f32>,
    },
}

/// The emitters of a scene for one [`Target`].
pub(crate) struct Emitter {
    samplers: Vec<Sampler>,
    /// Cumulative selection weights of `samplers`.
    cdf: Vec<f32>,
}

/// Bounding spheres of the specular objects (exact for analytic spheres).
fn specular_spheres(scene: &Scene) -> Vec<(Vec3, f32, Aabb)> {
    scene
        .specular_objects()
        .map(|o| {
            let b = o.shape.bounds();
            match o.shape {
                Shape::Sphere { center, radius } => (center, radius, b),
                _ => (b.center(), b.bounding_sphere_radius(), b),
            }
        })
        .collect()
}

fn cone(axis: Vec3, cos_max: f32) -> Cone {
    let (b1, b2) = perpendicular_frame(axis);
    Cone {
        axis,
        b1,
        b2,
        cos_max: cos_max.clamp(-1.0, 1.0),
    }
}

fn cumulative(w: impl Iterator<Item = f32>) -> Vec<f32> {
    let mut acc = 0.0;
    w.map(|x| {
        acc += x;
        acc
    })
    .collect()
}

fn pick(cdf: &[f32], u: f32) -> usize {
    let total = cdf.last().copied().unwrap_or(0.0);
    let x = u * total;
    cdf.iter()
        .position(|&c| x < c)
        .unwrap_or(cdf.len().saturating_sub(1))
}

impl Emitter {
    /// The emitters of `scene` aimed at `target`.
    pub(crate) fn new(scene: &Scene, target: Target) -> Emitter {
        let bounds = scene.bounds();
        let spheres = match target {
            Target::Specular => specular_spheres(scene),
            Target::Scene => vec![(bounds.center(), bounds.bounding_sphere_radius(), bounds)],
        };
        let mut samplers = Vec::new();
        let mut weights = Vec::new();
        for light in &scene.lights {
            let (sampler, w) = match light {
                Light::Directional {
                    direction,
                    irradiance,
                } => {
                    let dir = direction.normalize();
                    let (b1, b2) = perpendicular_frame(dir);
                    let discs: Vec<Disc> = spheres
                        .iter()
                        .map(|(c, r, b)| {
                            let center = *c - c.dot(dir) * dir;
                            let by_corners = b
                                .corners()
                                .iter()
                                .map(|k| {
                                    let v = *k - *c;
                                    (v - v.dot(dir) * dir).length()
                                })
                                .fold(0.0f32, f32::max);
                            Disc {
                                center,
                                radius: r.min(by_corners) * 1.000_01 + 1e-6,
                            }
                        })
                        .collect();
                    let cdf = cumulative(discs.iter().map(|d| PI * d.radius * d.radius));
                    let start = bounds
                        .corners()
                        .iter()
                        .map(|k| k.dot(dir))
                        .fold(f32::INFINITY, f32::min)
                        - 1.0;
                    let w = irradiance.element_sum() / 3.0 * cdf.last().copied().unwrap_or(0.0);
                    (
                        Sampler::Directional {
                            dir,
                            b1,
                            b2,
                            irradiance: *irradiance,
                            start,
                            discs,
                            cdf,
                        },
                        w,
                    )
                }
                Light::Point {
                    position,
                    intensity,
                }
                | Light::Spot {
                    position,
                    intensity,
                    ..
                } => {
                    let cones: Vec<Cone> = match (target, light) {
                        (
                            Target::Scene,
                            Light::Spot {
                                direction,
                                cone_deg,
                                ..
                            },
                        ) => vec![cone(direction.normalize(), cone_deg.to_radians().cos())],
                        (Target::Scene, _) => vec![cone(Vec3::Y, -1.0)],
                        (Target::Specular, _) => spheres
                            .iter()
                            .map(|(c, r, b)| aim_cone(*position, *c, *r, b))
                            .collect(),
                    };
                    let cdf = cumulative(cones.iter().map(Cone::solid_angle));
                    let w = intensity.element_sum() / 3.0 * cdf.last().copied().unwrap_or(0.0);
                    (
                        Sampler::Point {
                            position: *position,
                            intensity: *intensity,
                            light: light.clone(),
                            cones,
                            cdf,
                        },
                        w,
                    )
                }
            };
            samplers.push(sampler);
            weights.push(w.max(0.0));
        }
        Emitter {
            samplers,
            cdf: cumulative(weights.into_iter()),
        }
    }

    /// True if no photon can carry power (no light, or nothing to aim at).
    pub(crate) fn is_empty(&self) -> bool {
        self.cdf.last().is_none_or(|&w| w <= 0.0)
    }

    /// Draws a photon from four uniform numbers in [0, 1).
    #[inline]
    pub(crate) fn sample(&self, u: [f32; 4]) -> Photon {
        let (li, p_light, u0) = if self.cdf.len() == 1 {
            // One light: chosen with probability 1, u[0] left as it is.
            (0, 1.0, u[0])
        } else {
            let total = self.cdf.last().copied().unwrap_or(0.0);
            let li = pick(&self.cdf, u[0]);
            let prev = if li == 0 { 0.0 } else { self.cdf[li - 1] };
            let p_light = (self.cdf[li] - prev) / total;
            // Reuse u[0] within the chosen light's interval for the light's own choice.
            let u0 = ((u[0] * total - prev) / (self.cdf[li] - prev)).clamp(0.0, 0.999_999_9);
            (li, p_light, u0)
        };
        let mut photon = match &self.samplers[li] {
            Sampler::Directional {
                dir,
                b1,
                b2,
                irradiance,
                start,
                discs,
                cdf,
            } => {
                let d = &discs[pick(cdf, u0)];
                let r = d.radius * u[1].sqrt();
                let phi = TAU * u[2];
                let x = d.center + r * (phi.cos() * *b1 + phi.sin() * *b2);
                let count = discs
                    .iter()
                    .filter(|o| (x - o.center).length_squared() <= o.radius * o.radius)
                    .count()
                    .max(1);
                let area_total = cdf.last().copied().unwrap_or(0.0);
                Photon {
                    origin: x + *start * *dir,
                    dir: *dir,
                    power: *irradiance * (area_total / count as f32),
                }
            }
            Sampler::Point {
                position,
                intensity,
                light,
                cones,
                cdf,
            } => {
                let c = &cones[pick(cdf, u0)];
                let cos_t = 1.0 - u[1] * (1.0 - c.cos_max);
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let phi = TAU * u[2];
                let dir =
                    (cos_t * c.axis + sin_t * (phi.cos() * c.b1 + phi.sin() * c.b2)).normalize();
                let count = cones
                    .iter()
                    .filter(|o| dir.dot(o.axis) >= o.cos_max)
                    .count()
                    .max(1);
                let omega_total = cdf.last().copied().unwrap_or(0.0);
                Photon {
                    origin: *position,
                    dir,
                    power: *intensity * (light.angular_factor(dir) * omega_total / count as f32),
                }
            }
        };
        photon.power /= p_light;
        photon
    }
}

/// The narrower of the cone from `apex` subtending the sphere (c, r) and the cone
/// through the corners of `b`; all directions if `apex` is inside either volume.
fn aim_cone(apex: Vec3, c: Vec3, r: f32, b: &Aabb) -> Cone {
    let to_c = c - apex;
    let dist = to_c.length();
    let mut best = cone(Vec3::Y, -1.0);
    if dist > r * 1.000_1 {
        let axis = to_c / dist;
        let sin_max = (r / dist).min(1.0);
        let cos_max = (1.0 - sin_max * sin_max).sqrt() * 0.999_99;
        best = cone(axis, cos_max);
    }
    if !b.contains(apex) {
        let axis = (b.center() - apex).normalize();
        let cos_max = b
            .corners()
            .iter()
            .map(|k| (*k - apex).normalize().dot(axis))
            .fold(1.0f32, f32::min);
        // A cone narrower than a hemisphere is convex, so it holds the whole box.
        if cos_max > 0.0 {
            let candidate = cone(axis, cos_max * 0.999_99);
            if candidate.solid_angle() < best.solid_angle() {
                best = candidate;
            }
        }
    }
    best
}
