//! The content hash of a scene: FNV-1a 64 over a canonical byte encoding.

use glam::{Vec2, Vec3};

use crate::{Light, Material, Scene, Shape};

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a 64 with helpers for the canonical encoding: strings as length (u64 LE) +
/// UTF-8 bytes, floats as their IEEE bits LE, enum variants as a one-byte tag.
struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(FNV_PRIME);
        }
    }
    fn u64(&mut self, x: u64) {
        self.bytes(&x.to_le_bytes());
    }
    fn u32(&mut self, x: u32) {
        self.bytes(&x.to_le_bytes());
    }
    fn tag(&mut self, t: u8) {
        self.bytes(&[t]);
    }
    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
    }
    fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    fn v2(&mut self, v: Vec2) {
        self.f32(v.x);
        self.f32(v.y);
    }
    fn v3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
}

/// FNV-1a 64 of `scene`'s canonical encoding (version-tagged, so a future change of
/// the encoding changes every hash instead of colliding).
pub(crate) fn scene_hash(scene: &Scene) -> u64 {
    let mut h = Fnv(FNV_OFFSET);
    h.str("caustics-scene-hash-v1");
    h.str(&scene.name);
    h.str(&scene.description);
    let c = &scene.camera;
    h.v3(c.eye);
    h.v3(c.target);
    h.v3(c.up);
    h.f32(c.fov_y_deg);
    h.u32(c.width);
    h.u32(c.height);
    h.u64(scene.lights.len() as u64);
    for l in &scene.lights {
        match l {
            Light::Directional {
                direction,
                irradiance,
            } => {
                h.tag(0);
                h.v3(*direction);
                h.v3(*irradiance);
            }
            Light::Point {
                position,
                intensity,
            } => {
                h.tag(1);
                h.v3(*position);
                h.v3(*intensity);
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cone_deg,
                falloff_deg,
            } => {
                h.tag(2);
                h.v3(*position);
                h.v3(*direction);
                h.v3(*intensity);
                h.f32(*cone_deg);
                match falloff_deg {
                    Some(f) => {
                        h.tag(1);
                        h.f32(*f);
                    }
                    None => h.tag(0),
                }
            }
            Light::Sphere {
                position,
                radius,
                radiance,
            } => {
                h.tag(3);
                h.v3(*position);
                h.f32(*radius);
                h.v3(*radiance);
            }
            Light::Environment { map, scale } => {
                h.tag(4);
                h.v3(*scale);
                h.u32(map.width);
                h.u32(map.height);
                map.pixels.iter().for_each(|p| h.v3(*p));
            }
        }
    }
    match &scene.medium {
        Some(m) => {
            h.tag(1);
            h.v3(m.sigma_s);
            h.v3(m.sigma_a);
            h.f32(m.g);
        }
        None => h.tag(0),
    }
    h.u64(scene.materials.len() as u64);
    for m in &scene.materials {
        h.str(&m.name);
        match &m.material {
            Material::Diffuse { albedo } => {
                h.tag(0);
                h.v3(*albedo);
            }
            Material::Dielectric { ior } => {
                h.tag(1);
                h.f32(*ior);
            }
            Material::Mirror { reflectance } => {
                h.tag(2);
                h.v3(*reflectance);
            }
        }
    }
    h.u64(scene.objects.len() as u64);
    for o in &scene.objects {
        h.u64(o.material as u64);
        match &o.shape {
            Shape::Sphere { center, radius } => {
                h.tag(0);
                h.v3(*center);
                h.f32(*radius);
            }
            Shape::Quad {
                center,
                normal,
                size,
            } => {
                h.tag(1);
                h.v3(*center);
                h.v3(*normal);
                h.v2(*size);
            }
            Shape::Heightfield(f) => {
                h.tag(2);
                h.v3(f.center);
                h.v2(f.size);
                h.u32(f.resolution[0]);
                h.u32(f.resolution[1]);
                h.u64(f.waves.len() as u64);
                for w in &f.waves {
                    h.f32(w.amplitude);
                    h.f32(w.wavelength);
                    h.v2(w.direction);
                    h.f32(w.phase);
                }
            }
            Shape::Cylinder {
                center,
                axis,
                radius,
                height,
            } => {
                h.tag(3);
                h.v3(*center);
                h.v3(*axis);
                h.f32(*radius);
                h.f32(*height);
            }
            Shape::Mesh(m) => {
                h.tag(4);
                h.u64(m.positions.len() as u64);
                m.positions.iter().for_each(|p| h.v3(*p));
                m.normals.iter().for_each(|n| h.v3(*n));
                h.u64(m.indices.len() as u64);
                m.indices.iter().for_each(|i| h.u32(*i));
                h.tag(u8::from(m.normals_from_file));
            }
        }
    }
    // The instant is part of the key of an animated scene (two instants may pose the
    // same geometry, e.g. outside a motion's keyframes, yet are different frames of a
    // sequence); appended only away from t = 0 so that every earlier hash holds.
    if scene.is_animated() && scene.time != 0.0 {
        h.str("time");
        h.f32(scene.time);
    }
    h.0
}
