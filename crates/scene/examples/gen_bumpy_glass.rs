//! Writes `scenes/meshes/bumpy_glass.obj`: a unit sphere with high-frequency bumps.
//!
//! `cargo run -p caustics-scene --example gen_bumpy_glass` rewrites the file bit for bit:
//! an icosahedron subdivided 5 times (10,242 vertices, 20,480 triangles, built in a fixed
//! order), each vertex u on the unit sphere moved to r(u)·u with
//! r(u) = 1 + A·f(u), f(u) = sin(17x + 1.3)·sin(19y + 0.7)·sin(23z + 2.1), A = 0.04,
//! and its normal taken from the analytic displaced surface:
//! n ∝ r(u)·u − ∇ₛr(u), with ∇ₛ the tangential part of the 3-D gradient of r.
//! Coordinates are written with 6 decimals.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use caustics_scene::Vec3;

const SUBDIVISIONS: u32 = 5;
const AMPLITUDE: f32 = 0.04;
const FREQ: [f32; 3] = [17.0, 19.0, 23.0];
const PHASE: [f32; 3] = [1.3, 0.7, 2.1];

fn bump(u: Vec3) -> f32 {
    (FREQ[0] * u.x + PHASE[0]).sin()
        * (FREQ[1] * u.y + PHASE[1]).sin()
        * (FREQ[2] * u.z + PHASE[2]).sin()
}

fn bump_gradient(u: Vec3) -> Vec3 {
    let s = |k: usize, x: f32| (FREQ[k] * x + PHASE[k]).sin();
    let c = |k: usize, x: f32| FREQ[k] * (FREQ[k] * x + PHASE[k]).cos();
    Vec3::new(
        c(0, u.x) * s(1, u.y) * s(2, u.z),
        s(0, u.x) * c(1, u.y) * s(2, u.z),
        s(0, u.x) * s(1, u.y) * c(2, u.z),
    )
}

fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut cache: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *cache.entry(key).or_insert_with(|| {
                let m = (verts[a as usize] + verts[b as usize]).normalize();
                verts.push(m);
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    (verts, faces)
}

fn main() -> std::io::Result<()> {
    let (units, faces) = icosphere(SUBDIVISIONS);
    let mut obj = String::new();
    let _ = writeln!(
        obj,
        "# bumpy_glass: unit sphere with bumps, written by \
         `cargo run -p caustics-scene --example gen_bumpy_glass`\n\
         # r(u) = 1 + {AMPLITUDE}*sin({}x+{})*sin({}y+{})*sin({}z+{}); analytic normals",
        FREQ[0], PHASE[0], FREQ[1], PHASE[1], FREQ[2], PHASE[2]
    );
    let _ = writeln!(obj, "# {} vertices, {} triangles", units.len(), faces.len());
    for &u in &units {
        let p = (1.0 + AMPLITUDE * bump(u)) * u;
        let _ = writeln!(obj, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    }
    for &u in &units {
        let r = 1.0 + AMPLITUDE * bump(u);
        let g = AMPLITUDE * bump_gradient(u);
        let tangential = g - g.dot(u) * u;
        let n = (r * u - tangential).normalize();
        let _ = writeln!(obj, "vn {:.6} {:.6} {:.6}", n.x, n.y, n.z);
    }
    for [a, b, c] in &faces {
        let (a, b, c) = (a + 1, b + 1, c + 1);
        let _ = writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    let path: PathBuf = caustics_scene::builtin_dir().join("meshes/bumpy_glass.obj");
    std::fs::write(&path, obj)?;
    println!("wrote {} ({} triangles)", path.display(), faces.len());
    Ok(())
}
