//! Writes `scenes/meshes/glass_cushion.obj`: a rounded glass cube (a superellipsoid),
//! the built-in triangle-mesh refractor that is not a sphere.
//!
//! `cargo run -p caustics-scene --example gen_glass_cushion` rewrites the file bit for
//! bit. The surface is |x|⁴ + |y|⁴ + |z|⁴ = 1: flat-ish faces that focus little, rounded
//! edges and corners that focus strongly, so its caustic has bright lines and a dim
//! square core, unlike a sphere's single focus. It is tessellated coarsely on purpose
//! (a 20×20 grid on each face of the cube, projected onto the surface along the ray
//! from the centre: 2,402 vertices, 4,800 triangles) and carries the analytic normals
//! (n ∝ (x³, y³, z³)), so the shading normals differ from the facets by up to a few
//! degrees: the light transport's shading-normal factor (DESIGN "Conventions") matters
//! here. Star-shaped from its centre, so a distance map around the centre sees all of
//! it. Coordinates are written with 6 decimals.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use caustics_scene::Vec3;

/// Cells per side of each cube face.
const CELLS: u32 = 20;
/// The superellipsoid's exponent (2: a sphere; large: a cube).
const EXPONENT: f32 = 4.0;

/// The surface point in the direction of `d` (any length): r·d̂ with
/// Σ |r d̂ᵢ|^p = 1.
fn surface(d: Vec3) -> Vec3 {
    let u = d.normalize();
    let s: f32 = u.to_array().iter().map(|c| c.abs().powf(EXPONENT)).sum();
    u * s.powf(-1.0 / EXPONENT)
}

/// The outward unit normal at surface point `p`: the gradient of Σ |xᵢ|^p.
fn normal(p: Vec3) -> Vec3 {
    let g = |c: f32| c.signum() * c.abs().powf(EXPONENT - 1.0);
    Vec3::new(g(p.x), g(p.y), g(p.z)).normalize()
}

fn main() -> std::io::Result<()> {
    let mut vertices: Vec<Vec3> = Vec::new();
    // Cube-grid points shared by two or three faces (edges, corners) are one vertex:
    // keyed by their integer grid coordinates in [-CELLS, CELLS]³.
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut vertex = |g: [i32; 3]| -> u32 {
        *index.entry(g).or_insert_with(|| {
            let d = Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32);
            vertices.push(surface(d));
            (vertices.len() - 1) as u32
        })
    };
    let n = CELLS as i32;
    let mut faces: Vec<[u32; 3]> = Vec::new();
    // Each cube face: axis `a` fixed at ±n, (b, c) spanning the face, wound so the
    // triangles face outward (b × c along ±a).
    for a in 0..3 {
        for sign in [1i32, -1] {
            let (b, c) = if sign > 0 {
                ((a + 1) % 3, (a + 2) % 3)
            } else {
                ((a + 2) % 3, (a + 1) % 3)
            };
            let at = |i: i32, j: i32| {
                let mut g = [0i32; 3];
                g[a] = sign * n;
                g[b] = i;
                g[c] = j;
                g
            };
            for j in (-n..n).step_by(2) {
                for i in (-n..n).step_by(2) {
                    let v00 = vertex(at(i, j));
                    let v10 = vertex(at(i + 2, j));
                    let v11 = vertex(at(i + 2, j + 2));
                    let v01 = vertex(at(i, j + 2));
                    faces.push([v00, v10, v11]);
                    faces.push([v00, v11, v01]);
                }
            }
        }
    }
    let mut obj = String::new();
    let _ = writeln!(
        obj,
        "# glass_cushion: |x|^{EXPONENT} + |y|^{EXPONENT} + |z|^{EXPONENT} = 1, written by \
         `cargo run -p caustics-scene --example gen_glass_cushion`\n\
         # {CELLS}x{CELLS} cells per cube face projected onto the surface; analytic normals"
    );
    let _ = writeln!(
        obj,
        "# {} vertices, {} triangles",
        vertices.len(),
        faces.len()
    );
    for p in &vertices {
        let _ = writeln!(obj, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    }
    for p in &vertices {
        let m = normal(*p);
        let _ = writeln!(obj, "vn {:.6} {:.6} {:.6}", m.x, m.y, m.z);
    }
    for [a, b, c] in &faces {
        let (a, b, c) = (a + 1, b + 1, c + 1);
        let _ = writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    let path: PathBuf = caustics_scene::builtin_dir().join("meshes/glass_cushion.obj");
    std::fs::write(&path, obj)?;
    println!("wrote {} ({} triangles)", path.display(), faces.len());
    Ok(())
}
