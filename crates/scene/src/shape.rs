//! Shapes, their bounds and the conventions that fix their geometry.

use std::path::PathBuf;

use glam::{Vec2, Vec3};

/// A geometric primitive of the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre in metres.
        center: Vec3,
        /// Radius in metres (> 0).
        radius: f32,
    },
    /// A rectangle (one-sided for normals, a surface on both sides for light).
    /// Its in-plane axes are [`quad_axes`]`(normal)`: `size.x` along u, `size.y` along v.
    Quad {
        /// Centre in metres.
        center: Vec3,
        /// Unit normal.
        normal: Vec3,
        /// Side lengths along u and v, in metres (> 0).
        size: Vec2,
    },
    /// A water-like surface: a grid displaced by a sum of sine waves.
    Heightfield(Heightfield),
    /// An OPEN cylinder (no caps), the "ring" of Wand & Strasser's napkin-ring scene:
    /// centred at `center`, extending ±`height`/2 along `axis`. Normals point outward,
    /// but both sides are surfaces (a mirror ring reflects on its inside too).
    Cylinder {
        /// Centre (mid-height on the axis) in metres.
        center: Vec3,
        /// Unit axis.
        axis: Vec3,
        /// Radius in metres (> 0).
        radius: f32,
        /// Height along the axis in metres (> 0).
        height: f32,
    },
    /// A triangle mesh loaded from OBJ or glTF, already in world space.
    Mesh(Mesh),
}

/// The in-plane axes (u, v) of a quad with unit `normal`.
///
/// a = +Z if |normal.z| < 0.999, else +X; u = normalize(normal × a); v = normal × u.
/// (u, v, normal) is a right-handed orthonormal frame (u × v = normal), so a polygon
/// counter-clockwise in (u, v) is counter-clockwise seen from the normal side.
/// For a floor (normal +Y): u = +X and v = −Z.
pub fn quad_axes(normal: Vec3) -> (Vec3, Vec3) {
    let a = if normal.z.abs() < 0.999 {
        Vec3::Z
    } else {
        Vec3::X
    };
    let u = normal.cross(a).normalize();
    let v = normal.cross(u);
    (u, v)
}

/// A unit vector pair (b1, b2) perpendicular to the unit `axis` with b1 × b2 = axis
/// (the same rule as [`quad_axes`]).
pub fn perpendicular_frame(axis: Vec3) -> (Vec3, Vec3) {
    quad_axes(axis)
}

/// A heightfield: y = center.y + Σ a·sin(2π/λ · (d̂·(x, z)) + phase) in world x, z.
///
/// `resolution` is the number of vertices per axis, spread evenly over `size` around
/// `center` (so the first and last vertices lie on the border). The +y side is the
/// outside (DESIGN.md, "Heightfield").
#[derive(Clone, Debug, PartialEq)]
pub struct Heightfield {
    /// Centre of the rectangle; `center.y` is the rest height.
    pub center: Vec3,
    /// Extent along x and z in metres.
    pub size: Vec2,
    /// Vertex count along x and z (each in 2..=4096).
    pub resolution: [u32; 2],
    /// The waves summed into the height.
    pub waves: Vec<Wave>,
}

/// One sine wave of a [`Heightfield`].
#[derive(Clone, Debug, PartialEq)]
pub struct Wave {
    /// Amplitude a in metres.
    pub amplitude: f32,
    /// Wavelength λ in metres (> 0).
    pub wavelength: f32,
    /// Unit direction d̂ in the (x, z) plane.
    pub direction: Vec2,
    /// Phase in radians.
    pub phase: f32,
}

impl Wave {
    /// Wave number 2π/λ.
    pub fn wavenumber(&self) -> f32 {
        std::f32::consts::TAU / self.wavelength
    }
}

impl Heightfield {
    /// World-space height y at world (x, z).
    pub fn height(&self, x: f32, z: f32) -> f32 {
        let p = Vec2::new(x, z);
        self.center.y
            + self
                .waves
                .iter()
                .map(|w| w.amplitude * (w.wavenumber() * w.direction.dot(p) + w.phase).sin())
                .sum::<f32>()
    }

    /// The gradient (∂y/∂x, ∂y/∂z) at world (x, z).
    pub fn gradient(&self, x: f32, z: f32) -> Vec2 {
        let p = Vec2::new(x, z);
        self.waves
            .iter()
            .map(|w| {
                let k = w.wavenumber();
                w.direction * (w.amplitude * k * (k * w.direction.dot(p) + w.phase).cos())
            })
            .sum()
    }

    /// The analytic unit normal on the +y side: normalize(−∂y/∂x, 1, −∂y/∂z).
    pub fn normal(&self, x: f32, z: f32) -> Vec3 {
        let g = self.gradient(x, z);
        Vec3::new(-g.x, 1.0, -g.y).normalize()
    }

    /// Grid vertex (i, j), i along x in `0..resolution[0]`, j along z in
    /// `0..resolution[1]`: x = center.x − size.x/2 + size.x · i/(`resolution[0]` − 1),
    /// likewise z; y = [`Heightfield::height`].
    pub fn vertex(&self, i: u32, j: u32) -> Vec3 {
        let (x, z) = self.grid_xz(i, j);
        Vec3::new(x, self.height(x, z), z)
    }

    /// The (x, z) of grid vertex (i, j), see [`Heightfield::vertex`].
    pub fn grid_xz(&self, i: u32, j: u32) -> (f32, f32) {
        let step = |c: f32, s: f32, k: u32, n: u32| c - 0.5 * s + s * k as f32 / (n - 1) as f32;
        (
            step(self.center.x, self.size.x, i, self.resolution[0]),
            step(self.center.z, self.size.y, j, self.resolution[1]),
        )
    }

    /// Σ|a|: the surface lies within center.y ± this.
    pub fn max_displacement(&self) -> f32 {
        self.waves.iter().map(|w| w.amplitude.abs()).sum()
    }
}

/// A triangle mesh from a file, transformed to world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// The mesh file, resolved against the scene file's folder.
    pub path: PathBuf,
    /// World-space positions (the object's transform applied).
    pub positions: Vec<Vec3>,
    /// World-space unit vertex normals, one per position, interpolated for shading.
    pub normals: Vec<Vec3>,
    /// Triangle list, counter-clockwise seen from the side the normals point to.
    pub indices: Vec<u32>,
    /// True if the normals came from the file; false if they were computed as
    /// area-weighted smooth normals (vertices at one position share one normal).
    pub normals_from_file: bool,
    /// Faces of the file dropped on load as degenerate: two equal corner indices, or a
    /// zero (or non-finite) area after the transform. They are not in `indices`.
    pub degenerate_dropped: usize,
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞); the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding all `points` ([`Aabb::EMPTY`] if there are none).
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| Aabb {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }

    /// True if the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Full side lengths, max − min.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Radius of the sphere around [`Aabb::center`] through the corners: half the diagonal.
    pub fn bounding_sphere_radius(&self) -> f32 {
        0.5 * self.extent().length()
    }

    /// The eight corners (bit 0 of the index picks x, bit 1 y, bit 2 z: 0 = min).
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// True if `p` lies inside or on the box.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Where a directional light along the unit `dir` starts its light for a scene of
    /// these bounds: the distance along `dir` of a plane 1 m before the box's nearest
    /// corner, so the whole box lies ahead of it. The reference emits its directional
    /// photons from this plane and the methods with a medium count extinction from it,
    /// so both agree on the light's path length.
    pub fn directional_start(&self, dir: Vec3) -> f32 {
        self.corners()
            .iter()
            .map(|c| c.dot(dir))
            .fold(f32::INFINITY, f32::min)
            - 1.0
    }
}

impl Shape {
    /// The exact axis-aligned bounds (for heightfields: x, z range and center.y ± Σ|a|).
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere { center, radius } => Aabb {
                min: *center - Vec3::splat(*radius),
                max: *center + Vec3::splat(*radius),
            },
            Shape::Quad {
                center,
                normal,
                size,
            } => {
                let (u, v) = quad_axes(*normal);
                let (hu, hv) = (0.5 * size.x * u, 0.5 * size.y * v);
                Aabb::from_points([
                    *center - hu - hv,
                    *center + hu - hv,
                    *center + hu + hv,
                    *center - hu + hv,
                ])
            }
            Shape::Heightfield(h) => {
                let d = h.max_displacement();
                let half = Vec3::new(0.5 * h.size.x, d, 0.5 * h.size.y);
                Aabb {
                    min: h.center - half,
                    max: h.center + half,
                }
            }
            Shape::Cylinder {
                center,
                axis,
                radius,
                height,
            } => {
                // Per world axis k: half extent = h/2·|a_k| + r·sqrt(1 − a_k²).
                let a = axis.abs();
                let half =
                    0.5 * height * a + *radius * (Vec3::ONE - a * a).max(Vec3::ZERO).map(f32::sqrt);
                Aabb {
                    min: *center - half,
                    max: *center + half,
                }
            }
            Shape::Mesh(m) => Aabb::from_points(m.positions.iter().copied()),
        }
    }

    /// A short name of the shape's kind: "sphere", "quad", "heightfield", "cylinder", "mesh".
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Quad { .. } => "quad",
            Shape::Heightfield(_) => "heightfield",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Mesh(_) => "mesh",
        }
    }
}
