//! Loading triangle meshes from OBJ (tobj) and glTF 2.0 (gltf).
//!
//! Meshes keep the vertex normals of the file (smooth shading, DESIGN.md "Normals");
//! where a file has none, area-weighted smooth normals are computed, with all vertices
//! at one position sharing one normal (so texture-coordinate seams stay smooth).

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use crate::light::Material;
use crate::shape::Mesh;

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

/// Loads an OBJ file (all its models merged into one mesh), transformed by `xf`.
pub(crate) fn load_obj(path: &Path, xf: &Mat4) -> Result<Mesh, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // The .mtl (if any) is not used: materials come from the scene file.
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let mut all_have_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = u32::try_from(positions.len()).map_err(|_| "too many vertices".to_string())?;
        let count = m.positions.len() / 3;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if m.normals.len() == m.positions.len() {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        } else {
            all_have_normals = false;
        }
        for &i in &m.indices {
            if i as usize >= count {
                return Err(format!(
                    "model `{}`: index {i} out of range ({count} vertices)",
                    model.name
                ));
            }
            indices.push(base + i);
        }
    }
    let file_normals = all_have_normals.then_some(normals);
    finish(path, positions, file_normals, indices, xf)
}

/// One primitive of a glTF file, with the material the file gives it.
pub(crate) struct GltfPrimitive {
    /// The primitive in world space.
    pub(crate) mesh: Mesh,
    /// `(index, name, material)`: the glTF material index (None for the default
    /// material), its name if any, and the material derived from it.
    pub(crate) material: (Option<usize>, Option<String>, Material),
}

/// Loads every triangle primitive of the default scene (or the first scene) of a glTF
/// or GLB file, node transforms applied and then `xf`.
pub(crate) fn load_gltf(path: &Path, xf: &Mat4) -> Result<Vec<GltfPrimitive>, String> {
    let gltf = gltf::Gltf::open(path).map_err(|e| e.to_string())?;
    let buffers = gltf::import_buffers(&gltf.document, path.parent(), gltf.blob.clone())
        .map_err(|e| e.to_string())?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| "the file has no scene".to_string())?;
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, *xf)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    return Err(format!(
                        "{what}: mode {:?} is not supported (only triangle lists)",
                        prim.mode()
                    ));
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<Vec3> = reader
                    .read_positions()
                    .ok_or_else(|| format!("{what}: no POSITION attribute"))?
                    .map(Vec3::from)
                    .collect();
                let normals: Option<Vec<Vec3>> =
                    reader.read_normals().map(|n| n.map(Vec3::from).collect());
                let count = u32::try_from(positions.len())
                    .map_err(|_| format!("{what}: too many vertices"))?;
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..count).collect(),
                };
                if let Some(&bad) = indices.iter().find(|&&i| i >= count) {
                    return Err(format!(
                        "{what}: index {bad} out of range ({count} vertices)"
                    ));
                }
                if !indices.len().is_multiple_of(3) {
                    return Err(format!("{what}: index count is not a multiple of 3"));
                }
                let mesh = finish(path, positions, normals, indices, &world)
                    .map_err(|e| format!("{what}: {e}"))?;
                let m = prim.material();
                out.push(GltfPrimitive {
                    mesh,
                    material: (m.index(), m.name().map(str::to_string), gltf_material(&m)),
                });
            }
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    if out.is_empty() {
        return Err("the scene of the file holds no mesh primitive".into());
    }
    Ok(out)
}

/// The scene material of a glTF material:
/// `transmission_factor > 0` (KHR_materials_transmission) → dielectric with the ior of
/// KHR_materials_ior (default 1.5); else metallic 1 and roughness 0 → mirror with the
/// base colour as reflectance; else diffuse with the base colour (rgb) as albedo.
fn gltf_material(m: &gltf::Material<'_>) -> Material {
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    if transmission > 0.0 {
        Material::Dielectric {
            ior: m.ior().unwrap_or(1.5),
        }
    } else if pbr.metallic_factor() >= 1.0 && pbr.roughness_factor() <= 0.0 {
        Material::Mirror {
            reflectance: Vec3::new(r, g, b),
        }
    } else {
        Material::Diffuse {
            albedo: Vec3::new(r, g, b),
        }
    }
}

/// Transforms to world space, checks, and fills in normals.
fn finish(
    path: &Path,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    mut indices: Vec<u32>,
    xf: &Mat4,
) -> Result<Mesh, String> {
    if indices.len() < 3 {
        return Err("the mesh has no triangles".into());
    }
    let positions: Vec<Vec3> = positions.iter().map(|&p| xf.transform_point3(p)).collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a non-finite position"));
    }
    let linear = Mat3::from_mat4(*xf);
    if linear.determinant() < 0.0 {
        // A mirroring transform turns counter-clockwise triangles clockwise.
        for tri in indices.chunks_exact_mut(3) {
            tri.swap(1, 2);
        }
    }
    let (normals, normals_from_file) = match normals {
        Some(file_normals) => {
            let normal_matrix = linear.inverse().transpose();
            let mut out = Vec::with_capacity(file_normals.len());
            for (i, n) in file_normals.iter().enumerate() {
                let w = (normal_matrix * *n).normalize_or_zero();
                if w == Vec3::ZERO || !w.is_finite() {
                    return Err(format!("vertex {i} has a zero or non-finite normal"));
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
    })
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
