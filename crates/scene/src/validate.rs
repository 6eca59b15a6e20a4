//! From the raw file to the typed [`Scene`]: every check of DESIGN.md's scene format,
//! each error naming the exact JSON path of the bad value.

use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::animation::{
    Animation, Keyframe, MAX_KEYFRAMES, MAX_TIME_S, Motion, wave_angular_frequency,
};
use crate::light::{EnvironmentMap, Light, Material, Medium, NamedMaterial};
use crate::limits::{Limits, MAX_COORDINATE};
use crate::mesh::{Budget, MeshError, MeshTransform, invalid, load_gltf, load_obj};
use crate::raw::{self, RawLight, RawMaterial, RawScene, RawShape, Source};
use crate::shape::{Aabb, Heightfield, Shape, Wave};
use crate::{Camera, Object, Scene, SceneError};

/// Largest image side and heightfield resolution accepted.
pub(crate) const MAX_IMAGE_SIDE: u32 = 16384;
/// Largest heightfield vertex count per axis.
pub(crate) const MAX_RESOLUTION: u32 = 4096;
/// Largest |phase speed| of a wave (m/s).
const MAX_WAVE_SPEED_M_S: f32 = 1.0e4;

/// Parses and validates a whole document.
pub(crate) fn parse(
    text: &str,
    file: &Path,
    base_dir: &Path,
    limits: &Limits,
) -> Result<Scene, SceneError> {
    let src = Source { file, text };
    let raw = src.parse_scene()?;
    Builder {
        src: &src,
        base_dir,
        budget: RefCell::new(Budget::new(*limits)),
    }
    .build(raw)
}

struct Builder<'a> {
    src: &'a Source<'a>,
    base_dir: &'a Path,
    /// The triangles, vertices and mesh objects loaded so far.
    budget: RefCell<Budget>,
}

fn fmt_list(v: &[f32]) -> String {
    let parts: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    format!("[{}]", parts.join(", "))
}

impl Builder<'_> {
    fn err(&self, path: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.src.file.to_path_buf(),
            json_path: path.into(),
            message: message.into(),
        }
    }

    fn finite(&self, path: &str, x: f32) -> Result<f32, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(path, format!("expected a finite number, got {x}")))
        }
    }

    fn positive(&self, path: &str, x: f32) -> Result<f32, SceneError> {
        if self.finite(path, x)? > 0.0 {
            Ok(x)
        } else {
            Err(self.err(path, format!("expected a positive number, got {x}")))
        }
    }

    fn non_negative(&self, path: &str, x: f32) -> Result<f32, SceneError> {
        if self.finite(path, x)? >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(path, format!("expected a non-negative number, got {x}")))
        }
    }

    fn each<const N: usize>(
        &self,
        path: &str,
        v: [f32; N],
        check: impl Fn(&Self, &str, f32) -> Result<f32, SceneError>,
    ) -> Result<[f32; N], SceneError> {
        for (i, &x) in v.iter().enumerate() {
            check(self, &format!("{path}[{i}]"), x)?;
        }
        Ok(v)
    }

    fn point(&self, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        self.each(path, v, Self::finite).map(Vec3::from)
    }

    fn non_negative3(&self, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        self.each(path, v, Self::non_negative).map(Vec3::from)
    }

    fn unit_interval3(&self, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        self.each(path, v, |s, p, x| {
            if (0.0..=1.0).contains(&s.finite(p, x)?) {
                Ok(x)
            } else {
                Err(s.err(p, format!("expected a value in [0, 1], got {x}")))
            }
        })
        .map(Vec3::from)
    }

    fn direction3(&self, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let d = self.point(path, v)?;
        d.try_normalize().ok_or_else(|| {
            self.err(
                path,
                format!("expected a non-zero direction vector, got {}", fmt_list(&v)),
            )
        })
    }

    fn direction2(&self, path: &str, v: [f32; 2]) -> Result<Vec2, SceneError> {
        let d = Vec2::from(self.each(path, v, Self::finite)?);
        d.try_normalize().ok_or_else(|| {
            self.err(
                path,
                format!("expected a non-zero direction vector, got {}", fmt_list(&v)),
            )
        })
    }

    fn build(&self, raw: RawScene<'_>) -> Result<Scene, SceneError> {
        if raw.name.trim().is_empty() {
            return Err(self.err("name", "expected a non-empty scene name"));
        }
        let camera = self.camera(&raw.camera)?;
        if raw.lights.is_empty() {
            return Err(self.err("lights", "expected at least one light"));
        }
        let mut lights = Vec::with_capacity(raw.lights.len());
        let mut light_motion = Vec::with_capacity(raw.lights.len());
        for (i, l) in raw.lights.iter().enumerate() {
            let path = format!("lights[{i}]");
            let parsed = RawLight::parse(self.src, l, &path)?;
            let motion = parsed.motion().cloned();
            let light = self.light(&path, parsed)?;
            let motion = match motion {
                None => None,
                Some(m) => {
                    let mpath = format!("{path}.motion");
                    let pivot = match &light {
                        Light::Directional { .. } | Light::Environment { .. } => Vec3::ZERO,
                        Light::Point { position, .. }
                        | Light::Spot { position, .. }
                        | Light::Sphere { position, .. } => *position,
                    };
                    let m = self.motion(&mpath, &m, pivot)?;
                    if matches!(light, Light::Directional { .. }) && !m.is_rotation_only() {
                        return Err(self.err(
                            mpath,
                            "a directional light has no position: expected a rotation only (angular_velocity_deg or keyframes' rotate_deg), got a translation",
                        ));
                    }
                    Some(m)
                }
            };
            lights.push(light);
            light_motion.push(motion);
        }
        let medium = raw.medium.as_ref().map(|m| self.medium(m)).transpose()?;
        let mut materials = Vec::with_capacity(raw.materials.0.len());
        for (name, m) in &raw.materials.0 {
            let path = format!("materials.{name}");
            if name.is_empty() {
                return Err(self.err("materials", "expected non-empty material names"));
            }
            let parsed = RawMaterial::parse(self.src, m, &path)?;
            materials.push(NamedMaterial {
                name: name.clone(),
                material: self.material(&path, parsed)?,
            });
        }
        if raw.objects.is_empty() {
            return Err(self.err("objects", "expected at least one object"));
        }
        let mut objects = Vec::with_capacity(raw.objects.len());
        let mut object_motion = Vec::with_capacity(raw.objects.len());
        let mut wave_omega = Vec::with_capacity(raw.objects.len());
        for (i, o) in raw.objects.iter().enumerate() {
            let first = objects.len();
            let omega = self.object(i, o, &mut materials, &mut objects)?;
            let added = &objects[first..];
            let motion = match &o.motion {
                None => None,
                Some(m) => {
                    let mpath = format!("objects[{i}].motion");
                    let bounds = added
                        .iter()
                        .fold(Aabb::EMPTY, |b, o| b.union(&o.shape.bounds()));
                    let m = self.motion(&mpath, m, bounds.center())?;
                    if let Some(kind) = added
                        .iter()
                        .map(|o| &o.shape)
                        .find(|s| matches!(s, Shape::Quad { .. } | Shape::Heightfield(_)))
                        .map(Shape::kind)
                        .filter(|_| !m.is_translation_only())
                    {
                        return Err(self.err(
                            mpath,
                            format!(
                                "a {kind} moves by translation only (its axes follow from its normal, its waves from world x, z): expected no rotation, or make it a mesh"
                            ),
                        ));
                    }
                    Some(m)
                }
            };
            for k in 0..added.len() {
                object_motion.push(motion.clone());
                wave_omega.push(if k == 0 { omega.clone() } else { Vec::new() });
            }
        }
        let time = match raw.time {
            None => 0.0,
            Some(t) => self.time("time", t)?,
        };
        let animation = Animation {
            rest_objects: objects.clone(),
            rest_lights: lights.clone(),
            object_motion,
            light_motion,
            wave_omega,
        };
        let scene = Scene {
            name: raw.name,
            description: raw.description.unwrap_or_default(),
            source: self.src.file.to_path_buf(),
            camera,
            lights,
            medium,
            materials,
            objects,
            time: 0.0,
            animation: animation.moves().then(|| Arc::new(animation)),
        };
        scene.at_time(time)
    }

    /// An instant in seconds.
    fn time(&self, path: &str, t: f32) -> Result<f32, SceneError> {
        if self.finite(path, t)?.abs() > MAX_TIME_S {
            return Err(self.err(
                path,
                format!("expected a time in seconds within ±{MAX_TIME_S:e}, got {t}"),
            ));
        }
        Ok(t)
    }

    /// A `"motion"`, its pivot defaulting to `default_pivot`.
    fn motion(
        &self,
        path: &str,
        m: &raw::RawMotion,
        default_pivot: Vec3,
    ) -> Result<Motion, SceneError> {
        let p = |field: &str| format!("{path}.{field}");
        let pivot = match m.pivot {
            Some(v) => self.point(&p("pivot"), v)?,
            None => default_pivot,
        };
        let Some(keys) = &m.keyframes else {
            if m.velocity.is_none() && m.angular_velocity_deg.is_none() {
                return Err(self.err(
                    path,
                    "expected `velocity`, `angular_velocity_deg` or `keyframes`",
                ));
            }
            return Ok(Motion::Velocity {
                velocity: self.point(&p("velocity"), m.velocity.unwrap_or_default())?,
                angular_velocity_deg: self.point(
                    &p("angular_velocity_deg"),
                    m.angular_velocity_deg.unwrap_or_default(),
                )?,
                pivot,
            });
        };
        if m.velocity.is_some() || m.angular_velocity_deg.is_some() {
            return Err(self.err(
                path,
                "expected either `keyframes` or `velocity`/`angular_velocity_deg`, not both",
            ));
        }
        if keys.is_empty() || keys.len() > MAX_KEYFRAMES {
            return Err(self.err(
                p("keyframes"),
                format!("expected 1..={MAX_KEYFRAMES} keyframes, got {}", keys.len()),
            ));
        }
        let mut out: Vec<Keyframe> = Vec::with_capacity(keys.len());
        for (k, key) in keys.iter().enumerate() {
            let kp = |field: &str| format!("{path}.keyframes[{k}].{field}");
            let time = self.time(&kp("time"), key.time)?;
            if let Some(prev) = out.last().filter(|prev| time <= prev.time) {
                return Err(self.err(
                    kp("time"),
                    format!(
                        "expected a time after the previous keyframe's {} s (keyframes in increasing time), got {time}",
                        prev.time
                    ),
                ));
            }
            out.push(Keyframe {
                time,
                translate: self.point(&kp("translate"), key.translate)?,
                rotate_deg: self.point(&kp("rotate_deg"), key.rotate_deg)?,
            });
        }
        Ok(Motion::Keyframes { keys: out, pivot })
    }

    fn camera(&self, c: &raw::RawCamera) -> Result<Camera, SceneError> {
        let eye = self.point("camera.eye", c.eye)?;
        let target = self.point("camera.target", c.target)?;
        let up = self.direction3("camera.up", c.up)?;
        let fov = self.finite("camera.fov_y_deg", c.fov_y_deg)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err(
                "camera.fov_y_deg",
                format!("expected an angle in degrees in (0, 180), got {fov}"),
            ));
        }
        for (path, v) in [("camera.width", c.width), ("camera.height", c.height)] {
            if !(1..=MAX_IMAGE_SIDE).contains(&v) {
                return Err(self.err(
                    path,
                    format!("expected a size in pixels in 1..={MAX_IMAGE_SIDE}, got {v}"),
                ));
            }
        }
        let Some(forward) = (target - eye).try_normalize() else {
            return Err(self.err(
                "camera.target",
                "expected a point different from camera.eye",
            ));
        };
        if forward.cross(up).length() < 1e-4 {
            return Err(self.err(
                "camera.up",
                format!(
                    "expected a direction not parallel to the view direction (target - eye), got {}",
                    fmt_list(&c.up)
                ),
            ));
        }
        if let Some(e) = c.exposure.filter(|e| !(e.is_finite() && *e > 0.0)) {
            return Err(self.err(
                "camera.exposure",
                format!("expected a positive number (an exposure scale), got {e}"),
            ));
        }
        Ok(Camera {
            eye,
            target,
            up,
            fov_y_deg: fov,
            width: c.width,
            height: c.height,
            exposure: c.exposure,
        })
    }

    fn light(&self, path: &str, l: RawLight) -> Result<Light, SceneError> {
        let p = |field: &str| format!("{path}.{field}");
        Ok(match l {
            RawLight::Directional(d) => Light::Directional {
                direction: self.direction3(&p("direction"), d.direction)?,
                irradiance: self.non_negative3(&p("irradiance"), d.irradiance)?,
            },
            RawLight::Point(d) => Light::Point {
                position: self.point(&p("position"), d.position)?,
                intensity: self.non_negative3(&p("intensity"), d.intensity)?,
            },
            RawLight::Spot(d) => {
                let position = self.point(&p("position"), d.position)?;
                let direction = self.direction3(&p("direction"), d.direction)?;
                let intensity = self.non_negative3(&p("intensity"), d.intensity)?;
                let cone = self.finite(&p("cone_deg"), d.cone_deg)?;
                if !(cone > 0.0 && cone <= 90.0) {
                    return Err(self.err(
                        p("cone_deg"),
                        format!("expected a half angle in degrees in (0, 90], got {cone}"),
                    ));
                }
                if let Some(f) = d.falloff_deg {
                    let f = self.finite(&p("falloff_deg"), f)?;
                    if !(0.0..=cone).contains(&f) {
                        return Err(self.err(
                            p("falloff_deg"),
                            format!(
                                "expected an angle in degrees in [0, cone_deg = {cone}], got {f}"
                            ),
                        ));
                    }
                }
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    cone_deg: cone,
                    falloff_deg: d.falloff_deg,
                }
            }
            RawLight::Sphere(d) => Light::Sphere {
                position: self.point(&p("position"), d.position)?,
                radius: self.positive(&p("radius"), d.radius)?,
                radiance: self.non_negative3(&p("radiance"), d.radiance)?,
            },
            RawLight::Environment(d) => {
                let scale = match d.scale {
                    Some(v) => self.non_negative3(&p("scale"), v)?,
                    None => Vec3::ONE,
                };
                let map = match (&d.path, d.radiance) {
                    (Some(_), Some(_)) | (None, None) => {
                        return Err(self.err(
                            path,
                            "expected either `path` (a lat-long EXR map) or `radiance` (a constant sky), not both or neither",
                        ));
                    }
                    (None, Some(r)) => {
                        EnvironmentMap::constant(self.non_negative3(&p("radiance"), r)?)
                    }
                    (Some(file), None) => {
                        let resolved = self.base_dir.join(file);
                        let limits = self.budget.borrow().limits;
                        load_environment_map(&resolved, &limits).map_err(|why| {
                            self.err(p("path"), format!("{}: {why}", resolved.display()))
                        })?
                    }
                };
                Light::Environment {
                    map: Arc::new(map),
                    scale,
                }
            }
        })
    }

    fn medium(&self, m: &raw::RawMedium) -> Result<Medium, SceneError> {
        let sigma_s = self.non_negative3("medium.sigma_s", m.sigma_s)?;
        let sigma_a = self.non_negative3("medium.sigma_a", m.sigma_a)?;
        let g = self.finite("medium.g", m.g)?;
        if !(g > -1.0 && g < 1.0) {
            return Err(self.err("medium.g", format!("expected a value in (-1, 1), got {g}")));
        }
        Ok(Medium {
            sigma_s,
            sigma_a,
            g,
        })
    }

    fn material(&self, path: &str, m: RawMaterial) -> Result<Material, SceneError> {
        Ok(match m {
            RawMaterial::Diffuse(d) => Material::Diffuse {
                albedo: self.unit_interval3(&format!("{path}.albedo"), d.albedo)?,
            },
            RawMaterial::Dielectric(d) => Material::Dielectric {
                ior: self.ior(&format!("{path}.ior"), d.ior)?,
            },
            RawMaterial::Mirror(d) => Material::Mirror {
                reflectance: self.unit_interval3(&format!("{path}.reflectance"), d.reflectance)?,
            },
        })
    }

    fn ior(&self, path: &str, ior: f32) -> Result<f32, SceneError> {
        if self.finite(path, ior)? >= 1.0 {
            Ok(ior)
        } else {
            Err(self.err(
                path,
                format!("expected an index of refraction >= 1, got {ior}"),
            ))
        }
    }

    fn object(
        &self,
        i: usize,
        o: &raw::RawObject<'_>,
        materials: &mut Vec<NamedMaterial>,
        objects: &mut Vec<Object>,
    ) -> Result<Vec<f32>, SceneError> {
        let path = format!("objects[{i}].shape");
        let mut omega = Vec::new();
        let p = |field: &str| format!("{path}.{field}");
        let shape = match RawShape::parse(self.src, o.shape, &path)? {
            RawShape::Sphere(s) => Shape::Sphere {
                center: self.point(&p("center"), s.center)?,
                radius: self.positive(&p("radius"), s.radius)?,
            },
            RawShape::Quad(s) => Shape::Quad {
                center: self.point(&p("center"), s.center)?,
                normal: self.direction3(&p("normal"), s.normal)?,
                size: Vec2::from(self.each(&p("size"), s.size, Self::positive)?),
            },
            RawShape::Heightfield(s) => {
                let (field, w) = self.heightfield(&path, s)?;
                omega = w;
                Shape::Heightfield(field)
            }
            RawShape::Cylinder(s) => Shape::Cylinder {
                center: self.point(&p("center"), s.center)?,
                axis: self.direction3(&p("axis"), s.axis)?,
                radius: self.positive(&p("radius"), s.radius)?,
                height: self.positive(&p("height"), s.height)?,
            },
            RawShape::Mesh(m) => {
                self.mesh(i, &path, m, o, materials, objects)?;
                return Ok(omega);
            }
        };
        let b = shape.bounds();
        let reach = b.min.abs().max(b.max.abs()).max_element();
        if !reach.is_finite() || reach > MAX_COORDINATE {
            return Err(self.err(
                &path,
                format!(
                    "the shape reaches {reach} m from the origin: expected it within ±{MAX_COORDINATE:e} m (beyond, f32 geometry overflows in the BVH and on the GPU)"
                ),
            ));
        }
        let material = self.material_ref(i, o, materials)?;
        objects.push(Object { shape, material });
        Ok(omega)
    }

    /// The index of the material an object names.
    fn material_ref(
        &self,
        i: usize,
        o: &raw::RawObject<'_>,
        materials: &[NamedMaterial],
    ) -> Result<usize, SceneError> {
        let path = format!("objects[{i}].material");
        let Some(name) = &o.material else {
            return Err(self.err(
                path,
                "missing material name (required for every shape except glTF meshes)",
            ));
        };
        materials
            .iter()
            .position(|m| &m.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                self.err(
                    path,
                    format!(
                        "unknown material `{name}`; defined materials: {}",
                        if names.is_empty() {
                            "(none)".to_string()
                        } else {
                            names.join(", ")
                        }
                    ),
                )
            })
    }

    /// The heightfield and each wave's angular frequency (rad/s).
    fn heightfield(
        &self,
        path: &str,
        s: raw::RawHeightfield,
    ) -> Result<(Heightfield, Vec<f32>), SceneError> {
        let p = |field: &str| format!("{path}.{field}");
        let center = self.point(&p("center"), s.center)?;
        let size = Vec2::from(self.each(&p("size"), s.size, Self::positive)?);
        for (k, &r) in s.resolution.iter().enumerate() {
            if !(2..=MAX_RESOLUTION).contains(&r) {
                return Err(self.err(
                    format!("{path}.resolution[{k}]"),
                    format!("expected a vertex count in 2..={MAX_RESOLUTION}, got {r}"),
                ));
            }
        }
        let mut waves = Vec::with_capacity(s.waves.len());
        let mut omega = Vec::with_capacity(s.waves.len());
        for (k, w) in s.waves.iter().enumerate() {
            let wp = |field: &str| format!("{path}.waves[{k}].{field}");
            let wave = Wave {
                amplitude: self.non_negative(&wp("amplitude"), w.amplitude)?,
                wavelength: self.positive(&wp("wavelength"), w.wavelength)?,
                direction: self.direction2(&wp("direction"), w.direction)?,
                phase: self.finite(&wp("phase"), w.phase)?,
            };
            let speed = match w.speed_m_s {
                None => None,
                Some(c) if c.is_finite() && c.abs() <= MAX_WAVE_SPEED_M_S => Some(c),
                Some(c) => {
                    return Err(self.err(
                        wp("speed_m_s"),
                        format!(
                            "expected a phase speed in m/s within ±{MAX_WAVE_SPEED_M_S}, got {c}"
                        ),
                    ));
                }
            };
            omega.push(wave_angular_frequency(&wave, speed));
            waves.push(wave);
        }
        Ok((
            Heightfield {
                center,
                size,
                resolution: s.resolution,
                waves,
            },
            omega,
        ))
    }

    fn mesh(
        &self,
        i: usize,
        path: &str,
        m: raw::RawMesh,
        o: &raw::RawObject<'_>,
        materials: &mut Vec<NamedMaterial>,
        objects: &mut Vec<Object>,
    ) -> Result<(), SceneError> {
        let xf = match &m.transform {
            None => MeshTransform::default(),
            Some(t) => {
                let tp = |field: &str| format!("{path}.transform.{field}");
                MeshTransform {
                    translate: self.point(&tp("translate"), t.translate)?,
                    rotate_deg: self.point(&tp("rotate_deg"), t.rotate_deg)?,
                    scale: self.positive(&tp("scale"), t.scale)?,
                }
            }
        };
        let path_field = format!("{path}.path");
        let mesh_file = self.base_dir.join(&m.path);
        let mesh_err = |source: MeshError| SceneError::Mesh {
            file: self.src.file.to_path_buf(),
            json_path: path_field.clone(),
            mesh_file: mesh_file.clone(),
            source: Box::new(source),
        };
        if !mesh_file.is_file() {
            return Err(mesh_err(MeshError::Missing));
        }
        let budget = &mut *self.budget.borrow_mut();
        let ext = mesh_file
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "obj" => {
                let material = self.material_ref(i, o, materials)?;
                let mesh = load_obj(&mesh_file, &xf.matrix(), budget).map_err(mesh_err)?;
                objects.push(Object {
                    shape: Shape::Mesh(mesh),
                    material,
                });
            }
            "gltf" | "glb" => {
                let given = match o.material {
                    Some(_) => Some(self.material_ref(i, o, materials)?),
                    None => None,
                };
                let prims =
                    load_gltf(&mesh_file, self.base_dir, &xf.matrix(), budget).map_err(mesh_err)?;
                let stem = mesh_file
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                for prim in prims {
                    let material = match given {
                        Some(m) => m,
                        None => {
                            let (index, name, material) = prim.material;
                            let label = match (name, index) {
                                (Some(n), _) if !n.is_empty() => n,
                                (_, Some(k)) => k.to_string(),
                                _ => "default".into(),
                            };
                            check_derived(&material).map_err(|problem| {
                                mesh_err(invalid(format!("material {label}"), problem))
                            })?;
                            add_material(materials, format!("{stem}/{label}"), material)
                        }
                    };
                    objects.push(Object {
                        shape: Shape::Mesh(prim.mesh),
                        material,
                    });
                }
            }
            other => return Err(mesh_err(MeshError::Format(other.to_string()))),
        }
        Ok(())
    }
}

/// Largest environment map side (pixels).
pub(crate) const MAX_ENVIRONMENT_SIDE: u32 = 16384;

/// Reads a lat-long EXR map, its header checked before any pixel is allocated.
fn load_environment_map(path: &Path, limits: &Limits) -> Result<EnvironmentMap, String> {
    let bytes = std::fs::metadata(path)
        .map_err(|e| format!("cannot read the environment map: {e}"))?
        .len();
    if bytes > limits.max_file_bytes {
        return Err(format!(
            "the file is {bytes} bytes, past the limit of {} (--max-file-bytes)",
            limits.max_file_bytes
        ));
    }
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| format!("not a readable EXR file: {e}"))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| "an EXR file without layers".to_string())?;
    let size = header.layer_size;
    let (w, h) = (size.width(), size.height());
    if w == 0 || h == 0 || w > MAX_ENVIRONMENT_SIDE as usize || h > MAX_ENVIRONMENT_SIDE as usize {
        return Err(format!(
            "expected a map of 1..={MAX_ENVIRONMENT_SIDE} pixels per side, the file says {w}x{h}"
        ));
    }
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution: Vec2<usize>, _channels: &RgbaChannels| {
            vec![glam::Vec3::ZERO; resolution.width() * resolution.height()]
        },
        move |px: &mut Vec<glam::Vec3>, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            if let Some(p) = px.get_mut(pos.y() * w + pos.x()) {
                *p = glam::Vec3::new(r, g, b);
            }
        },
    )
    .map_err(|e| format!("cannot read the EXR pixels: {e}"))?;
    let pixels = image.layer_data.channel_data.pixels;
    if let Some(i) = pixels
        .iter()
        .position(|p| !(p.is_finite() && p.cmpge(glam::Vec3::ZERO).all()))
    {
        return Err(format!(
            "pixel ({}, {}) is {}: expected finite non-negative radiance",
            i % w,
            i / w,
            pixels[i]
        ));
    }
    Ok(EnvironmentMap {
        source: Some(path.to_path_buf()),
        width: w as u32,
        height: h as u32,
        pixels,
    })
}

/// A material derived from a glTF file must satisfy the same ranges as one written in
/// the scene file.
fn check_derived(m: &Material) -> Result<(), String> {
    let in_unit = |v: Vec3| v.is_finite() && v.cmpge(Vec3::ZERO).all() && v.cmple(Vec3::ONE).all();
    match m {
        Material::Dielectric { ior } if !(ior.is_finite() && *ior >= 1.0) => Err(format!(
            "material with KHR_materials_ior {ior}: expected >= 1"
        )),
        Material::Diffuse { albedo: c } | Material::Mirror { reflectance: c } if !in_unit(*c) => {
            Err(format!("material base colour {c} outside [0, 1]"))
        }
        _ => Ok(()),
    }
}

/// Appends a material derived from a file, reusing an identical one of the same name;
/// a different material of the same name gets the suffix `#2`, `#3`, …
fn add_material(materials: &mut Vec<NamedMaterial>, name: String, material: Material) -> usize {
    let mut candidate = name.clone();
    let mut k = 1;
    loop {
        match materials.iter().position(|m| m.name == candidate) {
            Some(idx) if materials[idx].material == material => return idx,
            Some(_) => {
                k += 1;
                candidate = format!("{name}#{k}");
            }
            None => {
                materials.push(NamedMaterial {
                    name: candidate,
                    material,
                });
                return materials.len() - 1;
            }
        }
    }
}
