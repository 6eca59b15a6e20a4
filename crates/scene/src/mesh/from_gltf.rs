//! glTF 2.0 and GLB files, parsed with the gltf crate's JSON layer and read here.
//!
//! `gltf::import` is not used: it follows buffer URIs anywhere (`../../etc/passwd`,
//! `file:///`), decodes `data:` URIs without a limit, and its GLB header arithmetic and
//! accessor reader can panic (a GLB length under 12, a stride below the element size, a
//! zero count) or trust counts that do not fit the buffers. Instead the GLB container is
//! split here, the JSON is parsed and validated by `gltf::Document::from_json` (which
//! checks that every index points at an existing element), buffers are resolved by
//! [`super::uri`], and the accessors a mesh uses are bounds-checked and read here.
//!
//! The node hierarchy of the scene is walked once from its roots: a node met again (a
//! cycle, or a node with two parents: glTF requires disjoint trees) is refused, and so
//! is a depth over [`crate::Limits::max_node_depth`]. Triangle and vertex counts are
//! reserved from the accessors' declared counts before their data is read.

use std::path::Path;

use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use super::uri::{allowed_root, read_uri};
use super::{Budget, FileCount, MeshError, finish, invalid, read_bounded};
use crate::light::Material;
use crate::shape::Mesh;

/// One primitive of a glTF file, with the material the file gives it.
pub(crate) struct GltfPrimitive {
    /// The primitive in world space.
    pub(crate) mesh: Mesh,
    /// `(index, name, material)`: the glTF material index (None for the default
    /// material), its name if any, and the material derived from it.
    pub(crate) material: (Option<usize>, Option<String>, Material),
}

/// Loads every triangle primitive of the default scene (or the first scene) of a glTF
/// or GLB file, node transforms applied and then `xf`. Buffers must lie in `scene_dir`
/// (see [`allowed_root`]).
pub(crate) fn load_gltf(
    path: &Path,
    scene_dir: &Path,
    xf: &Mat4,
    budget: &mut Budget,
) -> Result<Vec<GltfPrimitive>, MeshError> {
    let limit = budget.limits.max_file_bytes;
    let bytes = read_bounded(path, limit)?;
    let (json, mut blob) = if bytes.starts_with(b"glTF") {
        split_glb(&bytes)?
    } else {
        (&bytes[..], None)
    };
    let format = if blob.is_some() || bytes.starts_with(b"glTF") {
        "GLB"
    } else {
        "glTF"
    };
    let root: gltf::json::Root =
        gltf::json::deserialize::from_slice(json).map_err(|e| MeshError::Parse {
            format,
            message: e.to_string(),
        })?;
    attributes_exist(&root)?;
    let doc = gltf::Document::from_json(root).map_err(|e| MeshError::Parse {
        format,
        message: validation_message(e),
    })?;

    let (gltf_dir, allowed) = allowed_root(scene_dir, path)?;
    let mut buffers = Vec::new();
    let mut total = 0u64;
    for b in doc.buffers() {
        let element = format!("buffer {}", b.index());
        let data = match b.source() {
            gltf::buffer::Source::Uri(uri) => read_uri(&element, uri, &gltf_dir, &allowed, limit)?,
            gltf::buffer::Source::Bin if b.index() == 0 => blob.take().ok_or_else(|| {
                invalid(
                    &element,
                    "no `uri` and no GLB BIN chunk: expected one of them",
                )
            })?,
            gltf::buffer::Source::Bin => {
                return Err(invalid(
                    &element,
                    "no `uri`: expected one (only buffer 0 may use the GLB BIN chunk)",
                ));
            }
        };
        let declared = b.length() as u64;
        if (data.len() as u64) < declared {
            return Err(invalid(
                &element,
                format!(
                    "byteLength {declared}: expected at most the {} bytes its data holds",
                    data.len()
                ),
            ));
        }
        total = total.saturating_add(data.len() as u64);
        if total > limit {
            return Err(MeshError::Limit {
                what: format!("bytes of the buffers of the glTF file (reached at {element})"),
                count: total,
                limit,
                field: "max_file_bytes",
            });
        }
        buffers.push(data);
    }

    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| {
            invalid(
                "the file",
                "no scene: expected at least one entry in `scenes`",
            )
        })?;
    let nodes: Vec<gltf::Node<'_>> = doc.nodes().collect();
    let children: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| n.children().map(|c| c.index()).collect())
        .collect();
    // 0: not met, 1: on the current path, 2: done.
    let mut state = vec![0u8; nodes.len()];
    let mut file = FileCount::default();
    let mut out = Vec::new();
    for root in scene.nodes() {
        if state[root.index()] != 0 {
            return Err(invalid(
                format!("scene {}", scene.index()),
                format!(
                    "node {} is met twice (listed twice, or also a child of another node): expected disjoint trees",
                    root.index()
                ),
            ));
        }
        // Depth-first with an explicit stack: (node, its world matrix, next child).
        let mut stack: Vec<(usize, Mat4, usize)> = Vec::new();
        enter(&nodes[root.index()], xf, &mut stack, &mut state, budget)?;
        place(
            &nodes[root.index()],
            &stack,
            path,
            &buffers,
            budget,
            &mut file,
            &mut out,
        )?;
        while let Some(top) = stack.last_mut() {
            let (node, world, next) = (top.0, top.1, top.2);
            let Some(&c) = children[node].get(next) else {
                state[node] = 2;
                stack.pop();
                continue;
            };
            top.2 += 1;
            match state[c] {
                1 => {
                    let from = stack.iter().position(|f| f.0 == c).unwrap_or(0);
                    let mut cycle: Vec<usize> = stack[from..].iter().map(|f| f.0).collect();
                    cycle.push(c);
                    return Err(MeshError::NodeCycle { node: c, cycle });
                }
                2 => {
                    return Err(invalid(
                        format!("node {c}"),
                        format!(
                            "a child of node {node} and of another node: expected each node to have at most one parent"
                        ),
                    ));
                }
                _ => {}
            }
            enter(&nodes[c], &world, &mut stack, &mut state, budget)?;
            place(
                &nodes[c], &stack, path, &buffers, budget, &mut file, &mut out,
            )?;
        }
    }
    if out.is_empty() {
        return Err(invalid(
            "the file's scene",
            "no mesh primitive: expected at least one",
        ));
    }
    Ok(out)
}

/// Every primitive attribute names an existing accessor. Checked before
/// `Document::from_json`, whose validation indexes the POSITION accessor unchecked
/// (gltf-json 1.4.1, mesh.rs: a panic on an index past the accessors).
fn attributes_exist(root: &gltf::json::Root) -> Result<(), MeshError> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= n {
                    return Err(invalid(
                        format!("mesh {m} primitive {p}"),
                        format!(
                            "attribute {semantic:?} names accessor {}: expected one of the {n} accessors",
                            index.value()
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Pushes `node` on the walk's stack with its world matrix, checking the depth.
fn enter(
    node: &gltf::Node<'_>,
    parent: &Mat4,
    stack: &mut Vec<(usize, Mat4, usize)>,
    state: &mut [u8],
    budget: &Budget,
) -> Result<(), MeshError> {
    let depth = stack.len() as u64 + 1;
    let max = u64::from(budget.limits.max_node_depth);
    if depth > max {
        return Err(MeshError::Limit {
            what: format!(
                "depth of the node hierarchy (reached at node {})",
                node.index()
            ),
            count: depth,
            limit: max,
            field: "max_node_depth",
        });
    }
    let world = *parent * Mat4::from_cols_array_2d(&node.transform().matrix());
    state[node.index()] = 1;
    stack.push((node.index(), world, 0));
    Ok(())
}

/// The primitives of the mesh of the node on top of `stack`, if it has one.
fn place(
    node: &gltf::Node<'_>,
    stack: &[(usize, Mat4, usize)],
    path: &Path,
    buffers: &[Vec<u8>],
    budget: &mut Budget,
    file: &mut FileCount,
    out: &mut Vec<GltfPrimitive>,
) -> Result<(), MeshError> {
    let (Some(mesh), Some(&(_, world, _))) = (node.mesh(), stack.last()) else {
        return Ok(());
    };
    for prim in mesh.primitives() {
        let what = format!(
            "mesh {} primitive {} (at node {})",
            mesh.index(),
            prim.index(),
            node.index()
        );
        let mesh = primitive(&prim, &what, path, buffers, &world, budget, file)?;
        let m = prim.material();
        out.push(GltfPrimitive {
            mesh,
            material: (m.index(), m.name().map(str::to_string), gltf_material(&m)),
        });
    }
    Ok(())
}

/// Reads and checks one primitive.
fn primitive(
    prim: &gltf::Primitive<'_>,
    what: &str,
    path: &Path,
    buffers: &[Vec<u8>],
    world: &Mat4,
    budget: &mut Budget,
    file: &mut FileCount,
) -> Result<Mesh, MeshError> {
    if prim.mode() != Mode::Triangles {
        return Err(invalid(
            what,
            format!(
                "mode {:?}: expected Triangles (4), the only mode supported",
                prim.mode()
            ),
        ));
    }
    let pos = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| invalid(what, "no POSITION attribute: expected one"))?;
    let normals = prim.get(&Semantic::Normals);
    let vertices = pos.count();
    if let Some(n) = &normals
        && n.count() != vertices
    {
        return Err(invalid(
            format!("accessor {} (NORMAL of {what})", n.index()),
            format!(
                "count {}: expected the POSITION count {vertices}",
                n.count()
            ),
        ));
    }
    let index_count = prim.indices().map_or(vertices, |a| a.count());
    if !index_count.is_multiple_of(3) {
        return Err(invalid(
            what,
            format!("{index_count} vertex indices: expected a multiple of 3 (a triangle list)"),
        ));
    }
    budget.reserve(file, what, index_count as u64 / 3, vertices as u64)?;
    let positions = read_vec3(
        buffers,
        &pos,
        &format!("accessor {} (POSITION of {what})", pos.index()),
    )?;
    let normals = match &normals {
        Some(n) => Some(read_vec3(
            buffers,
            n,
            &format!("accessor {} (NORMAL of {what})", n.index()),
        )?),
        None => None,
    };
    let indices = match prim.indices() {
        Some(a) => read_indices(
            buffers,
            &a,
            &format!("accessor {} (indices of {what})", a.index()),
        )?,
        // vertices ≤ u32::MAX (Budget::reserve).
        None => (0..vertices as u32).collect(),
    };
    finish(path, what, positions, normals, indices, world)
}

/// The bytes of an accessor's elements (from its first byte to its last) and the
/// stride between them, after checking them against its view and buffer.
fn elements<'b>(
    buffers: &'b [Vec<u8>],
    a: &gltf::Accessor<'_>,
    element: &str,
    is_index: bool,
) -> Result<(&'b [u8], usize), MeshError> {
    if a.sparse().is_some() {
        return Err(invalid(
            element,
            "a sparse accessor: expected a plain one (sparse storage is not supported)",
        ));
    }
    let view = a
        .view()
        .ok_or_else(|| invalid(element, "no bufferView: expected one"))?;
    let count = a.count() as u64;
    if count == 0 {
        return Err(invalid(element, "count 0: expected at least 1"));
    }
    let size = a.size() as u64;
    let stride = match view.stride() {
        None => size,
        Some(_) if is_index => {
            return Err(invalid(
                format!("{element}, bufferView {}", view.index()),
                "a byteStride on an index view: expected none",
            ));
        }
        Some(s) => {
            let s = s as u64;
            if s < size || !(4..=252).contains(&s) || !s.is_multiple_of(4) {
                return Err(invalid(
                    format!("{element}, bufferView {}", view.index()),
                    format!(
                        "byteStride {s}: expected a multiple of 4 in {}..=252",
                        size.max(4)
                    ),
                ));
            }
            s
        }
    };
    let buffer = view.buffer();
    let data = &buffers[buffer.index()];
    let (v_off, v_len) = (view.offset() as u64, view.length() as u64);
    let declared = buffer.length() as u64;
    if v_off.checked_add(v_len).is_none_or(|end| end > declared) {
        return Err(invalid(
            format!("{element}, bufferView {}", view.index()),
            format!(
                "byteOffset {v_off} + byteLength {v_len}: expected within buffer {} of byteLength {declared}",
                buffer.index()
            ),
        ));
    }
    let a_off = a.offset() as u64;
    let end = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(size))
        .and_then(|x| x.checked_add(a_off));
    if end.is_none_or(|e| e > v_len) {
        return Err(invalid(
            element,
            format!(
                "byteOffset {a_off} + {count} elements of {size} bytes at stride {stride}: expected within its bufferView {} of byteLength {v_len}",
                view.index()
            ),
        ));
    }
    let start = (v_off + a_off) as usize;
    let end = (v_off + end.unwrap_or(0)) as usize;
    let bytes = data
        .get(start..end)
        .ok_or_else(|| invalid(element, "its bytes lie outside the buffer's data"))?;
    Ok((bytes, stride as usize))
}

/// A FLOAT VEC3 accessor (POSITION, NORMAL).
fn read_vec3(
    buffers: &[Vec<u8>],
    a: &gltf::Accessor<'_>,
    element: &str,
) -> Result<Vec<Vec3>, MeshError> {
    if a.dimensions() != Dimensions::Vec3 || a.data_type() != DataType::F32 {
        return Err(invalid(
            element,
            format!(
                "type {:?} of componentType {:?}: expected VEC3 of FLOAT (5126)",
                a.dimensions(),
                a.data_type()
            ),
        ));
    }
    let (bytes, stride) = elements(buffers, a, element, false)?;
    let f = |b: &[u8], k: usize| {
        f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
    };
    Ok((0..a.count())
        .map(|i| {
            let e = &bytes[i * stride..i * stride + 12];
            Vec3::new(f(e, 0), f(e, 1), f(e, 2))
        })
        .collect())
}

/// A SCALAR accessor of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT (indices).
fn read_indices(
    buffers: &[Vec<u8>],
    a: &gltf::Accessor<'_>,
    element: &str,
) -> Result<Vec<u32>, MeshError> {
    let size = match (a.dimensions(), a.data_type()) {
        (Dimensions::Scalar, DataType::U8) => 1,
        (Dimensions::Scalar, DataType::U16) => 2,
        (Dimensions::Scalar, DataType::U32) => 4,
        (d, t) => {
            return Err(invalid(
                element,
                format!(
                    "type {d:?} of componentType {t:?}: expected SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT"
                ),
            ));
        }
    };
    let (bytes, stride) = elements(buffers, a, element, true)?;
    Ok((0..a.count())
        .map(|i| {
            let e = &bytes[i * stride..i * stride + size];
            match size {
                1 => u32::from(e[0]),
                2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            }
        })
        .collect())
}

/// Splits a GLB container into its JSON chunk and its BIN chunk (if any), checking
/// every length against the file (glTF 2.0 §4.4).
fn split_glb(b: &[u8]) -> Result<(&[u8], Option<Vec<u8>>), MeshError> {
    let u32_at = |k: usize| {
        b.get(k..k + 4)
            .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(invalid(
            "the GLB header",
            format!("{} bytes: expected 12", b.len()),
        ));
    };
    if version != 2 {
        return Err(invalid(
            "the GLB header",
            format!("version {version}: expected 2"),
        ));
    }
    let length = length as usize;
    if !(20..=b.len()).contains(&length) {
        return Err(invalid(
            "the GLB header",
            format!(
                "length {length}: expected 20..={} (the file's size)",
                b.len()
            ),
        ));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (Some(len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(invalid(
                format!("GLB chunk {}", chunks.len()),
                "truncated header: expected 8 bytes",
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= length)
            .ok_or_else(|| {
                invalid(
                    format!("GLB chunk {}", chunks.len()),
                    format!(
                        "chunkLength {len}: expected at most the {} bytes left",
                        length.saturating_sub(start)
                    ),
                )
            })?;
        chunks.push((kind, &b[start..end]));
        // Chunks are 4-byte aligned.
        at = end.div_ceil(4) * 4;
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => {
            let bin = chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1.to_vec());
            Ok((json, bin))
        }
        _ => Err(invalid("GLB chunk 0", "expected the JSON chunk first")),
    }
}

/// The gltf crate's validation errors, the first few of them.
fn validation_message(e: gltf::Error) -> String {
    match e {
        gltf::Error::Validation(errors) => {
            let shown: Vec<String> = errors
                .iter()
                .take(5)
                .map(|(path, err)| format!("{path}: {err}"))
                .collect();
            let more = errors.len().saturating_sub(5);
            let tail = if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            };
            format!("{}{tail}", shown.join("; "))
        }
        other => other.to_string(),
    }
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
