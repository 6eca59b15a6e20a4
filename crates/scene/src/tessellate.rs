//! Triangulation of shapes for rasterizing methods.
//!
//! Every triangle is counter-clockwise seen from the side its normals point to, and
//! every normal is the analytic unit normal of the shape (smooth shading, DESIGN.md
//! "Normals"): never flat facet normals.

use std::f32::consts::{PI, TAU};

use glam::Vec3;

use crate::shape::{Shape, perpendicular_frame, quad_axes};

/// How finely curved shapes are tessellated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tessellation {
    /// Segments around a sphere (longitude); rings (latitude) = segments / 2. Default 96.
    pub sphere_segments: u32,
    /// Segments around a cylinder. Default 128.
    pub cylinder_segments: u32,
}

impl Default for Tessellation {
    fn default() -> Self {
        Tessellation {
            sphere_segments: 96,
            cylinder_segments: 128,
        }
    }
}

/// An indexed triangle list with one unit normal per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// World-space positions.
    pub positions: Vec<Vec3>,
    /// World-space unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Three indices per triangle, counter-clockwise seen from the normal side.
    pub indices: Vec<u32>,
}

impl TriangleMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The corners of triangle `t`.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }

    /// Sum of the triangle areas.
    pub fn area(&self) -> f32 {
        (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }
}

impl Shape {
    /// Triangulates the shape (see the module docs for winding and normals):
    /// spheres as a latitude-longitude grid, quads as 2 triangles, heightfields on their
    /// `resolution` grid with analytic normals, open cylinders with
    /// `cylinder_segments` quads around and one ring tall, meshes as loaded.
    pub fn triangulate(&self, tess: &Tessellation) -> TriangleMesh {
        match self {
            Shape::Sphere { center, radius } => sphere(*center, *radius, tess.sphere_segments),
            Shape::Quad {
                center,
                normal,
                size,
            } => {
                let (u, v) = quad_axes(*normal);
                let (hu, hv) = (0.5 * size.x * u, 0.5 * size.y * v);
                TriangleMesh {
                    positions: vec![
                        *center - hu - hv,
                        *center + hu - hv,
                        *center + hu + hv,
                        *center - hu + hv,
                    ],
                    normals: vec![*normal; 4],
                    indices: vec![0, 1, 2, 0, 2, 3],
                }
            }
            Shape::Heightfield(h) => {
                let [nx, nz] = h.resolution;
                let mut mesh = TriangleMesh::default();
                for j in 0..nz {
                    for i in 0..nx {
                        let (x, z) = h.grid_xz(i, j);
                        mesh.positions.push(Vec3::new(x, h.height(x, z), z));
                        mesh.normals.push(h.normal(x, z));
                    }
                }
                // Seen from +y (looking down −y), x × z = −y, so (p, p+z, p+x) is CCW.
                for j in 0..nz - 1 {
                    for i in 0..nx - 1 {
                        let v00 = j * nx + i;
                        let v10 = v00 + 1;
                        let v01 = v00 + nx;
                        let v11 = v01 + 1;
                        mesh.indices
                            .extend_from_slice(&[v00, v01, v10, v10, v01, v11]);
                    }
                }
                mesh
            }
            Shape::Cylinder {
                center,
                axis,
                radius,
                height,
            } => cylinder(*center, *axis, *radius, *height, tess.cylinder_segments),
            Shape::Mesh(m) => TriangleMesh {
                positions: m.positions.clone(),
                normals: m.normals.clone(),
                indices: m.indices.clone(),
            },
        }
    }
}

/// Latitude-longitude sphere: `segments` around (at least 3), segments/2 rings (at least
/// 2), seam and pole vertices duplicated, no degenerate triangles at the poles.
fn sphere(center: Vec3, radius: f32, segments: u32) -> TriangleMesh {
    let segments = segments.max(3);
    let rings = (segments / 2).max(2);
    let mut mesh = TriangleMesh::default();
    for i in 0..=rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = TAU * j as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            mesh.positions.push(center + radius * n);
            mesh.normals.push(n);
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let a = i * row + j; // (θ_i, φ_j)
            let b = a + 1; // (θ_i, φ_j+1)
            let c = a + row; // (θ_i+1, φ_j)
            let d = c + 1; // (θ_i+1, φ_j+1)
            // ∂/∂φ × ∂/∂θ points outward, so (a, b, c) is CCW from outside.
            if i != 0 {
                mesh.indices.extend_from_slice(&[a, b, c]);
            }
            if i != rings - 1 {
                mesh.indices.extend_from_slice(&[b, d, c]);
            }
        }
    }
    mesh
}

/// Open cylinder, `segments` quads around (at least 3), one ring tall, outward normals.
fn cylinder(center: Vec3, axis: Vec3, radius: f32, height: f32, segments: u32) -> TriangleMesh {
    let segments = segments.max(3);
    let (b1, b2) = perpendicular_frame(axis);
    let half = 0.5 * height * axis;
    let mut mesh = TriangleMesh::default();
    for j in 0..=segments {
        let phi = TAU * j as f32 / segments as f32;
        let n = phi.cos() * b1 + phi.sin() * b2;
        mesh.positions.push(center - half + radius * n);
        mesh.positions.push(center + half + radius * n);
        mesh.normals.push(n);
        mesh.normals.push(n);
    }
    for j in 0..segments {
        let (bot, top) = (2 * j, 2 * j + 1);
        let (bot_next, top_next) = (bot + 2, top + 2);
        // tangent (b2 at φ = 0) × axis = b1 = outward, so (bot, bot_next, top) is CCW.
        mesh.indices
            .extend_from_slice(&[bot, bot_next, top, bot_next, top_next, top]);
    }
    mesh
}
