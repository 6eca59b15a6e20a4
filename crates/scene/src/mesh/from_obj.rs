//! OBJ files, read with tobj after a pre-scan that checks what tobj does not.
//!
//! tobj trusts the indices of `f` lines (an index like `1/99999999999999999999/1`
//! overflows its arithmetic) and follows `mtllib` to any path; so every line is first
//! checked here, with its line number: `v`, `vt`, `vn` need their numbers, every face
//! corner index must refer to an element declared before it (1-based, or negative
//! relative), faces need at least 3 corners. `l` and `p` elements are ignored, and so
//! are `.mtl` files (materials come from the scene file).

use std::path::Path;

use glam::{Mat4, Vec3};

use super::{Budget, FileCount, MeshError, finish, invalid, read_bounded};
use crate::shape::Mesh;

/// Loads an OBJ file (all its models merged into one mesh), transformed by `xf`.
pub(crate) fn load_obj(path: &Path, xf: &Mat4, budget: &mut Budget) -> Result<Mesh, MeshError> {
    let bytes = read_bounded(path, budget.limits.max_file_bytes)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        invalid(format!("line {line}"), "expected UTF-8 text")
    })?;
    let triangles = prescan(text)?;
    let mut file = FileCount::default();
    // The vertex count is known only after tobj; it is at most 3 per triangle.
    budget.reserve(&mut file, "the OBJ file", triangles, 0)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| MeshError::Parse {
        format: "OBJ",
        message: e.to_string(),
    })?;
    let vertices: usize = models.iter().map(|m| m.mesh.positions.len() / 3).sum();
    budget.add_vertices(&mut file, "the OBJ file", vertices as u64)?;
    let mut positions = Vec::with_capacity(vertices);
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let mut all_have_normals = true;
    for model in &models {
        let m = &model.mesh;
        // At most u32::MAX vertices in all (Budget::add_vertices).
        let base = positions.len() as u32;
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
                return Err(invalid(
                    format!("model `{}`", model.name),
                    format!("index {i} out of range: expected below its {count} vertices"),
                ));
            }
            indices.push(base + i);
        }
    }
    let file_normals = all_have_normals.then_some(normals);
    finish(path, "the OBJ mesh", positions, file_normals, indices, xf)
}

/// Checks every line (see the module docs); returns the triangle count after
/// fan triangulation.
fn prescan(text: &str) -> Result<u64, MeshError> {
    let (mut v, mut vt, mut vn) = (0u64, 0u64, 0u64);
    let mut triangles = 0u64;
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let numbers = |count: usize, what: &str| -> Result<(), MeshError> {
            let got: Vec<&str> = line.split_whitespace().skip(1).take(count).collect();
            if got.len() < count || got.iter().any(|w| w.parse::<f32>().is_err()) {
                return Err(invalid(
                    format!("line {n}"),
                    format!(
                        "expected `{key}` and {count} numbers ({what}), got `{}`",
                        clip(line)
                    ),
                ));
            }
            Ok(())
        };
        match key {
            "v" => {
                numbers(3, "x y z")?;
                v += 1;
            }
            "vt" => {
                numbers(2, "u v")?;
                vt += 1;
            }
            "vn" => {
                numbers(3, "x y z")?;
                vn += 1;
            }
            "f" => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(invalid(
                        format!("line {n}"),
                        format!(
                            "face with {} corners: expected at least 3, got `{}`",
                            corners.len(),
                            clip(line)
                        ),
                    ));
                }
                for c in &corners {
                    corner(n, c, [v, vt, vn])?;
                }
                triangles += corners.len() as u64 - 2;
            }
            _ => {}
        }
    }
    Ok(triangles)
}

/// Checks one face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` against the element counts
/// declared so far.
fn corner(line: usize, c: &str, declared: [u64; 3]) -> Result<(), MeshError> {
    const KIND: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let parts: Vec<&str> = c.split('/').collect();
    let bad = |problem: String| invalid(format!("line {line}, corner `{}`", clip(c)), problem);
    if parts.len() > 3 {
        return Err(bad("expected v, v/vt, v//vn or v/vt/vn".into()));
    }
    for (k, part) in parts.iter().enumerate() {
        if part.is_empty() {
            if k == 0 {
                return Err(bad("expected a vertex index".into()));
            }
            continue;
        }
        let count = declared[k];
        let ok = match part.parse::<i64>() {
            Ok(i) if i > 0 => i.unsigned_abs() <= count,
            Ok(i) if i < 0 => i.unsigned_abs() <= count,
            _ => false,
        };
        if !ok {
            return Err(bad(format!(
                "{} index `{}` out of range: expected 1..={count} or -{count}..=-1 ({count} declared before this line)",
                KIND[k],
                clip(part)
            )));
        }
    }
    Ok(())
}

/// A line or word shortened to 60 characters for a message.
fn clip(s: &str) -> String {
    let mut out: String = s.chars().take(60).collect();
    if out.len() < s.len() {
        out.push('…');
    }
    out
}
