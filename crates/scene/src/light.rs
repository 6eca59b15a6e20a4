//! Lights, the participating medium and materials.

use std::sync::Arc;

use glam::Vec3;

/// A light source (DESIGN.md, "Units").
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// A distant light: parallel rays.
    Directional {
        /// Unit direction in which the light travels (from the light into the scene).
        direction: Vec3,
        /// Irradiance in W·m⁻² on a surface facing the light, per RGB channel.
        irradiance: Vec3,
    },
    /// An isotropic point light.
    Point {
        /// Position in metres.
        position: Vec3,
        /// Radiant intensity in W·sr⁻¹, per RGB channel.
        intensity: Vec3,
    },
    /// A point light restricted to a cone, see [`Light::spot_factor`].
    Spot {
        /// Position in metres.
        position: Vec3,
        /// Unit axis of the cone (the direction the light points to).
        direction: Vec3,
        /// Radiant intensity in W·sr⁻¹ inside the cone, per RGB channel.
        intensity: Vec3,
        /// Half angle of the cone in degrees, in (0, 90].
        cone_deg: f32,
        /// Width in degrees of the smooth edge inside the cone, in [0, `cone_deg`].
        falloff_deg: Option<f32>,
    },
    /// A spherical area light: every point of its surface sends `radiance` into its
    /// outer hemisphere (a Lambertian emitter). Seen from afar it is a point light of
    /// intensity π·radius²·radiance in every direction; up close it casts the soft
    /// shadows and blurred caustics of an extended source. Not an occluder.
    Sphere {
        /// Centre in metres.
        position: Vec3,
        /// Radius in metres (> 0).
        radius: f32,
        /// Radiance in W·m⁻²·sr⁻¹ leaving its surface, per RGB channel.
        radiance: Vec3,
    },
    /// Light from infinitely far away in every direction: radiance by direction from
    /// a lat-long map ([`EnvironmentMap`]) times `scale`.
    Environment {
        /// The map (a constant one for a uniform sky).
        map: Arc<EnvironmentMap>,
        /// Multiplies the map, per RGB channel.
        scale: Vec3,
    },
}

impl Light {
    /// The angular factor of a spot light for a direction at angle θ from its axis,
    /// given `cos_angle` = cos θ (clamped to [−1, 1]), angles in degrees:
    ///
    /// - without falloff (`None` or `Some(0)`): 1 if θ ≤ `cone_deg`, else 0;
    /// - with falloff f > 0: t = clamp((`cone_deg` − θ) / f, 0, 1) and the factor is the
    ///   smoothstep t²(3 − 2t): 1 for θ ≤ cone − f, 0 for θ ≥ cone, smooth in between.
    pub fn spot_factor(cone_deg: f32, falloff_deg: Option<f32>, cos_angle: f32) -> f32 {
        let theta = cos_angle.clamp(-1.0, 1.0).acos().to_degrees();
        match falloff_deg {
            Some(f) if f > 0.0 => {
                let t = ((cone_deg - theta) / f).clamp(0.0, 1.0);
                t * t * (3.0 - 2.0 * t)
            }
            _ => {
                if theta <= cone_deg {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }

    /// Its kind as scene files name it.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Directional { .. } => "directional",
            Light::Point { .. } => "point",
            Light::Spot { .. } => "spot",
            Light::Sphere { .. } => "sphere",
            Light::Environment { .. } => "environment",
        }
    }

    /// True for the lights with an extent (sphere, environment), which only the
    /// reference renders exactly.
    pub fn is_extended(&self) -> bool {
        matches!(self, Light::Sphere { .. } | Light::Environment { .. })
    }

    /// The spot factor of this light for a unit direction `dir` leaving it: 1 for
    /// directional and point lights, [`Light::spot_factor`] for spots.
    pub fn angular_factor(&self, dir: Vec3) -> f32 {
        match self {
            Light::Spot {
                direction,
                cone_deg,
                falloff_deg,
                ..
            } => Light::spot_factor(*cone_deg, *falloff_deg, direction.dot(dir)),
            _ => 1.0,
        }
    }
}

/// A homogeneous participating medium filling the whole scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Scattering coefficient σs in m⁻¹, per RGB channel.
    pub sigma_s: Vec3,
    /// Absorption coefficient σa in m⁻¹, per RGB channel.
    pub sigma_a: Vec3,
    /// Henyey–Greenstein asymmetry parameter g in (−1, 1); 0 is isotropic.
    pub g: f32,
}

impl Medium {
    /// Extinction coefficient σt = σs + σa in m⁻¹.
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_s + self.sigma_a
    }
}

/// A surface material (DESIGN.md, "Units" and "Conventions").
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector: radiance = albedo/π · irradiance.
    Diffuse {
        /// Albedo per channel, in [0, 1].
        albedo: Vec3,
    },
    /// Smooth dielectric with exact unpolarized Fresnel; the outside has ior 1.
    Dielectric {
        /// Index of refraction, ≥ 1.
        ior: f32,
    },
    /// Perfect mirror reflecting `reflectance` at every angle, on both sides.
    Mirror {
        /// Reflectance per channel, in [0, 1].
        reflectance: Vec3,
    },
}

impl Material {
    /// True for dielectrics and mirrors: the objects that generate caustics.
    pub fn is_specular(&self) -> bool {
        !matches!(self, Material::Diffuse { .. })
    }
}

/// A material with the name it has in the scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedMaterial {
    /// The key in `"materials"`, or `"<file stem>/<name or index>"` for glTF materials.
    pub name: String,
    /// The material.
    pub material: Material,
}

/// Radiance by direction, infinitely far away: a lat-long (equirectangular) map in
/// Mitsuba 3's convention, y up, so maps made for Mitsuba scenes line up: the pixel at
/// (u, v) ∈ [0, 1)² (u to the right, v down) holds the radiance arriving from
/// d = (sin θ sin φ, cos θ, −sin θ cos φ) with θ = π v, φ = 2π (u − ½).
/// Pixels are constant over their area (what [`EnvironmentMap::radiance`] returns and
/// what the reference importance-samples).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    /// The EXR file it was read from (`None` for a constant map).
    pub source: Option<std::path::PathBuf>,
    /// Pixels along u.
    pub width: u32,
    /// Pixels along v.
    pub height: u32,
    /// Linear RGB radiance (W·m⁻²·sr⁻¹), row-major, row 0 at the zenith (v = 0).
    pub pixels: Vec<Vec3>,
}

impl EnvironmentMap {
    /// The same radiance from every direction (one pixel).
    pub fn constant(radiance: Vec3) -> EnvironmentMap {
        EnvironmentMap {
            source: None,
            width: 1,
            height: 1,
            pixels: vec![radiance],
        }
    }

    /// (u, v) of the unit direction `dir` (towards the sky).
    pub fn uv(dir: Vec3) -> (f32, f32) {
        let u = dir.x.atan2(-dir.z) / std::f32::consts::TAU + 0.5;
        let v = dir.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        (u, v)
    }

    /// The unit direction (towards the sky) of map coordinates (u, v).
    pub fn direction(u: f32, v: f32) -> Vec3 {
        let (theta, phi) = (std::f32::consts::PI * v, std::f32::consts::TAU * (u - 0.5));
        Vec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    }

    /// The pixel (x, y) holding direction `dir`.
    pub fn pixel(&self, dir: Vec3) -> (u32, u32) {
        let (u, v) = EnvironmentMap::uv(dir);
        let x = ((u * self.width as f32) as i64).clamp(0, i64::from(self.width) - 1) as u32;
        let y = ((v * self.height as f32) as i64).clamp(0, i64::from(self.height) - 1) as u32;
        (x, y)
    }

    /// Radiance arriving from the unit direction `dir` (towards the sky).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let (x, y) = self.pixel(dir);
        self.pixels[(y * self.width + x) as usize]
    }
}
