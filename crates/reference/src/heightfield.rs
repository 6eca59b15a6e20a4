//! Heightfields intersected on their own grid instead of through a generic BVH.
//!
//! The triangles are exactly those of [`caustics_scene::Shape::triangulate`] (same
//! vertices, same two triangles per cell, same winding) and are tested with the same
//! ray–triangle test as the BVH of [`crate::bvh`]; only the search differs. A ray is
//! clipped to the heightfield's box, then walks the cells it crosses in (x, z) in
//! order (a 2D DDA); a cell's two triangles are tested only where the ray's height
//! over the cell overlaps the cell's height range (widened by a margin), and the
//! walk stops at the first cell holding a hit: triangles of later cells lie farther
//! along the ray. Normals follow DESIGN.md "Conventions": the analytic
//! [`Heightfield::normal`] at the hit's (x, z), turned to the facet's side.

use caustics_scene::{Heightfield, Shape, Tessellation};
use glam::{Vec3A, Vec3A as Vec3};
use obvhs::{ray::Ray, triangle::Triangle};

use crate::eps;
use crate::geometry::Hit;

/// One heightfield object on its grid.
pub(crate) struct HeightGrid {
    field: Heightfield,
    object: u32,
    /// Cells along x and z.
    cells: [usize; 2],
    /// Grid vertices (row-major, z rows of x), as triangulated.
    vertices: Vec<Vec3A>,
    /// Per cell: lowest and highest vertex height, widened by `margin`.
    bounds: Vec<[f32; 2]>,
    /// World x and z of vertex (0, 0), and cell sizes along x and z.
    origin: [f32; 2],
    step: [f32; 2],
    /// The box holding every vertex: min and max corners.
    lo: Vec3,
    hi: Vec3,
}

impl HeightGrid {
    /// The grid of object `object`, or `None` if its shape is not a heightfield.
    pub(crate) fn new(shape: &Shape, object: u32) -> Option<HeightGrid> {
        let Shape::Heightfield(h) = shape else {
            return None;
        };
        let mesh = shape.triangulate(&Tessellation::default());
        let [nx, nz] = h.resolution.map(|r| r as usize);
        let vertices: Vec<Vec3A> = mesh.positions.iter().map(|&p| p.into()).collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &mesh.positions {
            lo = lo.min((*p).into());
            hi = hi.max((*p).into());
        }
        let margin = 1e-5 * (1.0 + lo.abs().max(hi.abs()).max_element());
        let cells = [nx - 1, nz - 1];
        let mut bounds = Vec::with_capacity(cells[0] * cells[1]);
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let ys = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                    .map(|(a, b)| vertices[b * nx + a].y);
                let min = ys.iter().copied().fold(f32::INFINITY, f32::min);
                let max = ys.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                bounds.push([min - margin, max + margin]);
            }
        }
        let (x0, z0) = h.grid_xz(0, 0);
        let (x1, z1) = h.grid_xz(h.resolution[0] - 1, h.resolution[1] - 1);
        let margin3 = Vec3::splat(margin);
        Some(HeightGrid {
            field: h.clone(),
            object,
            cells,
            vertices,
            bounds,
            origin: [x0, z0],
            step: [(x1 - x0) / cells[0] as f32, (z1 - z0) / cells[1] as f32],
            lo: lo - margin3,
            hi: hi + margin3,
        })
    }

    /// The two triangles of cell (i, j), in the order and winding of the mesh.
    #[inline]
    fn triangles(&self, i: usize, j: usize) -> [Triangle; 2] {
        let nx = self.cells[0] + 1;
        let v00 = j * nx + i;
        let (v10, v01) = (v00 + 1, v00 + nx);
        let v11 = v01 + 1;
        let v = &self.vertices;
        [
            Triangle {
                v0: v[v00],
                v1: v[v01],
                v2: v[v10],
            },
            Triangle {
                v0: v[v10],
                v1: v[v01],
                v2: v[v11],
            },
        ]
    }

    /// The parameter range of the ray inside the box, clipped to (`T_MIN`, `t_max`).
    #[inline]
    fn clip(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let (mut t0, mut t1) = (eps::T_MIN, t_max);
        for a in 0..3 {
            let (oa, da, lo, hi) = (o[a], d[a], self.lo[a], self.hi[a]);
            if da == 0.0 {
                if !(oa >= lo && oa <= hi) {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / da;
            let (ta, tb) = ((lo - oa) * inv, (hi - oa) * inv);
            let (ta, tb) = if ta < tb { (ta, tb) } else { (tb, ta) };
            t0 = t0.max(ta);
            t1 = t1.min(tb);
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The closest hit with `T_MIN < t < t_max`: distance, cell (i, j) and which of
    /// its two triangles.
    #[inline]
    fn first(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, usize, usize, usize)> {
        let (t0, t1) = self.clip(o, d, t_max)?;
        let ray = Ray::new(o, d, eps::T_MIN, t_max);
        let [cx, cz] = self.cells;
        let p = o + t0 * d;
        let cell = |c: f32, origin: f32, step: f32, n: usize| {
            (((c - origin) / step).floor().max(0.0) as usize).min(n - 1)
        };
        let mut i = cell(p.x, self.origin[0], self.step[0], cx);
        let mut j = cell(p.z, self.origin[1], self.step[1], cz);
        // Per axis: the t of the next cell boundary, its increment, and the step.
        let axis = |oa: f32, da: f32, k: usize, origin: f32, step: f32| {
            if da > 0.0 {
                let next = origin + (k + 1) as f32 * step;
                ((next - oa) / da, step / da, 1isize)
            } else if da < 0.0 {
                let next = origin + k as f32 * step;
                ((next - oa) / da, -step / da, -1isize)
            } else {
                (f32::INFINITY, f32::INFINITY, 0isize)
            }
        };
        let (mut next_x, delta_x, step_x) = axis(o.x, d.x, i, self.origin[0], self.step[0]);
        let (mut next_z, delta_z, step_z) = axis(o.z, d.z, j, self.origin[1], self.step[1]);
        let mut t_enter = t0;
        loop {
            let t_exit = next_x.min(next_z).min(t1);
            let [ymin, ymax] = self.bounds[j * cx + i];
            let (ya, yb) = (o.y + t_enter * d.y, o.y + t_exit * d.y);
            if ya.max(yb) >= ymin && ya.min(yb) <= ymax {
                let [a, b] = self.triangles(i, j);
                let (ta, tb) = (a.intersect(&ray), b.intersect(&ray));
                // `intersect` gives INFINITY for a miss and accepts t = tmin.
                let ok = |t: f32| t > eps::T_MIN && t < t_max;
                let best = match (ok(ta), ok(tb)) {
                    (true, true) if tb < ta => Some((tb, 1)),
                    (true, _) => Some((ta, 0)),
                    (false, true) => Some((tb, 1)),
                    (false, false) => None,
                };
                if let Some((t, which)) = best {
                    return Some((t, i, j, which));
                }
            }
            if t_exit >= t1 {
                return None;
            }
            if next_x < next_z {
                i = i.checked_add_signed(step_x).filter(|&k| k < cx)?;
                t_enter = next_x;
                next_x += delta_x;
            } else {
                j = j.checked_add_signed(step_z).filter(|&k| k < cz)?;
                t_enter = next_z;
                next_z += delta_z;
            }
        }
    }

    /// The closest hit with `T_MIN < t < t_max` along the unit direction `d`.
    #[inline]
    pub(crate) fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        let (t, i, j, which) = self.first(o, d, t_max)?;
        let tri = self.triangles(i, j)[which];
        let p = o + t * d;
        let (v0, v1, v2) = (tri.v0, tri.v1, tri.v2);
        let ng = (v1 - v0).cross(v2 - v0).normalize();
        let ns = Vec3::from(self.field.normal(p.x, p.z));
        let ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
        Some(Hit {
            t,
            p,
            ng,
            ns,
            object: self.object,
        })
    }

    /// True if the heightfield lies at `T_MIN < t < t_max`.
    #[inline]
    pub(crate) fn occluded(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        self.first(o, d, t_max).is_some()
    }
}
