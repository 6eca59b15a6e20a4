//! Time in a scene: rigid motion of objects and lights, and heightfield waves that
//! travel with their dispersion.
//!
//! A scene file describes its objects and lights at rest; an optional `"motion"` on an
//! object or a light gives a rigid pose for every instant (constant velocity and
//! angular velocity, or keyframes), and every heightfield wave travels along its
//! direction at its phase speed. [`Scene::at_time`](crate::Scene::at_time) poses the
//! rest geometry at an instant and returns a still scene, so every method and the
//! reference render an instant exactly as they render a still scene: nothing of one
//! instant is carried to the next.

use glam::{Quat, Vec3};

use crate::light::Light;
use crate::shape::{Heightfield, Shape};
use crate::{Object, Wave};

/// Standard gravity (m/s²) of the deep-water dispersion relation ω² = g·k.
pub const GRAVITY_M_S2: f32 = 9.81;

/// Largest |time| in seconds a scene may be posed at (f32 seconds keep ~0.06 ms there).
pub const MAX_TIME_S: f32 = 1.0e5;

/// Most keyframes of one motion.
pub const MAX_KEYFRAMES: usize = 4096;

/// One keyframe of a [`Motion::Keyframes`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Instant in seconds.
    pub time: f32,
    /// Translation from the rest pose in metres.
    pub translate: Vec3,
    /// Rotation from the rest pose about the pivot, as a rotation vector in degrees
    /// (unit axis × angle).
    pub rotate_deg: Vec3,
}

/// A rigid motion from the rest pose.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Constant velocity and angular velocity: at time t the rest pose is rotated by
    /// `angular_velocity_deg`·t about the pivot, then moved by `velocity`·t.
    Velocity {
        /// m/s.
        velocity: Vec3,
        /// Rotation vector per second (unit axis × degrees per second).
        angular_velocity_deg: Vec3,
        /// Centre of rotation at rest, in metres.
        pivot: Vec3,
    },
    /// Keyframes with strictly increasing times: translation interpolated linearly,
    /// rotation spherically (slerp); held before the first and after the last.
    Keyframes {
        /// At least one.
        keys: Vec<Keyframe>,
        /// Centre of rotation at rest, in metres.
        pivot: Vec3,
    },
}

/// A rigid pose: `p ↦ rotation·(p − pivot) + pivot + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidPose {
    /// Rotation about the pivot.
    pub rotation: Quat,
    /// Translation after the rotation.
    pub translation: Vec3,
    /// Centre of rotation.
    pub pivot: Vec3,
}

impl RigidPose {
    /// The pose that moves nothing.
    pub const IDENTITY: RigidPose = RigidPose {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
        pivot: Vec3::ZERO,
    };

    /// A point moved by the pose.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.rotation * (p - self.pivot) + self.pivot + self.translation
    }

    /// A direction turned by the pose (unit in, unit out).
    pub fn direction(&self, v: Vec3) -> Vec3 {
        (self.rotation * v).normalize()
    }
}

fn rotation_deg(v: Vec3) -> Quat {
    Quat::from_scaled_axis(v * std::f32::consts::PI / 180.0)
}

impl Motion {
    /// Its pose at `t` seconds.
    pub fn pose(&self, t: f32) -> RigidPose {
        match self {
            Motion::Velocity {
                velocity,
                angular_velocity_deg,
                pivot,
            } => RigidPose {
                rotation: rotation_deg(*angular_velocity_deg * t),
                translation: *velocity * t,
                pivot: *pivot,
            },
            Motion::Keyframes { keys, pivot } => {
                let at = |k: &Keyframe| RigidPose {
                    rotation: rotation_deg(k.rotate_deg),
                    translation: k.translate,
                    pivot: *pivot,
                };
                let next = keys.partition_point(|k| k.time <= t);
                match (next.checked_sub(1).map(|i| &keys[i]), keys.get(next)) {
                    (Some(a), Some(b)) => {
                        let s = (t - a.time) / (b.time - a.time);
                        let (pa, pb) = (at(a), at(b));
                        RigidPose {
                            rotation: pa.rotation.slerp(pb.rotation, s),
                            translation: pa.translation.lerp(pb.translation, s),
                            pivot: *pivot,
                        }
                    }
                    (Some(k), None) | (None, Some(k)) => at(k),
                    (None, None) => RigidPose::IDENTITY,
                }
            }
        }
    }

    /// True if the motion never rotates (quads and heightfields accept only these).
    pub fn is_translation_only(&self) -> bool {
        match self {
            Motion::Velocity {
                angular_velocity_deg,
                ..
            } => *angular_velocity_deg == Vec3::ZERO,
            Motion::Keyframes { keys, .. } => keys.iter().all(|k| k.rotate_deg == Vec3::ZERO),
        }
    }

    /// True if the motion never translates (directional lights accept only these).
    pub fn is_rotation_only(&self) -> bool {
        match self {
            Motion::Velocity { velocity, .. } => *velocity == Vec3::ZERO,
            Motion::Keyframes { keys, .. } => keys.iter().all(|k| k.translate == Vec3::ZERO),
        }
    }
}

/// The angular frequency ω (rad/s) of a wave: k·`speed_m_s` when the phase speed is
/// given, else deep-water gravity waves, ω = √(g·k).
pub fn wave_angular_frequency(wave: &Wave, speed_m_s: Option<f32>) -> f32 {
    let k = wave.wavenumber();
    match speed_m_s {
        Some(c) => k * c,
        None => (GRAVITY_M_S2 * k).sqrt(),
    }
}

/// What moves in a scene: the rest geometry and the motions that pose it.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// The objects at rest (the file's geometry; waves at their t = 0 phase).
    pub rest_objects: Vec<Object>,
    /// The lights at rest.
    pub rest_lights: Vec<Light>,
    /// Each object's motion (index-aligned with `rest_objects`).
    pub object_motion: Vec<Option<Motion>>,
    /// Each light's motion (index-aligned with `rest_lights`).
    pub light_motion: Vec<Option<Motion>>,
    /// Angular frequency (rad/s) of every wave of every heightfield object (empty for
    /// other objects); a wave's phase at t is its rest phase − ω·t, so it travels
    /// along its direction.
    pub wave_omega: Vec<Vec<f32>>,
}

impl Animation {
    /// True if anything in the scene changes with time.
    pub fn moves(&self) -> bool {
        self.object_motion.iter().any(Option::is_some)
            || self.light_motion.iter().any(Option::is_some)
            || self.wave_omega.iter().flatten().any(|&w| w != 0.0)
    }

    /// The objects posed at `t`.
    pub fn objects_at(&self, t: f32) -> Vec<Object> {
        self.rest_objects
            .iter()
            .zip(&self.object_motion)
            .zip(&self.wave_omega)
            .map(|((o, motion), omega)| {
                let pose = motion.as_ref().map_or(RigidPose::IDENTITY, |m| m.pose(t));
                Object {
                    shape: pose_shape(&o.shape, &pose, omega, t),
                    material: o.material,
                }
            })
            .collect()
    }

    /// The lights posed at `t`.
    pub fn lights_at(&self, t: f32) -> Vec<Light> {
        self.rest_lights
            .iter()
            .zip(&self.light_motion)
            .map(|(l, motion)| match motion {
                None => l.clone(),
                Some(m) => pose_light(l, &m.pose(t)),
            })
            .collect()
    }
}

fn pose_shape(shape: &Shape, pose: &RigidPose, wave_omega: &[f32], t: f32) -> Shape {
    match shape {
        Shape::Sphere { center, radius } => Shape::Sphere {
            center: pose.point(*center),
            radius: *radius,
        },
        Shape::Quad {
            center,
            normal,
            size,
        } => Shape::Quad {
            center: pose.point(*center),
            normal: pose.direction(*normal),
            size: *size,
        },
        Shape::Heightfield(f) => Shape::Heightfield(Heightfield {
            center: pose.point(f.center),
            size: f.size,
            resolution: f.resolution,
            waves: f
                .waves
                .iter()
                .zip(wave_omega.iter().chain(std::iter::repeat(&0.0)))
                .map(|(w, &omega)| Wave {
                    phase: if omega * t == 0.0 {
                        // The rest phase as written, bit for bit.
                        w.phase
                    } else {
                        // Kept in [0, 2π) so that f32 keeps its precision at large t
                        // (ω·t is taken in f64).
                        (f64::from(w.phase) - f64::from(omega) * f64::from(t))
                            .rem_euclid(std::f64::consts::TAU) as f32
                    },
                    ..w.clone()
                })
                .collect(),
        }),
        Shape::Cylinder {
            center,
            axis,
            radius,
            height,
        } => Shape::Cylinder {
            center: pose.point(*center),
            axis: pose.direction(*axis),
            radius: *radius,
            height: *height,
        },
        Shape::Mesh(m) => {
            let mut moved = m.clone();
            if *pose != RigidPose::IDENTITY {
                moved.positions.iter_mut().for_each(|p| *p = pose.point(*p));
                moved
                    .normals
                    .iter_mut()
                    .for_each(|n| *n = pose.direction(*n));
            }
            Shape::Mesh(moved)
        }
    }
}

fn pose_light(light: &Light, pose: &RigidPose) -> Light {
    match light {
        Light::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            direction: pose.direction(*direction),
            irradiance: *irradiance,
        },
        Light::Point {
            position,
            intensity,
        } => Light::Point {
            position: pose.point(*position),
            intensity: *intensity,
        },
        Light::Spot {
            position,
            direction,
            intensity,
            cone_deg,
            falloff_deg,
        } => Light::Spot {
            position: pose.point(*position),
            direction: pose.direction(*direction),
            intensity: *intensity,
            cone_deg: *cone_deg,
            falloff_deg: *falloff_deg,
        },
        Light::Sphere {
            position,
            radius,
            radiance,
        } => Light::Sphere {
            position: pose.point(*position),
            radius: *radius,
            radiance: *radiance,
        },
        // Validation gives an environment light no motion.
        Light::Environment { .. } => light.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys() -> Motion {
        Motion::Keyframes {
            keys: vec![
                Keyframe {
                    time: 0.0,
                    translate: Vec3::ZERO,
                    rotate_deg: Vec3::ZERO,
                },
                Keyframe {
                    time: 2.0,
                    translate: Vec3::new(2.0, 0.0, 0.0),
                    rotate_deg: Vec3::new(0.0, 90.0, 0.0),
                },
            ],
            pivot: Vec3::new(0.0, 0.0, 1.0),
        }
    }

    #[test]
    fn keyframes_interpolate_and_hold() {
        let m = keys();
        let mid = m.pose(1.0);
        assert!((mid.translation - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6);
        // Half of 90° about +y at the pivot (0, 0, 1): the pivot itself stays put.
        assert!((mid.point(Vec3::new(0.0, 0.0, 1.0)) - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-6);
        let (_, angle) = mid.rotation.to_axis_angle();
        assert!((angle.to_degrees() - 45.0).abs() < 1e-3);
        // Held before the first key and after the last.
        assert_eq!(m.pose(-1.0), m.pose(0.0));
        assert_eq!(m.pose(5.0), m.pose(2.0));
        assert!(!m.is_translation_only() && !m.is_rotation_only());
    }

    #[test]
    fn velocity_moves_linearly_and_turns_about_the_pivot() {
        let m = Motion::Velocity {
            velocity: Vec3::new(0.5, 0.0, 0.0),
            angular_velocity_deg: Vec3::new(0.0, 0.0, -180.0),
            pivot: Vec3::new(0.0, 1.0, 0.0),
        };
        let p = m.pose(1.0);
        // Half a turn about z through (0, 1, 0): (1, 1, 0) → (−1, 1, 0), then +0.5 x.
        assert!((p.point(Vec3::new(1.0, 1.0, 0.0)) - Vec3::new(-0.5, 1.0, 0.0)).length() < 1e-5);
        assert!((p.direction(Vec3::X) + Vec3::X).length() < 1e-5);
    }

    #[test]
    fn deep_water_waves_follow_their_dispersion() {
        let w = Wave {
            amplitude: 0.1,
            wavelength: 1.0,
            direction: glam::Vec2::X,
            phase: 0.0,
        };
        // ω² = g·k: a 1 m wave has a period of √(2π/g)·… = 0.8 s.
        let omega = wave_angular_frequency(&w, None);
        assert!((omega * omega - GRAVITY_M_S2 * std::f32::consts::TAU).abs() < 1e-3);
        assert!((std::f32::consts::TAU / omega - 0.8005).abs() < 1e-3);
        // A given phase speed c: ω = k·c, so the crest moves c metres per second.
        assert!((wave_angular_frequency(&w, Some(2.0)) - 2.0 * std::f32::consts::TAU).abs() < 1e-4);
    }
}
