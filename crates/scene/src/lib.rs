//! Scene format of caustics-bench: JSON loading, validation, shapes, tessellation and
//! the radiometry conventions of DESIGN.md. Pure data: no GPU.
//!
//! A scene file is validated on load; every error names the file, the JSON path of the
//! bad value and what was expected:
//!
//! ```
//! use caustics_scene::{Scene, Material, Tessellation};
//! use std::path::Path;
//!
//! let json = r#"{
//!   "name": "tiny",
//!   "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
//!              "fov_y_deg": 40, "width": 64, "height": 48},
//!   "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
//!   "materials": {"glass": {"type": "dielectric", "ior": 1.5},
//!                 "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
//!   "objects": [
//!     {"shape": {"type": "sphere", "center": [0, 1.5, 0], "radius": 1}, "material": "glass"},
//!     {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]},
//!      "material": "floor"}
//!   ]
//! }"#;
//! let scene = Scene::from_json_str(json, Path::new("tiny.json"))?;
//! assert!(scene.material(&scene.objects[0]).is_specular());
//! let mesh = scene.objects[0].shape.triangulate(&Tessellation::default());
//! assert_eq!(mesh.positions.len(), mesh.normals.len());
//!
//! let bad = json.replace("\"radius\": 1", "\"radius\": -1");
//! let err = Scene::from_json_str(&bad, Path::new("tiny.json")).unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "tiny.json: objects[0].shape.radius: expected a positive number, got -1"
//! );
//! # Ok::<(), caustics_scene::SceneError>(())
//! ```
//!
//! Built-in scenes live in the workspace's `scenes/` folder: [`builtin_names`],
//! [`resolve`].

mod animation;
mod camera;
mod error;
mod hash;
mod light;
mod limits;
mod mesh;
mod raw;
mod representative;
mod shape;
mod tessellate;
mod validate;

use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

pub use animation::{
    Animation, GRAVITY_M_S2, Keyframe, MAX_KEYFRAMES, MAX_TIME_S, Motion, RigidPose,
    wave_angular_frequency,
};
pub use camera::Camera;
pub use error::SceneError;
pub use light::{EnvironmentMap, Light, Material, Medium, NamedMaterial};
pub use limits::{Limits, MAX_COORDINATE, format_bytes, parse_mib};
pub use mesh::{MeshError, MeshTransform, smooth_normals};
pub use representative::MAX_REPRESENTATIVE_LIGHTS;
pub use shape::{Aabb, Heightfield, Mesh, Shape, Wave, perpendicular_frame, quad_axes};
pub use tessellate::{Tessellation, TriangleMesh};

/// A validated scene: camera, lights, optional medium, materials and objects.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The scene's `"name"`.
    pub name: String,
    /// The optional one-line `"description"`; empty if absent.
    pub description: String,
    /// The file it was loaded from (or the label given to [`Scene::from_json_str`]).
    pub source: PathBuf,
    /// The camera.
    pub camera: Camera,
    /// The lights (at least one).
    pub lights: Vec<Light>,
    /// The participating medium filling the scene, if any.
    pub medium: Option<Medium>,
    /// Materials in file order, then those derived from glTF files in load order.
    pub materials: Vec<NamedMaterial>,
    /// The objects (a glTF file contributes one object per primitive), posed at `time`.
    pub objects: Vec<Object>,
    /// The instant in seconds the objects and lights are posed at (the file's
    /// `"time"`, default 0; [`Scene::at_time`] poses another).
    pub time: f32,
    /// What moves (object and light motions, travelling waves); `None` for a still
    /// scene, which looks the same at every instant.
    pub animation: Option<Arc<Animation>>,
}

/// One object: a shape and the index of its material in [`Scene::materials`].
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

impl Scene {
    /// Reads and validates a scene file; mesh paths are relative to the file's folder.
    ///
    /// Meshes are checked against [`Limits::default`] (see [`Scene::load_with_limits`]).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with_limits(path, &Limits::default())
    }

    /// [`Scene::load`] with other resource limits (to load a larger mesh).
    pub fn load_with_limits(path: &Path, limits: &Limits) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Scene::from_json_str_with_limits(&text, path, limits)
    }

    /// Validates a scene given as JSON text. `source` names it in messages and its
    /// parent folder is the base of relative mesh paths.
    pub fn from_json_str(json: &str, source: &Path) -> Result<Scene, SceneError> {
        Scene::from_json_str_with_limits(json, source, &Limits::default())
    }

    /// [`Scene::from_json_str`] with other resource limits.
    pub fn from_json_str_with_limits(
        json: &str,
        source: &Path,
        limits: &Limits,
    ) -> Result<Scene, SceneError> {
        let base = source
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        validate::parse(json, source, base, limits)
    }

    /// True if anything in the scene changes with time.
    pub fn is_animated(&self) -> bool {
        self.animation.as_ref().is_some_and(|a| a.moves())
    }

    /// The scene posed at `t` seconds: a still scene that every method and the
    /// reference render as they render any scene (a still scene is returned as it is,
    /// its `time` set). Errors if `t` is not a finite time within ±[`MAX_TIME_S`] or
    /// a moving object leaves the coordinate range there.
    pub fn at_time(&self, t: f32) -> Result<Scene, SceneError> {
        let err = |json_path: String, message: String| SceneError::Invalid {
            file: self.source.clone(),
            json_path,
            message,
        };
        if !(t.is_finite() && t.abs() <= MAX_TIME_S) {
            return Err(err(
                "time".into(),
                format!("expected a time in seconds within ±{MAX_TIME_S:e}, got {t}"),
            ));
        }
        let mut posed = self.clone();
        posed.time = t;
        if let Some(a) = &self.animation {
            posed.objects = a.objects_at(t);
            posed.lights = a.lights_at(t);
            for (i, o) in posed.objects.iter().enumerate() {
                let b = o.shape.bounds();
                let reach = b.min.abs().max(b.max.abs()).max_element();
                if !reach.is_finite() || reach > MAX_COORDINATE {
                    return Err(err(
                        format!("objects[{i}].motion"),
                        format!(
                            "at time {t} s the object reaches {reach} m from the origin: expected it within ±{MAX_COORDINATE:e} m"
                        ),
                    ));
                }
            }
            for (i, l) in posed.lights.iter().enumerate() {
                let p = match l {
                    Light::Point { position, .. }
                    | Light::Spot { position, .. }
                    | Light::Sphere { position, .. } => *position,
                    Light::Directional { .. } | Light::Environment { .. } => Vec3::ZERO,
                };
                if !p.is_finite() || p.abs().max_element() > MAX_COORDINATE {
                    return Err(err(
                        format!("lights[{i}].motion"),
                        format!(
                            "at time {t} s the light is at {p}: expected it within ±{MAX_COORDINATE:e} m"
                        ),
                    ));
                }
            }
        }
        Ok(posed)
    }

    /// Bounds of all objects.
    pub fn bounds(&self) -> Aabb {
        self.objects
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(&o.shape.bounds()))
    }

    /// Bounds of the objects whose material is specular (the caustic generators), or
    /// `None` if there are none.
    pub fn specular_bounds(&self) -> Option<Aabb> {
        let b = self
            .specular_objects()
            .fold(Aabb::EMPTY, |b, o| b.union(&o.shape.bounds()));
        (!b.is_empty()).then_some(b)
    }

    /// The objects whose material is specular.
    pub fn specular_objects(&self) -> impl Iterator<Item = &Object> {
        self.objects
            .iter()
            .filter(|o| self.material(o).is_specular())
    }

    /// The material of `object`.
    ///
    /// # Panics
    /// If `object.material` is out of range (never for an object of a loaded scene).
    pub fn material(&self, object: &Object) -> &Material {
        &self.materials[object.material].material
    }

    /// A stable content hash of the validated scene, 16 hex digits.
    ///
    /// FNV-1a 64 over a canonical byte encoding of the typed scene (see `hash.rs`):
    /// name, description, camera, lights, medium, materials and objects, every float
    /// as its little-endian bits, mesh objects by their world-space positions, normals
    /// and indices (so the referenced mesh files' content is covered), and the instant
    /// of an animated scene posed away from t = 0 (a still scene, or any scene at
    /// t = 0, hashes as before animation existed). It does not
    /// depend on the JSON formatting, on key order inside an object, or on where the
    /// file lies (`source` and mesh paths are excluded).
    pub fn hash_hex(&self) -> String {
        format!("{:016x}", hash::scene_hash(self))
    }
}

/// The JSON Schema (draft 2020-12) of a scene file, generated from the types that read
/// it (committed as `schemas/scene.schema.json`; the parser checks more than it can
/// say: finite numbers, unit vectors, mesh files).
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(raw::scene_schema()).unwrap_or(serde_json::Value::Null)
}

/// Names the workspace (the folder holding `scenes/` and `bench/experiments/`) for a
/// binary that runs away from the checkout it was built in.
pub const ROOT_ENV: &str = "CAUSTICS_ROOT";

/// The workspace whose `scenes/` (and `bench/experiments/`) a run reads:
/// `CAUSTICS_ROOT` when set; else the checkout the binary was built in, while it still
/// holds `scenes/`; else the nearest folder at or above the current directory that
/// holds `scenes/` (a binary copied to a machine with a GPU, or installed, and run from
/// a checkout there); else the build checkout, which the errors then name.
pub fn workspace_root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let built = manifest.parent().and_then(Path::parent).unwrap_or(manifest);
    let declared = std::env::var_os(ROOT_ENV)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from);
    let cwd = std::env::current_dir().ok();
    choose_workspace_root(declared, built, cwd.as_deref())
}

/// [`workspace_root`]'s rule, apart from the process's environment.
fn choose_workspace_root(declared: Option<PathBuf>, built: &Path, cwd: Option<&Path>) -> PathBuf {
    if let Some(root) = declared {
        return root;
    }
    if built.join("scenes").is_dir() {
        return built.to_path_buf();
    }
    cwd.and_then(|c| c.ancestors().find(|a| a.join("scenes").is_dir()))
        .map_or_else(|| built.to_path_buf(), Path::to_path_buf)
}

/// The folder of the built-in scenes: `<workspace>/scenes` ([`workspace_root`]).
pub fn builtin_dir() -> PathBuf {
    workspace_root().join("scenes")
}

/// Sorted names (file stems) of the built-in scenes, `scenes/*.json`.
pub fn builtin_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(builtin_dir())
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "json"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

/// Resolves a built-in scene name (`"ring"`) or a path to a scene file.
///
/// An existing file is returned as is; a name with a `.json` extension or a path
/// separator that does not exist is an [`SceneError::Io`] error; any other name must be
/// a built-in scene, else [`SceneError::UnknownScene`] lists them.
pub fn resolve(name_or_path: &str) -> Result<PathBuf, SceneError> {
    let path = Path::new(name_or_path);
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let looks_like_path = path.extension().is_some_and(|e| e == "json")
        || name_or_path.contains('/')
        || name_or_path.contains('\\');
    if looks_like_path {
        return Err(SceneError::Io {
            file: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such scene file"),
        });
    }
    let builtin = builtin_dir().join(format!("{name_or_path}.json"));
    if builtin.is_file() {
        Ok(builtin)
    } else {
        Err(SceneError::UnknownScene {
            name: name_or_path.to_string(),
            available: builtin_names(),
            dir: builtin_dir(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::choose_workspace_root;

    /// A binary copied away from its checkout (the build path gone) finds the scenes of
    /// the checkout it runs in, from any folder inside it; `CAUSTICS_ROOT` wins over
    /// both; an intact build checkout wins over the current directory.
    #[test]
    fn workspace_root_follows_a_moved_binary() {
        let tmp = tempfile::tempdir().expect("temp dir");
        let checkout = tmp.path().join("checkout");
        let deep = checkout.join("results").join("runs");
        std::fs::create_dir_all(checkout.join("scenes")).expect("scenes");
        std::fs::create_dir_all(&deep).expect("deep");
        let gone = tmp.path().join("built-here-then-removed");
        let elsewhere = tmp.path().join("elsewhere");
        std::fs::create_dir_all(&elsewhere).expect("elsewhere");

        assert_eq!(choose_workspace_root(None, &gone, Some(&deep)), checkout);
        assert_eq!(
            choose_workspace_root(None, &gone, Some(&checkout)),
            checkout
        );
        // Nowhere to find scenes: the build path, which the unknown-scene error names.
        assert_eq!(choose_workspace_root(None, &gone, Some(&elsewhere)), gone);
        assert_eq!(choose_workspace_root(None, &gone, None), gone);
        // The build checkout while it exists, wherever the binary runs.
        assert_eq!(
            choose_workspace_root(None, &checkout, Some(&elsewhere)),
            checkout
        );
        assert_eq!(
            choose_workspace_root(Some(elsewhere.clone()), &checkout, Some(&deep)),
            elsewhere
        );
    }
}
