//! The scene file as written: serde types that mirror the JSON one to one.
//!
//! Parsing happens in two layers so that every error carries its exact JSON path:
//! the document is read into [`RawScene`], which keeps every tagged value (lights,
//! materials, shapes) as a borrowed [`RawValue`]; each of those is then read on its
//! own by [`parse_tagged`], first for its `"type"`, then into the variant's struct.
//! (serde's internally tagged enums buffer their content, which loses the path and the
//! line/column of errors inside them.) All structs deny unknown fields.

use std::fmt;
use std::path::Path;

use indexmap::IndexMap;
use serde::de::{DeserializeOwned, IgnoredAny, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::value::RawValue;

use crate::SceneError;

/// The top level of a scene file.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(
    title = "caustics-bench scene",
    description = "A scene file of caustics-bench: camera, lights, optional medium, named materials and objects (README, \"Scene files\"). Units: metres, W/m² (directional irradiance), W/sr (point and spot intensity). The loader checks more than this schema says (finite values, non-degenerate vectors, mesh files, limits)."
)]
pub(crate) struct RawScene<'a> {
    pub(crate) name: String,
    #[serde(default)]
    pub(crate) description: Option<String>,
    pub(crate) camera: RawCamera,
    #[serde(borrow)]
    #[schemars(with = "Vec<LightSchema>")]
    pub(crate) lights: Vec<&'a RawValue>,
    #[serde(default)]
    pub(crate) medium: Option<RawMedium>,
    #[serde(default, borrow)]
    #[schemars(with = "std::collections::BTreeMap<String, MaterialSchema>")]
    pub(crate) materials: UniqueMap<'a>,
    #[serde(borrow)]
    pub(crate) objects: Vec<RawObject<'a>>,
    /// The instant in seconds the scene is posed at (default 0); only matters where
    /// something moves (`motion`, heightfield waves).
    #[serde(default)]
    pub(crate) time: Option<f32>,
}

/// `"camera"`.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCamera {
    pub(crate) eye: [f32; 3],
    pub(crate) target: [f32; 3],
    #[serde(default = "default_up")]
    pub(crate) up: [f32; 3],
    pub(crate) fov_y_deg: f32,
    pub(crate) width: u32,
    pub(crate) height: u32,
    #[serde(default)]
    pub(crate) exposure: Option<f32>,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

/// `"medium"`.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMedium {
    pub(crate) sigma_s: [f32; 3],
    pub(crate) sigma_a: [f32; 3],
    #[serde(default)]
    pub(crate) g: f32,
}

/// One entry of `"objects"`.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawObject<'a> {
    #[serde(borrow)]
    #[schemars(with = "ShapeSchema")]
    pub(crate) shape: &'a RawValue,
    #[serde(default)]
    pub(crate) material: Option<String>,
    /// Rigid motion of the object from its rest pose (the shape as written).
    #[serde(default)]
    pub(crate) motion: Option<RawMotion>,
}

/// `"motion"` of an object or a light: either `velocity` and/or
/// `angular_velocity_deg` (constant, from the rest pose at t = 0), or `keyframes`;
/// `pivot` is the centre of rotation (default: the object's bounds centre, the light's
/// position).
#[derive(Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMotion {
    /// m/s.
    #[serde(default)]
    pub(crate) velocity: Option<[f32; 3]>,
    /// Rotation vector per second: unit axis × degrees per second.
    #[serde(default)]
    pub(crate) angular_velocity_deg: Option<[f32; 3]>,
    /// Poses at instants, strictly increasing in time; held outside their range.
    #[serde(default)]
    pub(crate) keyframes: Option<Vec<RawKeyframe>>,
    /// Centre of rotation at rest (m).
    #[serde(default)]
    pub(crate) pivot: Option<[f32; 3]>,
}

/// One keyframe: translation (m) and rotation vector (unit axis × degrees) from rest.
#[derive(Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawKeyframe {
    pub(crate) time: f32,
    #[serde(default)]
    pub(crate) translate: [f32; 3],
    #[serde(default)]
    pub(crate) rotate_deg: [f32; 3],
}

/// `"materials"`: a JSON object whose keys must be unique (serde maps keep the last
/// duplicate silently; a scene file with two materials of one name is an error).
#[derive(Default)]
pub(crate) struct UniqueMap<'a>(pub(crate) IndexMap<String, &'a RawValue>);

impl<'de: 'a, 'a> Deserialize<'de> for UniqueMap<'a> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct MapVisitor<'a>(std::marker::PhantomData<&'a ()>);
        impl<'de: 'a, 'a> Visitor<'de> for MapVisitor<'a> {
            type Value = UniqueMap<'a>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object mapping material names to materials")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = IndexMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    let value: &'a RawValue = map.next_value()?;
                    if out.contains_key(&key) {
                        return Err(serde::de::Error::custom(format!(
                            "duplicate material name `{key}`"
                        )));
                    }
                    out.insert(key, value);
                }
                Ok(UniqueMap(out))
            }
        }
        deserializer.deserialize_map(MapVisitor(std::marker::PhantomData))
    }
}

/// Reads only the `"type"` of a tagged value.
#[derive(Deserialize)]
#[serde(expecting = "an object with a \"type\" field")]
struct Tag {
    #[serde(rename = "type")]
    kind: String,
}

// Schema-only mirrors of the tagged values (parsing goes through `RawLight`,
// `RawMaterial` and `RawShape`, which read `"type"` first so that errors keep their path).
#[derive(schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
#[schemars(
    rename = "Light",
    description = "A light, by \"type\": directional (direction, irradiance in W/m²), point (position, intensity in W/sr), spot (position, direction, intensity in W/sr, cone_deg, optional falloff_deg), sphere (an area light: position, radius, radiance in W/m²/sr) or environment (radiance from every direction: a lat-long EXR `path` or a constant `radiance`, times an optional `scale`)."
)]
#[allow(dead_code)]
enum LightSchema {
    Directional(RawDirectional),
    Point(RawPoint),
    Spot(RawSpot),
    Sphere(RawSphereLight),
    Environment(RawEnvironment),
}

#[derive(schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
#[schemars(
    rename = "Material",
    description = "A material, by \"type\": diffuse (albedo), dielectric (ior) or mirror (reflectance)."
)]
#[allow(dead_code)]
enum MaterialSchema {
    Diffuse(RawDiffuse),
    Dielectric(RawDielectric),
    Mirror(RawMirror),
}

#[derive(schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
#[schemars(
    rename = "Shape",
    description = "A shape, by \"type\": sphere, quad, heightfield (with optional waves), cylinder (open) or mesh (an OBJ or glTF file relative to the scene file, with an optional transform). Metres throughout."
)]
#[allow(dead_code)]
enum ShapeSchema {
    Sphere(RawSphere),
    Quad(RawQuad),
    Heightfield(RawHeightfield),
    Cylinder(RawCylinder),
    Mesh(RawMesh),
}

/// The JSON Schema (draft 2020-12) of a scene file, from the types that read it.
pub(crate) fn scene_schema() -> schemars::Schema {
    schemars::schema_for!(RawScene<'static>)
}

/// `"lights"` entries.
pub(crate) enum RawLight {
    Directional(RawDirectional),
    Point(RawPoint),
    Spot(RawSpot),
    Sphere(RawSphereLight),
    Environment(RawEnvironment),
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSphereLight {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) position: [f32; 3],
    pub(crate) radius: f32,
    /// W·m⁻²·sr⁻¹ leaving the surface.
    pub(crate) radiance: [f32; 3],
    /// Rigid motion of the light from its rest pose.
    #[serde(default)]
    pub(crate) motion: Option<RawMotion>,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEnvironment {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    /// A lat-long EXR map relative to the scene file (Mitsuba 3's convention).
    #[serde(default)]
    pub(crate) path: Option<String>,
    /// A constant radiance from every direction instead (W·m⁻²·sr⁻¹).
    #[serde(default)]
    pub(crate) radiance: Option<[f32; 3]>,
    /// Multiplies the map (default 1).
    #[serde(default)]
    pub(crate) scale: Option<[f32; 3]>,
}

impl RawLight {
    /// The light's `"motion"`, if it has one.
    pub(crate) fn motion(&self) -> Option<&RawMotion> {
        match self {
            RawLight::Directional(l) => l.motion.as_ref(),
            RawLight::Point(l) => l.motion.as_ref(),
            RawLight::Spot(l) => l.motion.as_ref(),
            RawLight::Sphere(l) => l.motion.as_ref(),
            RawLight::Environment(_) => None,
        }
    }
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDirectional {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) direction: [f32; 3],
    pub(crate) irradiance: [f32; 3],
    /// Rigid motion of the light (position and direction) from its rest pose.
    #[serde(default)]
    pub(crate) motion: Option<RawMotion>,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPoint {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) position: [f32; 3],
    pub(crate) intensity: [f32; 3],
    /// Rigid motion of the light (position and direction) from its rest pose.
    #[serde(default)]
    pub(crate) motion: Option<RawMotion>,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSpot {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) position: [f32; 3],
    pub(crate) direction: [f32; 3],
    pub(crate) intensity: [f32; 3],
    pub(crate) cone_deg: f32,
    #[serde(default)]
    pub(crate) falloff_deg: Option<f32>,
    /// Rigid motion of the light (position and direction) from its rest pose.
    #[serde(default)]
    pub(crate) motion: Option<RawMotion>,
}

/// `"materials"` values.
pub(crate) enum RawMaterial {
    Diffuse(RawDiffuse),
    Dielectric(RawDielectric),
    Mirror(RawMirror),
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDiffuse {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) albedo: [f32; 3],
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDielectric {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) ior: f32,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMirror {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) reflectance: [f32; 3],
}

/// `"shape"` values.
pub(crate) enum RawShape {
    Sphere(RawSphere),
    Quad(RawQuad),
    Heightfield(RawHeightfield),
    Cylinder(RawCylinder),
    Mesh(RawMesh),
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSphere {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) center: [f32; 3],
    pub(crate) radius: f32,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawQuad {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) center: [f32; 3],
    pub(crate) normal: [f32; 3],
    pub(crate) size: [f32; 2],
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawHeightfield {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) center: [f32; 3],
    pub(crate) size: [f32; 2],
    pub(crate) resolution: [u32; 2],
    #[serde(default)]
    pub(crate) waves: Vec<RawWave>,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawWave {
    pub(crate) amplitude: f32,
    pub(crate) wavelength: f32,
    pub(crate) direction: [f32; 2],
    #[serde(default)]
    pub(crate) phase: f32,
    /// Phase speed in m/s along `direction` (0: still); default: deep-water gravity
    /// waves, ω² = g·k.
    #[serde(default)]
    pub(crate) speed_m_s: Option<f32>,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCylinder {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) center: [f32; 3],
    pub(crate) axis: [f32; 3],
    pub(crate) radius: f32,
    pub(crate) height: f32,
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMesh {
    #[serde(rename = "type")]
    #[schemars(skip)]
    _kind: IgnoredAny,
    pub(crate) path: String,
    #[serde(default)]
    pub(crate) transform: Option<RawTransform>,
}

/// `"transform"` of a mesh: `translate`, `rotate_deg` (XYZ Euler), uniform `scale`.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTransform {
    #[serde(default)]
    pub(crate) translate: [f32; 3],
    #[serde(default)]
    pub(crate) rotate_deg: [f32; 3],
    #[serde(default = "one")]
    pub(crate) scale: f32,
}

fn one() -> f32 {
    1.0
}

/// Parses one variant of a tagged value: (source, fragment, JSON path prefix).
type VariantParser<T> = fn(&Source<'_>, &str, &str) -> Result<T, SceneError>;

/// Where a document came from, for turning serde errors into [`SceneError`]s.
pub(crate) struct Source<'a> {
    /// The file name used in messages.
    pub(crate) file: &'a Path,
    /// The whole document, to turn a fragment's line/column into the file's.
    pub(crate) text: &'a str,
}

impl Source<'_> {
    /// Parses the whole document.
    pub(crate) fn parse_scene(&self) -> Result<RawScene<'_>, SceneError> {
        if self.text.trim().is_empty() {
            return Err(SceneError::Syntax {
                file: self.file.to_path_buf(),
                line: 1,
                column: 1,
                json_path: "(root)".into(),
                message: "the file is empty; expected a scene object".into(),
            });
        }
        if !self.text.trim_start().starts_with('{') {
            return Err(SceneError::Invalid {
                file: self.file.to_path_buf(),
                json_path: "(root)".into(),
                message: "expected a JSON object (the scene) at the top level".into(),
            });
        }
        self.parse_fragment(self.text, "")
    }

    /// Parses a light, material or shape by its `"type"`.
    pub(crate) fn parse_tagged<T>(
        &self,
        raw: &RawValue,
        prefix: &str,
        what: &str,
        variants: &[(&str, VariantParser<T>)],
    ) -> Result<T, SceneError> {
        let tag: Tag = self.parse_fragment(raw.get(), prefix)?;
        match variants.iter().find(|(name, _)| *name == tag.kind) {
            Some((_, parse)) => parse(self, raw.get(), prefix),
            None => {
                let names: Vec<&str> = variants.iter().map(|(n, _)| *n).collect();
                Err(SceneError::Invalid {
                    file: self.file.to_path_buf(),
                    json_path: join_path(prefix, "type"),
                    message: format!(
                        "unknown {what} type `{}`, expected one of: {}",
                        tag.kind,
                        names.join(", ")
                    ),
                })
            }
        }
    }

    /// Deserializes `fragment` (the whole text or a slice of it) as `T`; errors get the
    /// JSON path `prefix` + the path inside the fragment, and the file's line/column.
    pub(crate) fn parse_fragment<'t, T: Deserialize<'t>>(
        &self,
        fragment: &'t str,
        prefix: &str,
    ) -> Result<T, SceneError> {
        let mut de = serde_json::Deserializer::from_str(fragment);
        let value = match serde_path_to_error::deserialize(&mut de) {
            Ok(v) => v,
            Err(err) => {
                let path = err.path().to_string();
                return Err(self.convert(fragment, prefix, &path, err.into_inner()));
            }
        };
        de.end()
            .map_err(|err| self.convert(fragment, prefix, "", err))?;
        Ok(value)
    }

    fn convert(
        &self,
        fragment: &str,
        prefix: &str,
        inner_path: &str,
        inner: serde_json::Error,
    ) -> SceneError {
        let inner_path = if inner_path == "." { "" } else { inner_path };
        let json_path = join_path(prefix, inner_path);
        let (line, column) = self.file_position(fragment, inner.line(), inner.column());
        let message = strip_position(&inner.to_string());
        match inner.classify() {
            serde_json::error::Category::Data => SceneError::Invalid {
                file: self.file.to_path_buf(),
                json_path,
                message: format!("{message} (line {line}, column {column})"),
            },
            _ => SceneError::Syntax {
                file: self.file.to_path_buf(),
                line,
                column,
                json_path,
                message,
            },
        }
    }

    /// Turns a line/column inside `fragment` (a slice of `self.text`) into the file's.
    fn file_position(&self, fragment: &str, line: usize, column: usize) -> (usize, usize) {
        let offset = (fragment.as_ptr() as usize).wrapping_sub(self.text.as_ptr() as usize);
        if offset > self.text.len() {
            return (line, column);
        }
        let before = &self.text[..offset];
        let start_line = before.matches('\n').count() + 1;
        let start_column = before.len() - before.rfind('\n').map_or(0, |i| i + 1);
        if line <= 1 {
            (start_line, start_column + column)
        } else {
            (start_line + line - 1, column)
        }
    }
}

/// Joins two JSON paths: `objects[0].shape` + `radius`, or + `[1]`.
pub(crate) fn join_path(prefix: &str, inner: &str) -> String {
    match (prefix.is_empty(), inner.is_empty()) {
        (true, true) => "(root)".into(),
        (true, false) => inner.into(),
        (false, true) => prefix.into(),
        (false, false) if inner.starts_with('[') => format!("{prefix}{inner}"),
        (false, false) => format!("{prefix}.{inner}"),
    }
}

/// serde_json appends " at line L column C"; the position is reported separately.
fn strip_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}

/// Deserializes an owned variant struct from a fragment (used by the variant tables).
pub(crate) fn variant<T: DeserializeOwned, U>(
    src: &Source<'_>,
    fragment: &str,
    prefix: &str,
    wrap: fn(T) -> U,
) -> Result<U, SceneError> {
    src.parse_fragment::<T>(fragment, prefix).map(wrap)
}

impl RawLight {
    pub(crate) fn parse(
        src: &Source<'_>,
        raw: &RawValue,
        prefix: &str,
    ) -> Result<Self, SceneError> {
        src.parse_tagged(
            raw,
            prefix,
            "light",
            &[
                ("directional", |s, f, p| {
                    variant(s, f, p, RawLight::Directional)
                }),
                ("point", |s, f, p| variant(s, f, p, RawLight::Point)),
                ("spot", |s, f, p| variant(s, f, p, RawLight::Spot)),
                ("sphere", |s, f, p| variant(s, f, p, RawLight::Sphere)),
                ("environment", |s, f, p| {
                    variant(s, f, p, RawLight::Environment)
                }),
            ],
        )
    }
}

impl RawMaterial {
    pub(crate) fn parse(
        src: &Source<'_>,
        raw: &RawValue,
        prefix: &str,
    ) -> Result<Self, SceneError> {
        src.parse_tagged(
            raw,
            prefix,
            "material",
            &[
                ("diffuse", |s, f, p| variant(s, f, p, RawMaterial::Diffuse)),
                ("dielectric", |s, f, p| {
                    variant(s, f, p, RawMaterial::Dielectric)
                }),
                ("mirror", |s, f, p| variant(s, f, p, RawMaterial::Mirror)),
            ],
        )
    }
}

impl RawShape {
    pub(crate) fn parse(
        src: &Source<'_>,
        raw: &RawValue,
        prefix: &str,
    ) -> Result<Self, SceneError> {
        src.parse_tagged(
            raw,
            prefix,
            "shape",
            &[
                ("sphere", |s, f, p| variant(s, f, p, RawShape::Sphere)),
                ("quad", |s, f, p| variant(s, f, p, RawShape::Quad)),
                ("heightfield", |s, f, p| {
                    variant(s, f, p, RawShape::Heightfield)
                }),
                ("cylinder", |s, f, p| variant(s, f, p, RawShape::Cylinder)),
                ("mesh", |s, f, p| variant(s, f, p, RawShape::Mesh)),
            ],
        )
    }
}
