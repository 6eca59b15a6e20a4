//! Mesh objects in one BVH (heightfields have their own grid, [`crate::heightfield`]).
//!
//! The BVH is [`obvhs`]'s compressed wide BVH8 (CWBVH, Ylitie et al. 2017) built with
//! PLOC: a maintained crate, on glam like the rest of the workspace (obvhs 0.3 takes
//! glam 0.30, so no second glam is built), with SIMD node tests and no heavy math
//! dependency (the `bvh` crate pulls in nalgebra). Only meshes go in it; analytic
//! shapes are intersected exactly in [`crate::geometry`].
//!
//! Normals follow DESIGN.md "Conventions": mesh hits interpolate the vertex normals
//! with the hit's barycentrics (smooth shading, never flat facets).

use std::time::Duration;

use caustics_scene::{Scene, Shape, Tessellation};
use glam::Vec3A as Vec3;
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle,
};

use crate::eps;
use crate::geometry::Hit;

/// All mesh objects of a scene with their BVH.
pub(crate) struct Triangles {
    bvh: CwBvh,
    /// Triangles in BVH primitive order.
    tris: Vec<Triangle>,
    /// Per triangle (BVH order): object index.
    owner: Vec<u32>,
    /// Per triangle (BVH order): vertex normals.
    normals: Vec<[Vec3; 3]>,
}

impl Triangles {
    /// The mesh objects of `scene`, or `None` if it has none.
    pub(crate) fn new(scene: &Scene) -> Option<Triangles> {
        let mut tris = Vec::new();
        let mut owner = Vec::new();
        let mut normals = Vec::new();
        for (i, o) in scene.objects.iter().enumerate() {
            if !matches!(o.shape, Shape::Mesh(_)) {
                continue;
            }
            let mesh = o.shape.triangulate(&Tessellation::default());
            for t in 0..mesh.triangle_count() {
                let idx = &mesh.indices[3 * t..3 * t + 3];
                let [a, b, c] = mesh.triangle(t);
                tris.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                owner.push(i as u32);
                normals.push([
                    mesh.normals[idx[0] as usize].into(),
                    mesh.normals[idx[1] as usize].into(),
                    mesh.normals[idx[2] as usize].into(),
                ]);
            }
        }
        if tris.is_empty() {
            return None;
        }
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        // Reorder the primitives to BVH order so traversal needs no indirection.
        let order = &bvh.primitive_indices;
        let tris_o = order.iter().map(|&k| tris[k as usize]).collect();
        let owner_o = order.iter().map(|&k| owner[k as usize]).collect();
        let normals_o = order.iter().map(|&k| normals[k as usize]).collect();
        Some(Triangles {
            bvh,
            tris: tris_o,
            owner: owner_o,
            normals: normals_o,
        })
    }

    /// The closest triangle hit with `T_MIN < t < t_max`.
    #[inline]
    pub(crate) fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        let ray = Ray::new(o, d, eps::T_MIN, t_max);
        let mut hit = RayHit::none();
        if !self
            .bvh
            .ray_traverse(ray, &mut hit, |r, id| self.tris[id].intersect(r))
        {
            return None;
        }
        let k = hit.primitive_id as usize;
        let t = hit.t;
        let tri = &self.tris[k];
        let p = o + t * d;
        let (v0, v1, v2) = (tri.v0, tri.v1, tri.v2);
        let ng = (v1 - v0).cross(v2 - v0).normalize();
        let object = self.owner[k];
        let [b0, b1, b2] = barycentric(p, v0, v1, v2);
        let [n0, n1, n2] = self.normals[k];
        let ns = (b0 * n0 + b1 * n1 + b2 * n2).normalize_or(ng);
        let ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
        Some(Hit {
            t,
            p,
            ng,
            ns,
            object,
        })
    }

    /// True if a triangle lies at `T_MIN < t < t_max`.
    #[inline]
    pub(crate) fn occluded(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        let ray = Ray::new(o, d, eps::T_MIN, t_max);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, id| self.tris[id].intersect(r))
    }
}

/// Barycentric coordinates of `p` (on the triangle's plane) for (v0, v1, v2).
fn barycentric(p: Vec3, v0: Vec3, v1: Vec3, v2: Vec3) -> [f32; 3] {
    let (e1, e2, q) = (v1 - v0, v2 - v0, p - v0);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (q.dot(e1), q.dot(e2));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() < f32::MIN_POSITIVE {
        return [1.0 / 3.0; 3];
    }
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    [1.0 - b1 - b2, b1, b2]
}
