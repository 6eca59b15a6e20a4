//! Lights, the participating medium and materials.

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
