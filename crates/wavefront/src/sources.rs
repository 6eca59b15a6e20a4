//! The wavefront mesh before tracing (built once per scene on the CPU): one source
//! per vertex, and its triangles.
//!
//! * Open heightfield refractor: Wallace's construction, the water mesh itself. Each
//!   vertex is where a light ray meets the surface, with the analytic normal.
//! * Analytic generator (refracting sphere or quad; mirror sphere, quad or open
//!   cylinder): a regular grid of light rays covering the generator's bounding sphere
//!   as the light sees it: a square on the plane through the centre perpendicular to
//!   a directional light, or a square of directions around the cone a point/spot
//!   light sees the sphere in. Rays that miss the generator are dropped by the trace.

use bytemuck::{Pod, Zeroable};
use caustics_scene::{Light, Shape, TriangleMesh, Vec3};

/// Matches `Source` in trace.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Source {
    /// xyz: surface point or ray origin; w: `SOURCE_SURFACE` (0) or `SOURCE_RAY` (1).
    pub origin: [f32; 4],
    /// xyz: surface normal or unit ray direction.
    pub dir_or_normal: [f32; 4],
}

/// Sources and triangles of a wavefront.
#[derive(Clone, Debug)]
pub struct WavefrontMesh {
    /// One per vertex.
    pub sources: Vec<Source>,
    /// Three vertex indices per triangle.
    pub triangles: Vec<u32>,
}

fn orthonormal_basis(w: Vec3) -> (Vec3, Vec3) {
    let a = if w.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = w.cross(a).normalize();
    (u, w.cross(u))
}

fn grid_triangles(n: u32) -> Vec<u32> {
    let mut t = Vec::with_capacity(((n - 1) * (n - 1) * 6) as usize);
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v00 = j * n + i;
            let (v10, v01, v11) = (v00 + 1, v00 + n, v00 + n + 1);
            t.extend_from_slice(&[v00, v10, v11, v00, v11, v01]);
        }
    }
    t
}

/// Heightfield: the tessellated surface, vertex for vertex.
pub(crate) fn from_surface(mesh: &TriangleMesh) -> WavefrontMesh {
    let sources = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .map(|(p, n)| Source {
            origin: p.extend(0.0).to_array(),
            dir_or_normal: n.extend(0.0).to_array(),
        })
        .collect();
    WavefrontMesh {
        sources,
        triangles: mesh.indices.clone(),
    }
}

/// A `grid`×`grid` lattice of light rays covering the sphere (`center`, `radius`)
/// with a 2 % margin, so that the silhouette lies inside the lattice. Returns `None`
/// when a point/spot light sits inside the sphere.
pub(crate) fn ray_lattice(
    center: Vec3,
    radius: f32,
    light: &Light,
    grid: u32,
) -> Option<WavefrontMesh> {
    let n = grid;
    let mut sources = Vec::with_capacity((n * n) as usize);
    let lattice = |k: u32| (k as f32 / (n - 1) as f32) * 2.0 - 1.0;
    match *light {
        // Declined by the capability check (no wavefront of an extended light).
        Light::Sphere { .. } | Light::Environment { .. } => return None,
        Light::Directional { direction, .. } => {
            let (u, v) = orthonormal_basis(direction);
            let half = radius * 1.02;
            for j in 0..n {
                for i in 0..n {
                    let o = center + u * (lattice(i) * half) + v * (lattice(j) * half)
                        - direction * (2.0 * radius + 1.0);
                    sources.push(Source {
                        origin: o.extend(1.0).to_array(),
                        dir_or_normal: direction.extend(0.0).to_array(),
                    });
                }
            }
        }
        Light::Point { position, .. } | Light::Spot { position, .. } => {
            let to_center = center - position;
            let dist = to_center.length();
            if dist <= radius * 1.0001 {
                return None;
            }
            let w = to_center / dist;
            let (u, v) = orthonormal_basis(w);
            let half = (radius / dist).asin().tan() * 1.02;
            for j in 0..n {
                for i in 0..n {
                    let d = (w + u * (lattice(i) * half) + v * (lattice(j) * half)).normalize();
                    sources.push(Source {
                        origin: position.extend(1.0).to_array(),
                        dir_or_normal: d.extend(0.0).to_array(),
                    });
                }
            }
        }
    }
    Some(WavefrontMesh {
        sources,
        triangles: grid_triangles(n),
    })
}

/// The smallest sphere the lattice must cover for an analytic generator.
pub(crate) fn bounding_sphere(shape: &Shape) -> (Vec3, f32) {
    match shape {
        Shape::Sphere { center, radius } => (*center, *radius),
        Shape::Quad { center, size, .. } => (*center, 0.5 * size.length()),
        Shape::Cylinder {
            center,
            radius,
            height,
            ..
        } => (*center, radius.hypot(0.5 * height)),
        other => {
            let b = other.bounds();
            (b.center(), b.bounding_sphere_radius())
        }
    }
}

/// The wavefront of `shape` (the scene's one specular object): its vertex grid for a
/// heightfield, else a ray lattice over its bounding sphere (`None`: light inside it).
pub(crate) fn for_shape(
    shape: &Shape,
    mesh: &TriangleMesh,
    light: &Light,
    grid: u32,
) -> Option<WavefrontMesh> {
    match shape {
        Shape::Heightfield(_) => Some(from_surface(mesh)),
        other => {
            let (center, radius) = bounding_sphere(other);
            ray_lattice(center, radius, light, grid)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_has_two_triangles_per_cell_in_range() {
        let t = grid_triangles(4);
        assert_eq!(t.len(), 3 * 3 * 6);
        assert!(t.iter().all(|&i| i < 16));
    }

    #[test]
    fn directional_rays_cover_the_sphere_silhouette() {
        let light = Light::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::ONE,
        };
        let m = ray_lattice(Vec3::new(0.0, 1.0, 0.0), 1.0, &light, 9).expect("light outside");
        assert_eq!(m.sources.len(), 81);
        let xs: Vec<f32> = m.sources.iter().map(|s| s.origin[0]).collect();
        let max = xs.iter().cloned().fold(f32::MIN, f32::max);
        assert!((max - 1.02).abs() < 1e-5, "{max}");
        assert!(
            m.sources
                .iter()
                .all(|s| s.origin[1] > 2.0 && s.dir_or_normal[1] == -1.0)
        );
    }

    #[test]
    fn point_light_inside_sphere_is_refused() {
        let light = Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        };
        assert!(ray_lattice(Vec3::ZERO, 1.0, &light, 4).is_none());
    }
}
