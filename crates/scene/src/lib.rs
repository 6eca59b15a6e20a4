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

mod camera;
mod error;
mod hash;
mod light;
mod limits;
mod mesh;
mod raw;
mod shape;
mod tessellate;
mod validate;

use std::path::{Path, PathBuf};

pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

pub use camera::Camera;
pub use error::SceneError;
pub use light::{Light, Material, Medium, NamedMaterial};
pub use limits::{Limits, MAX_COORDINATE, format_bytes, parse_mib};
pub use mesh::{MeshError, MeshTransform, smooth_normals};
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
    /// The objects (a glTF file contributes one object per primitive).
    pub objects: Vec<Object>,
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
    /// and indices (so the referenced mesh files' content is covered). It does not
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

/// The folder of the built-in scenes: `<workspace>/scenes`.
pub fn builtin_dir() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .and_then(Path::parent)
        .unwrap_or(manifest)
        .join("scenes")
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
        })
    }
}
