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
//! - **sphere** area light of radiance L and radius r: a point x uniform on its surface
//!   (pdf 1/A, A = 4πr²), then a direction uniform in the union of the cones from x
//!   towards the specular objects (as for a point light, aimed from x), weight
//!   L·cos θ·A·Ω(x)/(cones holding ω), 0 for directions into the sphere;
//! - **environment** light of radiance L(ω): a direction towards the sky drawn by
//!   importance, pixel ∝ luminance·sin θ of the lat-long map, uniform inside the pixel
//!   (solid-angle pdf p_pixel/(2π²·sin θ·Δu·Δv)); then, as for a directional light
//!   along −ω, a point on the union of discs ⟂ ω around the specular objects, weight
//!   L(ω)·Σ areas/(discs holding x)/pdf(ω) (the disc of the scene's bounding sphere
//!   for the direct image).
//!
//! Several lights: one is picked per photon with probability ∝ its total sampled
//! power, and the weight is divided by that probability. The extended lights draw the
//! numbers they need beyond four from the photon's stream (`more`), after the four the
//! other lights use, so adding them changed no other light's photons.

use std::f32::consts::{PI, TAU};

use caustics_scene::{Aabb, EnvironmentMap, Light, Scene, Shape, Vec3, perpendicular_frame};

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
        irradiance: Vec3,
        crossing: Crossing,
    },
    Point {
        position: Vec3,
        intensity: Vec3,
        light: Light,
        cones: Vec<Cone>,
        /// Cumulative solid angles.
        cdf: Vec<f32>,
    },
    Sphere {
        position: Vec3,
        radius: f32,
        radiance: Vec3,
        /// Bounding spheres (and boxes) the photons are aimed at.
        targets: Vec<(Vec3, f32, Aabb)>,
    },
    Environment(Box<EnvironmentSampler>),
}

/// Importance sampling of a lat-long map (pixel ∝ luminance·sin θ) and the discs the
/// photons cross, as for a directional light.
#[derive(Clone, Debug)]
struct EnvironmentSampler {
    map: std::sync::Arc<EnvironmentMap>,
    scale: Vec3,
    /// Cumulative row weights (length = height).
    rows: Vec<f64>,
    /// Per row, cumulative pixel weights (width × height, row-major).
    cols: Vec<f64>,
    /// Σ weights.
    total: f64,
    /// Bounding spheres the photons are aimed at.
    targets: Vec<(Vec3, f32, Aabb)>,
    /// The scene's bounds, for the photons' start plane.
    bounds: Aabb,
}

impl EnvironmentSampler {
    fn new(
        map: std::sync::Arc<EnvironmentMap>,
        scale: Vec3,
        targets: Vec<(Vec3, f32, Aabb)>,
        bounds: Aabb,
    ) -> EnvironmentSampler {
        let (w, h) = (map.width as usize, map.height as usize);
        let mut cols = Vec::with_capacity(w * h);
        let mut rows = Vec::with_capacity(h);
        let mut total = 0.0f64;
        for y in 0..h {
            let sin_theta = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            let mut acc = 0.0f64;
            for x in 0..w {
                let l = (map.pixels[y * w + x] * scale).element_sum() as f64 / 3.0;
                acc += l.max(0.0) * sin_theta;
                cols.push(acc);
            }
            total += acc;
            rows.push(total);
        }
        EnvironmentSampler {
            map,
            scale,
            rows,
            cols,
            total,
            targets,
            bounds,
        }
    }

    /// Draws a direction towards the sky: (ω, solid-angle pdf), or None for a black map.
    fn direction(&self, u1: f32, u2: f32, du: f32, dv: f32) -> Option<(Vec3, usize, f32)> {
        if self.total <= 0.0 {
            return None;
        }
        let (w, h) = (self.map.width as usize, self.map.height as usize);
        let target = f64::from(u1) * self.total;
        let y = self.rows.partition_point(|&c| c <= target).min(h - 1);
        let row = &self.cols[y * w..(y + 1) * w];
        let row_total = row[w - 1];
        if row_total <= 0.0 {
            return None;
        }
        let x = row
            .partition_point(|&c| c <= f64::from(u2) * row_total)
            .min(w - 1);
        let prev = if x == 0 { 0.0 } else { row[x - 1] };
        let p_pixel = (row[x] - prev) / self.total;
        let (u, v) = ((x as f32 + du) / w as f32, (y as f32 + dv) / h as f32);
        let dir = EnvironmentMap::direction(u, v);
        let sin_theta = (std::f32::consts::PI * v).sin();
        if p_pixel <= 0.0 || sin_theta <= 0.0 {
            return None;
        }
        // (u, v) ↦ ω has dΩ = 2π²·sin θ du dv; the pixel spans 1/w × 1/h of (u, v).
        let pdf = p_pixel as f32 * (w * h) as f32 / (2.0 * PI * PI * sin_theta);
        Some((dir, y * w + x, pdf))
    }
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
                    let crossing = Crossing::new(direction.normalize(), &spheres, &bounds);
                    let w = irradiance.element_sum() / 3.0 * crossing.area();
                    (
                        Sampler::Directional {
                            irradiance: *irradiance,
                            crossing,
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
                Light::Sphere {
                    position,
                    radius,
                    radiance,
                } => {
                    let targets = spheres.clone();
                    let from_centre: f32 = targets
                        .iter()
                        .map(|(c, r, b)| aim_cone(*position, *c, *r, b).solid_angle())
                        .sum();
                    // ≈ L·πr²·Ω: the flux towards the targets (only the choice of light
                    // depends on it, not the estimate).
                    let w = radiance.element_sum() / 3.0 * PI * radius * radius * from_centre;
                    (
                        Sampler::Sphere {
                            position: *position,
                            radius: *radius,
                            radiance: *radiance,
                            targets,
                        },
                        w,
                    )
                }
                Light::Environment { map, scale } => {
                    let sampler =
                        EnvironmentSampler::new(map.clone(), *scale, spheres.clone(), bounds);
                    let area: f32 = spheres.iter().map(|(_, r, _)| PI * r * r).sum();
                    // ≈ Σ_pixels L·ΔΩ × the targets' cross-section.
                    let w = (sampler.total * 2.0 * std::f64::consts::PI.powi(2)
                        / f64::from(map.width * map.height)) as f32
                        * area;
                    (Sampler::Environment(Box::new(sampler)), w)
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

    /// Draws a photon from four uniform numbers in [0, 1), and from `more` where an
    /// extended light needs more.
    #[inline]
    pub(crate) fn sample(&self, u: [f32; 4], mut more: impl FnMut() -> f32) -> Photon {
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
                irradiance,
                crossing,
            } => {
                let (origin, per_area) = crossing.sample(u0, u[1], u[2]);
                Photon {
                    origin,
                    dir: crossing.dir,
                    power: *irradiance * per_area,
                }
            }
            Sampler::Point {
                position,
                intensity,
                light,
                cones,
                cdf,
            } => {
                let (dir, count, omega_total) = in_cones(cones, cdf, u0, u[1], u[2]);
                Photon {
                    origin: *position,
                    dir,
                    power: *intensity * (light.angular_factor(dir) * omega_total / count as f32),
                }
            }
            Sampler::Sphere {
                position,
                radius,
                radiance,
                targets,
            } => {
                // x uniform on the sphere.
                let z = 1.0 - 2.0 * u[1];
                let rho = (1.0 - z * z).max(0.0).sqrt();
                let phi = TAU * u[2];
                let normal = Vec3::new(rho * phi.cos(), rho * phi.sin(), z);
                let origin = *position + *radius * normal;
                let cones: Vec<Cone> = targets
                    .iter()
                    .map(|(c, r, b)| aim_cone(origin, *c, *r, b))
                    .collect();
                let cdf = cumulative(cones.iter().map(Cone::solid_angle));
                let (u1, u2) = (more(), more());
                let (dir, count, omega_total) = in_cones(&cones, &cdf, u[3], u1, u2);
                let area = 4.0 * PI * radius * radius;
                let cos_out = normal.dot(dir).max(0.0);
                Photon {
                    // On the surface: the light is no object, nothing to start past.
                    origin,
                    dir,
                    power: *radiance * (cos_out * area * omega_total / count as f32),
                }
            }
            Sampler::Environment(env) => {
                let (u1, u2) = (u0, u[1]);
                let (du, dv) = (u[2], u[3]);
                let Some((sky, pixel, pdf)) = env.direction(u1, u2, du, dv) else {
                    return Photon {
                        origin: Vec3::ZERO,
                        dir: Vec3::Y,
                        power: Vec3::ZERO,
                    };
                };
                let crossing = Crossing::new(-sky, &env.targets, &env.bounds);
                let (u1, u2, u3) = (more(), more(), more());
                let (origin, per_area) = crossing.sample(u1, u2, u3);
                Photon {
                    origin,
                    dir: crossing.dir,
                    power: env.map.pixels[pixel] * env.scale * (per_area / pdf),
                }
            }
        };
        photon.power /= p_light;
        photon
    }
}

/// A direction uniform in the union of `cones` (one picked by `u_pick` ∝ its solid
/// angle, then uniform in it by `u1`, `u2`), the number of cones holding it, and the
/// union's summed solid angle: pdf(ω) = count / Σ Ω.
fn in_cones(cones: &[Cone], cdf: &[f32], u_pick: f32, u1: f32, u2: f32) -> (Vec3, usize, f32) {
    let c = &cones[pick(cdf, u_pick)];
    let cos_t = 1.0 - u1 * (1.0 - c.cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = TAU * u2;
    let dir = (cos_t * c.axis + sin_t * (phi.cos() * c.b1 + phi.sin() * c.b2)).normalize();
    let count = cones
        .iter()
        .filter(|o| dir.dot(o.axis) >= o.cos_max)
        .count()
        .max(1);
    (dir, count, cdf.last().copied().unwrap_or(0.0))
}

/// Parallel photons along `dir` through the union of discs ⟂ `dir` around the targets
/// (directional lights, and an environment's drawn direction): a point uniform on the
/// union, started on a plane 1 m before the whole scene.
#[derive(Clone, Debug)]
struct Crossing {
    dir: Vec3,
    b1: Vec3,
    b2: Vec3,
    /// Distance along `dir` of the start plane.
    start: f32,
    discs: Vec<Disc>,
    /// Cumulative disc areas.
    cdf: Vec<f32>,
}

impl Crossing {
    fn new(dir: Vec3, targets: &[(Vec3, f32, Aabb)], bounds: &Aabb) -> Crossing {
        let (b1, b2) = perpendicular_frame(dir);
        let discs: Vec<Disc> = targets
            .iter()
            .map(|(c, r, b)| Disc {
                center: *c - c.dot(dir) * dir,
                radius: disc_radius(dir, *c, *r, b),
            })
            .collect();
        let cdf = cumulative(discs.iter().map(|d| PI * d.radius * d.radius));
        let start = bounds.directional_start(dir);
        Crossing {
            dir,
            b1,
            b2,
            start,
            discs,
            cdf,
        }
    }

    /// Σ disc areas (m²).
    fn area(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// A start point (a disc picked by `u_pick` ∝ its area, uniform in it by `u1`,
    /// `u2`) and 1/pdf per unit irradiance: Σ areas / (discs holding the point).
    fn sample(&self, u_pick: f32, u1: f32, u2: f32) -> (Vec3, f32) {
        let d = &self.discs[pick(&self.cdf, u_pick)];
        let r = d.radius * u1.sqrt();
        let phi = TAU * u2;
        let x = d.center + r * (phi.cos() * self.b1 + phi.sin() * self.b2);
        let count = self
            .discs
            .iter()
            .filter(|o| (x - o.center).length_squared() <= o.radius * o.radius)
            .count()
            .max(1);
        (x + self.start * self.dir, self.area() / count as f32)
    }
}

/// Radius of the disc ⟂ `dir` around the projection of (`c`, `r`, box `b`): the
/// narrower of the sphere's silhouette and the disc through the box's projected corners.
fn disc_radius(dir: Vec3, c: Vec3, r: f32, b: &Aabb) -> f32 {
    let by_corners = b
        .corners()
        .iter()
        .map(|k| {
            let v = *k - c;
            (v - v.dot(dir) * dir).length()
        })
        .fold(0.0f32, f32::max);
    r.min(by_corners) * 1.000_01 + 1e-6
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
