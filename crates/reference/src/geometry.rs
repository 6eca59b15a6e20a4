//! Analytic primitives (sphere, quad, open cylinder) and the scene's intersector,
//! which adds the heightfields of [`crate::heightfield`] and the meshes of
//! [`crate::bvh`]. Epsilons: [`crate::eps`].

use caustics_scene::{Scene, Shape, quad_axes};
use glam::Vec3A as Vec3;

use crate::bvh::Triangles;
use crate::eps;
use crate::heightfield::HeightGrid;

/// A surface hit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    /// Distance along the unit ray direction.
    pub(crate) t: f32,
    /// World position.
    pub(crate) p: Vec3,
    /// Unit geometric normal, pointing to the shape's outside (the side that faces
    /// the normal of the scene description: outward for spheres and cylinders, the
    /// quad's normal, +y for heightfields, the winding side for meshes).
    pub(crate) ng: Vec3,
    /// Unit shading normal (analytic or interpolated), on the same side as `ng`.
    pub(crate) ns: Vec3,
    /// Index of the object in the scene.
    pub(crate) object: u32,
}

/// An analytic primitive.
#[derive(Clone, Debug)]
enum Analytic {
    Sphere {
        center: Vec3,
        radius: f32,
    },
    Quad {
        center: Vec3,
        normal: Vec3,
        u: Vec3,
        v: Vec3,
        half: [f32; 2],
    },
    Cylinder {
        center: Vec3,
        axis: Vec3,
        radius: f32,
        half_height: f32,
    },
}

/// The scene's geometry: analytic primitives tested one by one (there are few),
/// heightfields on their own grids, and meshes in one BVH.
pub(crate) struct Geometry {
    analytic: Vec<(Analytic, u32)>,
    heightfields: Vec<HeightGrid>,
    triangles: Option<Triangles>,
}

impl Geometry {
    /// Builds the intersector of `scene`.
    pub(crate) fn new(scene: &Scene) -> Geometry {
        let mut analytic = Vec::new();
        let mut heightfields = Vec::new();
        for (i, o) in scene.objects.iter().enumerate() {
            let prim = match &o.shape {
                Shape::Sphere { center, radius } => Analytic::Sphere {
                    center: (*center).into(),
                    radius: *radius,
                },
                Shape::Quad {
                    center,
                    normal,
                    size,
                } => {
                    let (u, v) = quad_axes(*normal);
                    Analytic::Quad {
                        center: (*center).into(),
                        normal: (*normal).into(),
                        u: u.into(),
                        v: v.into(),
                        half: [0.5 * size.x, 0.5 * size.y],
                    }
                }
                Shape::Cylinder {
                    center,
                    axis,
                    radius,
                    height,
                } => Analytic::Cylinder {
                    center: (*center).into(),
                    axis: (*axis).into(),
                    radius: *radius,
                    half_height: 0.5 * height,
                },
                Shape::Heightfield(_) => {
                    heightfields.extend(HeightGrid::new(&o.shape, i as u32));
                    continue;
                }
                Shape::Mesh(_) => continue,
            };
            analytic.push((prim, i as u32));
        }
        Geometry {
            analytic,
            heightfields,
            triangles: Triangles::new(scene),
        }
    }

    /// The closest hit with `eps::T_MIN < t < t_max` along the unit direction `d`.
    #[inline]
    pub(crate) fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<Hit> {
        let mut best: Option<usize> = None;
        let mut t_best = t_max;
        for (k, (prim, _)) in self.analytic.iter().enumerate() {
            if let Some(t) = prim.distance(o, d, t_best) {
                t_best = t;
                best = Some(k);
            }
        }
        let mut hit = best.map(|k| {
            let (prim, obj) = &self.analytic[k];
            prim.hit_at(o, d, t_best, *obj)
        });
        for grid in &self.heightfields {
            if let Some(h) = grid.intersect(o, d, t_best) {
                t_best = h.t;
                hit = Some(h);
            }
        }
        if let Some(tris) = &self.triangles
            && let Some(h) = tris.intersect(o, d, t_best)
        {
            return Some(h);
        }
        hit
    }

    /// True if anything lies on the segment `eps::T_MIN < t < t_max` along `d`.
    #[inline]
    pub(crate) fn occluded(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        self.analytic
            .iter()
            .any(|(prim, _)| prim.distance(o, d, t_max).is_some())
            || self.heightfields.iter().any(|g| g.occluded(o, d, t_max))
            || self
                .triangles
                .as_ref()
                .is_some_and(|t| t.occluded(o, d, t_max))
    }
}

impl Analytic {
    /// The distance to the closest hit with `eps::T_MIN < t < t_max`.
    #[inline(always)]
    fn distance(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<f32> {
        match *self {
            Analytic::Sphere { center, radius } => {
                // Closest-point form: the roots are t_c ± h with |f| computed exactly.
                let oc = o - center;
                let tc = -oc.dot(d);
                let f = oc + tc * d;
                let disc = radius * radius - f.length_squared();
                if disc < 0.0 {
                    return None;
                }
                let h = disc.sqrt();
                first_root(tc - h, tc + h, t_max)
            }
            Analytic::Quad {
                center,
                normal,
                u,
                v,
                half,
            } => {
                let dn = d.dot(normal);
                if dn.abs() < 1e-12 {
                    return None;
                }
                let t = (center - o).dot(normal) / dn;
                if !(t > eps::T_MIN && t < t_max) {
                    return None;
                }
                let p = o + t * d;
                let r = p - center;
                if r.dot(u).abs() > half[0] || r.dot(v).abs() > half[1] {
                    return None;
                }
                Some(t)
            }
            Analytic::Cylinder {
                center,
                axis,
                radius,
                half_height,
            } => {
                let oc = o - center;
                let o_perp = oc - oc.dot(axis) * axis;
                let d_perp = d - d.dot(axis) * axis;
                let a = d_perp.length_squared();
                if a < 1e-12 {
                    return None;
                }
                let tc = -o_perp.dot(d_perp) / a;
                let f = o_perp + tc * d_perp;
                let disc = radius * radius - f.length_squared();
                if disc < 0.0 {
                    return None;
                }
                let h = (disc / a).sqrt();
                let in_height = |t: f32| (oc + t * d).dot(axis).abs() <= half_height;
                [tc - h, tc + h]
                    .into_iter()
                    .find(|&t| t > eps::T_MIN && t < t_max && in_height(t))
            }
        }
    }

    /// The hit at distance `t` (from [`Analytic::distance`]).
    #[inline(always)]
    fn hit_at(&self, o: Vec3, d: Vec3, t: f32, object: u32) -> Hit {
        let p = o + t * d;
        let n = match *self {
            Analytic::Sphere { center, .. } => (p - center).normalize(),
            Analytic::Quad { normal, .. } => normal,
            Analytic::Cylinder { center, axis, .. } => {
                let r = p - center;
                (r - r.dot(axis) * axis).normalize()
            }
        };
        Hit {
            t,
            p,
            ng: n,
            ns: n,
            object,
        }
    }
}

/// The smaller of two sorted roots inside (`T_MIN`, `t_max`).
#[inline]
fn first_root(t0: f32, t1: f32, t_max: f32) -> Option<f32> {
    if t0 > eps::T_MIN && t0 < t_max {
        Some(t0)
    } else if t1 > eps::T_MIN && t1 < t_max {
        Some(t1)
    } else {
        None
    }
}
