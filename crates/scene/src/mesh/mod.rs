//! Loading triangle meshes from OBJ (tobj) and glTF 2.0 (gltf), checked before use.
//!
//! Meshes keep the vertex normals of the file (smooth shading, DESIGN.md "Normals");
//! where a file has none, area-weighted smooth normals are computed, with all vertices
//! at one position sharing one normal (so texture-coordinate seams stay smooth).
//!
//! Every mesh a scene names is checked ([`finish`] for what both formats share, the
//! format modules for the rest), and refused with a [`MeshError`] naming the element:
//! - files: at most [`Limits::max_file_bytes`], read through a bounded reader;
//! - counts: triangles and vertices per file and per scene, mesh objects per scene
//!   ([`Limits`]), checked from the declared counts before the data is read;
//! - positions: finite and within ±[`MAX_COORDINATE`] m after the object's transform
//!   (and the glTF node transforms);
//! - normals from the file: finite and non-zero (they are normalized after the
//!   inverse-transpose transform);
//! - transforms: finite and invertible;
//! - indices: within the vertex count; faces: at least 3 corners (OBJ; polygons are
//!   fan-triangulated), triangle lists only (glTF);
//! - degenerate faces (two equal indices, or zero or non-finite area after the
//!   transform) are **dropped and counted** ([`Mesh::degenerate_dropped`]), since meshes
//!   exported by other tools often hold a few; a mesh left with no triangle is refused.

mod error;
mod from_gltf;
mod from_obj;
mod uri;

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use crate::limits::{Limits, MAX_COORDINATE};
use crate::shape::Mesh;

pub use error::MeshError;
pub(crate) use error::invalid;
pub(crate) use from_gltf::load_gltf;
pub(crate) use from_obj::load_obj;

/// The placement of a mesh file in the scene: `"transform"` of a mesh shape.
///
/// The matrix is T · Rz · Ry · Rx · S: the mesh is scaled uniformly by `scale`, then
/// rotated about the world X axis by `rotate_deg.x`, then about Y by `rotate_deg.y`,
/// then about Z by `rotate_deg.z` (degrees, right-handed, counter-clockwise looking
/// down the axis), then translated by `translate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshTransform {
    /// Translation in metres.
    pub translate: Vec3,
    /// XYZ Euler angles in degrees, applied X first, then Y, then Z.
    pub rotate_deg: Vec3,
    /// Uniform scale (> 0).
    pub scale: f32,
}

impl Default for MeshTransform {
    fn default() -> Self {
        MeshTransform {
            translate: Vec3::ZERO,
            rotate_deg: Vec3::ZERO,
            scale: 1.0,
        }
    }
}

impl MeshTransform {
    /// The rotation Rz · Ry · Rx.
    pub fn rotation(&self) -> Mat3 {
        let r = self.rotate_deg * (std::f32::consts::PI / 180.0);
        Mat3::from_rotation_z(r.z) * Mat3::from_rotation_y(r.y) * Mat3::from_rotation_x(r.x)
    }

    /// The object-to-world matrix T · Rz · Ry · Rx · S.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_translation(self.translate)
            * Mat4::from_mat3(self.rotation())
            * Mat4::from_scale(Vec3::splat(self.scale))
    }
}

/// Reads a whole file through a reader bounded by `limit` bytes.
pub(crate) fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, MeshError> {
    let io = |source| MeshError::Io {
        file: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let declared = file.metadata().map_err(io)?.len();
    let too_large = |bytes| MeshError::Limit {
        what: format!("bytes in {}", path.display()),
        count: bytes,
        limit,
        field: "max_file_bytes",
    };
    if declared > limit {
        return Err(too_large(declared));
    }
    let mut data = Vec::with_capacity(usize::try_from(declared).unwrap_or(0));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(io)?;
    if data.len() as u64 > limit {
        return Err(too_large(data.len() as u64));
    }
    Ok(data)
}

/// The scene-wide counts of meshes loaded so far, against [`Limits`].
pub(crate) struct Budget {
    pub(crate) limits: Limits,
    triangles: u64,
    vertices: u64,
    objects: u64,
}

/// The counts of one mesh file so far.
#[derive(Default)]
pub(crate) struct FileCount {
    triangles: u64,
    vertices: u64,
}

impl Budget {
    pub(crate) fn new(limits: Limits) -> Budget {
        Budget {
            limits,
            triangles: 0,
            vertices: 0,
            objects: 0,
        }
    }

    /// Takes `triangles` and `vertices` for one more mesh object of the file counted by
    /// `file`, or says which limit that passes. Called before the data is read.
    pub(crate) fn reserve(
        &mut self,
        file: &mut FileCount,
        element: &str,
        triangles: u64,
        vertices: u64,
    ) -> Result<(), MeshError> {
        self.take(file, element, triangles, vertices, 1)
    }

    /// Takes `vertices` more for the object last reserved (OBJ: known after parsing).
    pub(crate) fn add_vertices(
        &mut self,
        file: &mut FileCount,
        element: &str,
        vertices: u64,
    ) -> Result<(), MeshError> {
        self.take(file, element, 0, vertices, 0)
    }

    fn take(
        &mut self,
        file: &mut FileCount,
        element: &str,
        triangles: u64,
        vertices: u64,
        objects: u64,
    ) -> Result<(), MeshError> {
        let l = &self.limits;
        let checks = [
            (
                file.triangles,
                triangles,
                l.max_mesh_triangles,
                "triangles in the mesh file",
                "max_mesh_triangles",
            ),
            (
                file.vertices,
                vertices,
                l.max_mesh_vertices,
                "vertices in the mesh file",
                "max_mesh_vertices",
            ),
            (
                self.triangles,
                triangles,
                l.max_scene_triangles,
                "triangles of all meshes in the scene",
                "max_scene_triangles",
            ),
            (
                self.vertices,
                vertices,
                l.max_scene_vertices,
                "vertices of all meshes in the scene",
                "max_scene_vertices",
            ),
            (
                self.objects,
                objects,
                l.max_mesh_objects,
                "mesh objects in the scene",
                "max_mesh_objects",
            ),
        ];
        for (have, add, limit, what, field) in checks {
            let count = have.saturating_add(add);
            if count > limit {
                return Err(MeshError::Limit {
                    what: format!("{what} (reached at {element})"),
                    count,
                    limit,
                    field,
                });
            }
        }
        // Indices are u32: a mesh never gets more vertices than that, whatever the limits.
        let total = file.vertices.saturating_add(vertices);
        if total > u64::from(u32::MAX) {
            return Err(MeshError::Limit {
                what: format!("vertices in the mesh file (reached at {element})"),
                count: total,
                limit: u64::from(u32::MAX),
                field: "max_mesh_vertices (32-bit indices: this one cannot be raised)",
            });
        }
        file.triangles += triangles;
        file.vertices += vertices;
        self.triangles += triangles;
        self.vertices += vertices;
        self.objects += objects;
        Ok(())
    }
}

/// Transforms to world space, checks (see the module docs), drops degenerate faces and
/// fills in normals. `element` names the model or primitive in messages; `indices`
/// holds whole triangles.
pub(crate) fn finish(
    path: &Path,
    element: &str,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<u32>,
    xf: &Mat4,
) -> Result<Mesh, MeshError> {
    if !xf.is_finite() {
        return Err(invalid(element, "the transform has a non-finite entry"));
    }
    let linear = Mat3::from_mat4(*xf);
    let det = linear.determinant();
    if !(det.is_finite() && det != 0.0) {
        return Err(invalid(
            element,
            format!("the transform is singular (determinant {det}); expected an invertible one"),
        ));
    }
    let file_positions = positions;
    let positions: Vec<Vec3> = file_positions
        .iter()
        .map(|&p| xf.transform_point3(p))
        .collect();
    for (i, p) in positions.iter().enumerate() {
        if !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE) {
            return Err(invalid(
                format!("{element}, vertex {i}"),
                format!(
                    "position {} (in the file {}) after the transform: expected finite coordinates within ±{MAX_COORDINATE:e} m",
                    fmt_v3(*p),
                    fmt_v3(file_positions[i]),
                ),
            ));
        }
    }
    let count = positions.len();
    let mut kept = Vec::with_capacity(indices.len());
    let mut degenerate = 0;
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        if let Some(&bad) = tri.iter().find(|&&i| i as usize >= count) {
            return Err(invalid(
                format!("{element}, triangle {t}"),
                format!("index {bad} out of range: expected below the vertex count {count}"),
            ));
        }
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        let zero_area = !(n.is_finite() && n != Vec3::ZERO);
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || zero_area {
            degenerate += 1;
        } else {
            kept.extend_from_slice(tri);
        }
    }
    if kept.is_empty() {
        return Err(MeshError::Empty {
            element: element.to_string(),
            degenerate,
        });
    }
    let mut indices = kept;
    if det < 0.0 {
        // A mirroring transform turns counter-clockwise triangles clockwise.
        for tri in indices.chunks_exact_mut(3) {
            tri.swap(1, 2);
        }
    }
    let (normals, normals_from_file) = match normals {
        Some(file_normals) => {
            if file_normals.len() != count {
                return Err(invalid(
                    element,
                    format!(
                        "{} normals for {count} vertices: expected one per vertex",
                        file_normals.len()
                    ),
                ));
            }
            let normal_matrix = linear.inverse().transpose();
            let mut out = Vec::with_capacity(file_normals.len());
            for (i, n) in file_normals.iter().enumerate() {
                let mut w = (normal_matrix * *n).normalize_or_zero();
                let scale = n.abs().max_element();
                if w == Vec3::ZERO && n.is_finite() && scale > 0.0 {
                    // A huge or tiny (finite, non-zero) normal: scaled to a largest
                    // component of 1 first, so that it survives the transform.
                    w = (normal_matrix * (*n / scale)).normalize_or_zero();
                }
                if w == Vec3::ZERO || !w.is_finite() {
                    return Err(invalid(
                        format!("{element}, vertex {i}"),
                        format!("normal {}: expected a finite non-zero vector", fmt_v3(*n)),
                    ));
                }
                out.push(w);
            }
            (out, true)
        }
        None => (smooth_normals(&positions, &indices), false),
    };
    Ok(Mesh {
        path: path.to_path_buf(),
        positions,
        normals,
        indices,
        normals_from_file,
        degenerate_dropped: degenerate,
    })
}

/// `(x, y, z)` with each component as Rust prints it (`1e20`, `NaN`).
pub(crate) fn fmt_v3(v: Vec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

/// Area-weighted smooth vertex normals: each vertex gets the normalized sum of
/// (b − a) × (c − a) over the triangles touching its position (vertices with equal
/// positions are welded for this). A vertex in no non-degenerate triangle gets +Y.
pub fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut group_of = Vec::with_capacity(positions.len());
    let mut groups: HashMap<[u32; 3], usize> = HashMap::new();
    for p in positions {
        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let next = groups.len();
        group_of.push(*groups.entry(key).or_insert(next));
    }
    let mut sums = vec![Vec3::ZERO; groups.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for v in [a, b, c] {
            sums[group_of[v]] += n;
        }
    }
    group_of
        .iter()
        .map(|&g| sums[g].try_normalize().unwrap_or(Vec3::Y))
        .collect()
}
