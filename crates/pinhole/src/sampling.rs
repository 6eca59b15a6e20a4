//! Point samples on the reflector (Wand & Straßer 2003, §3.2), built once per scene on
//! the CPU from a seeded generator, so that a (strategy, count, seed) triple always
//! gives the same samples.
//!
//! Every strategy returns exactly the requested number of samples. Each sample
//! carries its position, its unit normal, the principal directions and curvatures of
//! the surface there (a "differential point sample", §3.3) and the surface area it
//! stands for. Curvature is analytic for the sphere, the open cylinder and the quad;
//! on triangle meshes and tessellated heightfields ([`Surface::Triangles`]) it is the
//! triangle's shape operator fitted to its vertex normals (Rusinkiewicz 2004, §3: the
//! change of the normal along each edge), where the paper fits a second-order surface
//! to a denser set of samples around each sample point: both estimate the same local
//! second-order shape, and the vertex normals are the surface the scene defines. The
//! areas sum to the surface area:
//!
//! * `random`: uniform by area; each sample stands for A/N.
//! * `grid`: from 8N uniform candidates, one per occupied cube of a 3D grid whose cell
//!   size is searched so that at least N cubes are occupied; a sample stands for the
//!   share of candidates in its cube (this corrects the bias the paper notes: a
//!   surface diagonal to the grid gets fewer samples, each standing for more area).
//! * `quantized`: `grid` with each sample moved to its cube's centre (the paper's
//!   strategy 3, with its displacement); the normal stays that of the chosen point.
//! * `neighbor_removal`: from 8N uniform candidates in random order, a candidate is
//!   kept unless a kept sample lies within distance r (greedy Poisson-disc removal),
//!   r searched so that at least N are kept; a sample stands for the share of
//!   candidates nearest to it.
//!
//! When a search overshoots N, the surplus samples (chosen by the seeded generator)
//! are dropped and the remaining areas are rescaled to sum to A.

use std::collections::HashMap;

use caustics_scene::{Aabb, Shape, TriangleMesh, Vec3, perpendicular_frame, quad_axes};
use serde::{Deserialize, Serialize};

/// Candidates per requested sample for the stratifying strategies (the paper's
/// "random sample set with high density").
pub const OVERSAMPLING: usize = 8;

/// The paper's four sampling strategies (§3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// Uniform random points.
    Random,
    /// One random point per occupied grid cube.
    Grid,
    /// One point per occupied grid cube, moved to the cube's centre.
    Quantized,
    /// Greedy removal of points closer than r to a kept one (the paper's choice).
    #[default]
    NeighborRemoval,
}

impl Strategy {
    /// All four, in the paper's order.
    pub const ALL: [Strategy; 4] = [
        Strategy::Random,
        Strategy::Grid,
        Strategy::Quantized,
        Strategy::NeighborRemoval,
    ];

    /// The parameter value naming this strategy.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Random => "random",
            Strategy::Grid => "grid",
            Strategy::Quantized => "quantized",
            Strategy::NeighborRemoval => "neighbor_removal",
        }
    }
}

/// A point on an analytic surface with its local second-order shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position (m).
    pub position: Vec3,
    /// Unit outward normal.
    pub normal: Vec3,
    /// First principal direction (unit, tangent).
    pub t1: Vec3,
    /// Second principal direction (unit, tangent, ⟂ t1).
    pub t2: Vec3,
    /// Curvature along t1 (1/m): n(p + s·t1) ≈ n + s·k1·t1.
    pub k1: f32,
    /// Curvature along t2 (1/m).
    pub k2: f32,
}

/// One pinhole: a surface point and the area it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSample {
    /// Geometry and curvature at the sample.
    pub point: SurfacePoint,
    /// Surface area this sample stands for (m²).
    pub area: f32,
    /// How far the sample was moved off the surface (m): non-zero only for
    /// `quantized`. Visibility tests ignore occluders this close to the sample.
    pub displacement: f32,
}

/// Why samples cannot be generated.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SamplingError {
    /// Only spheres, open cylinders and quads have an analytic sampler (meshes and
    /// heightfields are sampled through their triangles, [`Surface::triangles`]).
    #[error("no analytic point sampler for a {0}")]
    UnsupportedShape(&'static str),
    /// Zero samples requested.
    #[error("at least one sample is needed")]
    NoSamples,
    /// The triangles have no area to sample.
    #[error("the generator's triangles have no area")]
    NoArea,
}

/// A generator's surface, as the sampler sees it.
#[derive(Clone, Debug)]
pub enum Surface<'a> {
    /// An analytic shape (sphere, open cylinder, quad).
    Analytic(&'a Shape),
    /// World-space triangles with vertex normals (a mesh, a tessellated heightfield).
    Triangles(TriangleSurface<'a>),
}

/// Triangles prepared for sampling by area: the cumulative areas, and each
/// triangle's principal frame and curvatures.
#[derive(Clone, Debug)]
pub struct TriangleSurface<'a> {
    mesh: &'a TriangleMesh,
    /// Cumulative triangle areas (m²), ending at the total.
    cumulative: Vec<f64>,
    /// Per triangle: (t1, t2, k1, k2), the principal frame of its shape operator.
    curvature: Vec<(Vec3, Vec3, f32, f32)>,
}

impl<'a> Surface<'a> {
    /// The triangles of `mesh` (zero-area triangles are never drawn).
    pub fn triangles(mesh: &'a TriangleMesh) -> Result<Self, SamplingError> {
        let mut cumulative = Vec::with_capacity(mesh.triangle_count());
        let mut curvature = Vec::with_capacity(mesh.triangle_count());
        let mut total = 0.0f64;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let area = 0.5 * (b - a).cross(c - a).length();
            total += if area.is_finite() { area as f64 } else { 0.0 };
            cumulative.push(total);
            curvature.push(triangle_curvature(mesh, t));
        }
        if total <= 0.0 {
            return Err(SamplingError::NoArea);
        }
        Ok(Surface::Triangles(TriangleSurface {
            mesh,
            cumulative,
            curvature,
        }))
    }

    /// Surface area (m²).
    pub fn area(&self) -> Result<f32, SamplingError> {
        match self {
            Surface::Analytic(shape) => area(shape),
            Surface::Triangles(t) => Ok(*t.cumulative.last().unwrap_or(&0.0) as f32),
        }
    }

    /// Bounds of the surface.
    pub fn bounds(&self) -> Aabb {
        match self {
            Surface::Analytic(shape) => shape.bounds(),
            Surface::Triangles(t) => Aabb::from_points(t.mesh.positions.iter().copied()),
        }
    }

    /// The point at uniform coordinates (u1, u2, u3) ∈ [0, 1)³, uniform by area (an
    /// analytic shape uses u1 and u2; triangles: u1 picks the triangle by area, u2 and
    /// u3 the point in it).
    pub fn point(&self, u1: f32, u2: f32, u3: f32) -> Result<SurfacePoint, SamplingError> {
        match self {
            Surface::Analytic(shape) => surface_point(shape, u1, u2),
            Surface::Triangles(t) => Ok(t.point(u1, u2, u3)),
        }
    }
}

impl TriangleSurface<'_> {
    fn point(&self, u1: f32, u2: f32, u3: f32) -> SurfacePoint {
        let total = *self.cumulative.last().unwrap_or(&0.0);
        let target = u1 as f64 * total;
        // First triangle whose cumulative area exceeds the target: zero-area
        // triangles (equal cumulative values) are never chosen.
        let t = self
            .cumulative
            .partition_point(|&c| c <= target)
            .min(self.cumulative.len() - 1);
        // Uniform barycentrics (the square-root warp).
        let r = u2.sqrt();
        let (w1, w2) = (r * (1.0 - u3), r * u3);
        let w0 = 1.0 - w1 - w2;
        let i = &self.mesh.indices[3 * t..3 * t + 3];
        let (p, n) = (&self.mesh.positions, &self.mesh.normals);
        let [i0, i1, i2] = [i[0] as usize, i[1] as usize, i[2] as usize];
        let position = w0 * p[i0] + w1 * p[i1] + w2 * p[i2];
        let normal = (w0 * n[i0] + w1 * n[i1] + w2 * n[i2])
            .try_normalize()
            .unwrap_or_else(|| facet_normal(self.mesh, t));
        let (t1, _, k1, k2) = self.curvature[t];
        // The triangle's principal frame, made tangent to the interpolated normal.
        let t1 = (t1 - t1.dot(normal) * normal)
            .try_normalize()
            .unwrap_or_else(|| perpendicular_frame(normal).0);
        SurfacePoint {
            position,
            normal,
            t1,
            t2: normal.cross(t1),
            k1,
            k2,
        }
    }
}

fn facet_normal(mesh: &TriangleMesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.triangle(t);
    (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Y)
}

/// The principal directions and curvatures of triangle `t`: the symmetric 2×2 shape
/// operator S (dn = S·dp in the facet's plane) that best fits the change of the vertex
/// normals along the three edges in the least-squares sense (Rusinkiewicz 2004, eq. 6),
/// then its eigenvectors. Sign: n(p + s·t1) ≈ n + s·k1·t1, so a sphere with outward
/// normals has k = 1/r.
fn triangle_curvature(mesh: &TriangleMesh, t: usize) -> (Vec3, Vec3, f32, f32) {
    let nf = facet_normal(mesh, t);
    let (u, v) = perpendicular_frame(nf);
    let i = &mesh.indices[3 * t..3 * t + 3];
    let corner = |k: usize| {
        let j = i[k % 3] as usize;
        (mesh.positions[j], mesh.normals[j])
    };
    // Normal equations of S = [[a, b], [b, c]] over the edges e (tangent coords
    // (eu, ev)) with normal change dn (du, dv): S·e = dn.
    let mut m = [[0.0f64; 3]; 3];
    let mut rhs = [0.0f64; 3];
    for k in 0..3 {
        let (p0, n0) = corner(k);
        let (p1, n1) = corner(k + 1);
        let (e, dn) = (p1 - p0, n1 - n0);
        let (eu, ev) = (e.dot(u) as f64, e.dot(v) as f64);
        let (du, dv) = (dn.dot(u) as f64, dn.dot(v) as f64);
        // du = a·eu + b·ev; dv = b·eu + c·ev.
        let rows = [([eu, ev, 0.0], du), ([0.0, eu, ev], dv)];
        for (row, y) in rows {
            for r in 0..3 {
                for c in 0..3 {
                    m[r][c] += row[r] * row[c];
                }
                rhs[r] += row[r] * y;
            }
        }
    }
    let (a, b, c) = match solve3(m, rhs) {
        Some(x) => (x[0], x[1], x[2]),
        None => (0.0, 0.0, 0.0),
    };
    // Eigen-decomposition of the symmetric 2×2.
    let mean = 0.5 * (a + c);
    let diff = 0.5 * (a - c);
    let root = (diff * diff + b * b).sqrt();
    let (k1, k2) = (mean + root, mean - root);
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    let t1 = (angle.cos() as f32) * u + (angle.sin() as f32) * v;
    let t2 = nf.cross(t1);
    (t1, t2, k1 as f32, k2 as f32)
}

/// Solves the 3×3 system m·x = rhs (Cramer's rule); None where it is singular.
fn solve3(m: [[f64; 3]; 3], rhs: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    let scale = m.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
    if !d.is_finite() || d.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut mk = m;
        for r in 0..3 {
            mk[r][k] = rhs[r];
        }
        *xk = det(&mk) / d;
    }
    Some(x)
}

/// SplitMix64: a small, seedable, well-mixed generator (deterministic per seed).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9e37_79b9_7f4a_7c15)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64) as usize % n
    }
}

/// Surface area of an analytic shape (m²).
pub fn area(shape: &Shape) -> Result<f32, SamplingError> {
    use std::f32::consts::PI;
    match shape {
        Shape::Sphere { radius, .. } => Ok(4.0 * PI * radius * radius),
        Shape::Cylinder { radius, height, .. } => Ok(2.0 * PI * radius * height),
        Shape::Quad { size, .. } => Ok(size.x * size.y),
        other => Err(SamplingError::UnsupportedShape(other.kind())),
    }
}

/// The point of `shape` at uniform coordinates (u1, u2) ∈ [0, 1)² (uniform by area).
pub fn surface_point(shape: &Shape, u1: f32, u2: f32) -> Result<SurfacePoint, SamplingError> {
    use std::f32::consts::TAU;
    match *shape {
        Shape::Sphere { center, radius } => {
            let z = 1.0 - 2.0 * u1;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let phi = TAU * u2;
            let n = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            let (t1, t2) = perpendicular_frame(n);
            Ok(SurfacePoint {
                position: center + radius * n,
                normal: n,
                t1,
                t2,
                k1: 1.0 / radius,
                k2: 1.0 / radius,
            })
        }
        Shape::Cylinder {
            center,
            axis,
            radius,
            height,
        } => {
            let (a, b) = perpendicular_frame(axis);
            let phi = TAU * u1;
            let radial = phi.cos() * a + phi.sin() * b;
            let along = (u2 - 0.5) * height;
            Ok(SurfacePoint {
                position: center + radius * radial + along * axis,
                normal: radial,
                t1: (-phi.sin() * a + phi.cos() * b).normalize(),
                t2: axis,
                k1: 1.0 / radius,
                k2: 0.0,
            })
        }
        Shape::Quad {
            center,
            normal,
            size,
        } => {
            let (u, v) = quad_axes(normal);
            Ok(SurfacePoint {
                position: center + (u1 - 0.5) * size.x * u + (u2 - 0.5) * size.y * v,
                normal,
                t1: u,
                t2: v,
                k1: 0.0,
                k2: 0.0,
            })
        }
        ref other => Err(SamplingError::UnsupportedShape(other.kind())),
    }
}

fn candidates(
    surface: &Surface,
    n: usize,
    rng: &mut Rng,
) -> Result<Vec<SurfacePoint>, SamplingError> {
    (0..n)
        .map(|_| {
            let (u1, u2) = (rng.next_f32(), rng.next_f32());
            // Analytic shapes draw two numbers per point (the sequences of existing
            // seeds stay as they were); triangles a third.
            let u3 = match surface {
                Surface::Analytic(_) => 0.0,
                Surface::Triangles(_) => rng.next_f32(),
            };
            surface.point(u1, u2, u3)
        })
        .collect()
}

type Cell = (i64, i64, i64);

fn cell_of(p: Vec3, origin: Vec3, h: f32) -> Cell {
    let q = (p - origin) / h;
    (q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64)
}

/// Generates exactly `n` samples on `surface` with `strategy`, deterministically for
/// `seed`.
pub fn generate(
    surface: &Surface,
    strategy: Strategy,
    n: usize,
    seed: u64,
) -> Result<Vec<PointSample>, SamplingError> {
    if n == 0 {
        return Err(SamplingError::NoSamples);
    }
    let total = surface.area()?;
    let mut rng = Rng::new(seed);
    if strategy == Strategy::Random {
        let points = candidates(surface, n, &mut rng)?;
        return Ok(points
            .into_iter()
            .map(|point| PointSample {
                point,
                area: total / n as f32,
                displacement: 0.0,
            })
            .collect());
    }
    let cands = candidates(surface, OVERSAMPLING * n, &mut rng)?;
    let bounds = surface.bounds();
    let diag = bounds.extent().length().max(1e-6);
    let origin = bounds.min - Vec3::splat(1e-4 * diag);
    // Kept candidate indices and the number of candidates each stands for.
    let (kept, counts, h) = match strategy {
        Strategy::Grid | Strategy::Quantized => {
            let h = search(diag, n, |h| grid_keep(&cands, origin, h).0.len());
            let (kept, counts) = grid_keep(&cands, origin, h);
            (kept, counts, h)
        }
        _ => {
            let r = search(diag, n, |r| poisson_keep(&cands, origin, r).len());
            let kept = poisson_keep(&cands, origin, r);
            let counts = nearest_counts(&cands, &kept, origin, r);
            (kept, counts, r)
        }
    };
    // Drop the surplus (seeded), then rescale the areas to sum to the surface area.
    let mut order: Vec<usize> = (0..kept.len()).collect();
    while order.len() > n {
        let i = rng.below(order.len());
        order.remove(i);
    }
    let weight: f64 = order.iter().map(|&i| counts[i] as f64).sum();
    Ok(order
        .into_iter()
        .map(|i| {
            let mut point = cands[kept[i]];
            let mut displacement = 0.0;
            if strategy == Strategy::Quantized {
                let c = cell_of(point.position, origin, h);
                let centre =
                    origin + h * Vec3::new(c.0 as f32 + 0.5, c.1 as f32 + 0.5, c.2 as f32 + 0.5);
                displacement = (centre - point.position).length();
                point.position = centre;
            }
            PointSample {
                point,
                area: (total as f64 * counts[i] as f64 / weight) as f32,
                displacement,
            }
        })
        .collect())
}

/// The largest scale s in (0, diag] with `count(s)` >= n (count falls as s grows),
/// by bisection on log s.
fn search(diag: f32, n: usize, count: impl Fn(f32) -> usize) -> f32 {
    let (mut lo, mut hi) = (diag * 1e-6, diag);
    if count(hi) >= n {
        return hi;
    }
    for _ in 0..40 {
        let mid = (lo * hi).sqrt();
        if count(mid) >= n {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi / lo < 1.0 + 1e-5 {
            break;
        }
    }
    lo
}

/// First candidate per occupied cube of size `h`, and the candidates per cube.
fn grid_keep(cands: &[SurfacePoint], origin: Vec3, h: f32) -> (Vec<usize>, Vec<u32>) {
    let mut cell_index: HashMap<Cell, usize> = HashMap::new();
    let (mut kept, mut counts) = (Vec::new(), Vec::new());
    for (i, c) in cands.iter().enumerate() {
        let k = *cell_index
            .entry(cell_of(c.position, origin, h))
            .or_insert_with(|| {
                kept.push(i);
                counts.push(0);
                kept.len() - 1
            });
        counts[k] += 1;
    }
    (kept, counts)
}

fn neighbours(c: Cell) -> impl Iterator<Item = Cell> {
    (-1..=1).flat_map(move |dx| {
        (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| (c.0 + dx, c.1 + dy, c.2 + dz)))
    })
}

/// Greedy neighbourhood removal: candidates in order, kept unless within `r` of a kept one.
fn poisson_keep(cands: &[SurfacePoint], origin: Vec3, r: f32) -> Vec<usize> {
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    let mut kept = Vec::new();
    let r2 = r * r;
    for (i, c) in cands.iter().enumerate() {
        let cell = cell_of(c.position, origin, r);
        let covered = neighbours(cell).any(|nc| {
            grid.get(&nc).is_some_and(|v| {
                v.iter()
                    .any(|&j| cands[j].position.distance_squared(c.position) < r2)
            })
        });
        if !covered {
            grid.entry(cell).or_default().push(i);
            kept.push(i);
        }
    }
    kept
}

/// Number of candidates nearest to each kept sample (every candidate lies within `r`
/// of a kept one, so the 27 neighbouring cells hold its nearest).
fn nearest_counts(cands: &[SurfacePoint], kept: &[usize], origin: Vec3, r: f32) -> Vec<u32> {
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    for (k, &i) in kept.iter().enumerate() {
        grid.entry(cell_of(cands[i].position, origin, r))
            .or_default()
            .push(k);
    }
    let mut counts = vec![0u32; kept.len()];
    for c in cands {
        let cell = cell_of(c.position, origin, r);
        let nearest = neighbours(cell)
            .filter_map(|nc| grid.get(&nc))
            .flatten()
            .min_by(|&&a, &&b| {
                let da = cands[kept[a]].position.distance_squared(c.position);
                let db = cands[kept[b]].position.distance_squared(c.position);
                da.total_cmp(&db)
            });
        if let Some(&k) = nearest {
            counts[k] += 1;
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring() -> Shape {
        Shape::Cylinder {
            center: Vec3::new(0.0, 0.25, 0.0),
            axis: Vec3::Y,
            radius: 1.0,
            height: 0.5,
        }
    }

    #[test]
    fn every_strategy_gives_the_requested_count_and_is_deterministic() {
        for strategy in Strategy::ALL {
            for n in [1, 7, 100, 1000] {
                let a = generate(&Surface::Analytic(&ring()), strategy, n, 42).expect("samples");
                assert_eq!(a.len(), n, "{strategy:?} n={n}");
                let b = generate(&Surface::Analytic(&ring()), strategy, n, 42).expect("samples");
                assert_eq!(a, b, "{strategy:?} n={n} not deterministic");
                let c = generate(&Surface::Analytic(&ring()), strategy, n, 43).expect("samples");
                assert_ne!(a, c, "{strategy:?} n={n}: the seed changes nothing");
                let total: f32 = a.iter().map(|s| s.area).sum();
                let want = area(&ring()).expect("area");
                assert!(
                    (total - want).abs() < 1e-3 * want,
                    "{strategy:?} n={n}: areas sum to {total}, surface {want}"
                );
            }
        }
    }

    #[test]
    fn samples_lie_on_the_surface_except_quantized_ones() {
        for strategy in Strategy::ALL {
            for s in generate(&Surface::Analytic(&ring()), strategy, 200, 3).expect("samples") {
                let p = s.point.position;
                let off = ((p.x * p.x + p.z * p.z).sqrt() - 1.0).abs();
                let bound = if strategy == Strategy::Quantized {
                    s.displacement + 1e-5
                } else {
                    1e-5
                };
                assert!(off <= bound, "{strategy:?}: {p} is {off} off the ring");
                assert!((s.point.normal.length() - 1.0).abs() < 1e-5);
                assert!(s.point.t1.dot(s.point.normal).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn stratified_samples_are_more_even_than_random_ones() {
        // Smallest distance between two samples: Poisson-disc removal guarantees r.
        let min_dist = |v: &[PointSample]| {
            let mut m = f32::MAX;
            for (i, a) in v.iter().enumerate() {
                for b in &v[i + 1..] {
                    m = m.min(a.point.position.distance(b.point.position));
                }
            }
            m
        };
        let random =
            generate(&Surface::Analytic(&ring()), Strategy::Random, 300, 5).expect("random");
        let poisson = generate(
            &Surface::Analytic(&ring()),
            Strategy::NeighborRemoval,
            300,
            5,
        )
        .expect("poisson");
        let spacing = (area(&ring()).expect("area") / 300.0).sqrt();
        assert!(min_dist(&poisson) > 0.5 * spacing, "{}", min_dist(&poisson));
        assert!(min_dist(&random) < 0.2 * spacing, "{}", min_dist(&random));
    }

    #[test]
    fn curvature_is_analytic() {
        let p = surface_point(&ring(), 0.3, 0.5).expect("point");
        assert_eq!((p.k1, p.k2), (1.0, 0.0));
        // n(p + s t1) = n + s k1 t1 to first order on the cylinder.
        let q = surface_point(&ring(), 0.3 + 1e-3, 0.5).expect("point");
        let s = (q.position - p.position).dot(p.t1);
        let dn = (q.normal - p.normal) / s;
        assert!((dn - p.k1 * p.t1).length() < 1e-2, "{dn}");
        let quad = Shape::Quad {
            center: Vec3::ZERO,
            normal: Vec3::Y,
            size: caustics_scene::Vec2::new(1.0, 2.0),
        };
        assert_eq!(surface_point(&quad, 0.1, 0.9).expect("quad").k1, 0.0);
    }

    #[test]
    fn zero_samples_and_meshes_are_errors() {
        assert_eq!(
            generate(&Surface::Analytic(&ring()), Strategy::Random, 0, 1),
            Err(SamplingError::NoSamples)
        );
    }

    /// A sphere of radius 2 tessellated into 96 × 48 segments, sampled through its
    /// triangles: the areas sum to the triangles' area, every sample lies on a triangle
    /// with a unit normal close to the radial one, and the fitted curvatures are 1/r.
    #[test]
    fn triangle_samples_have_the_meshs_area_normals_and_curvature() {
        let sphere = Shape::Sphere {
            center: Vec3::new(0.0, 1.0, 0.0),
            radius: 2.0,
        };
        let mesh = sphere.triangulate(&caustics_scene::Tessellation::default());
        let surface = Surface::triangles(&mesh).expect("triangles");
        let mesh_area = mesh.area();
        assert!((surface.area().expect("area") - mesh_area).abs() < 1e-4 * mesh_area);
        for strategy in Strategy::ALL {
            let samples = generate(&surface, strategy, 500, 9).expect("samples");
            assert_eq!(samples.len(), 500);
            let total: f32 = samples.iter().map(|s| s.area).sum();
            assert!(
                (total - mesh_area).abs() < 1e-3 * mesh_area,
                "{strategy:?}: {total}"
            );
            for s in &samples {
                let p = s.point;
                let radial = (p.position - Vec3::new(0.0, 1.0, 0.0)) / 2.0;
                let off = (radial.length() - 1.0).abs();
                assert!(off < 2e-3 + s.displacement, "{strategy:?}: {} off", off);
                assert!((p.normal.length() - 1.0).abs() < 1e-5);
                // (Quantized samples sit at their cube's centre, with the chosen point's
                // normal.)
                if strategy != Strategy::Quantized {
                    assert!(p.normal.dot(radial.normalize()) > 0.999, "{strategy:?}");
                }
                assert!(p.t1.dot(p.normal).abs() < 1e-5 && p.t2.dot(p.normal).abs() < 1e-5);
                assert!(
                    (p.k1 - 0.5).abs() < 0.05 && (p.k2 - 0.5).abs() < 0.05,
                    "k {} {}",
                    p.k1,
                    p.k2
                );
            }
        }
        assert_eq!(
            generate(&surface, Strategy::Random, 10, 1),
            generate(&surface, Strategy::Random, 10, 1)
        );
    }

    /// A cylinder's triangles: curvature 1/r around, 0 along the axis, with the
    /// principal directions found.
    #[test]
    fn triangle_curvature_finds_the_principal_directions() {
        let mesh = ring().triangulate(&caustics_scene::Tessellation::default());
        let surface = Surface::triangles(&mesh).expect("triangles");
        for s in generate(&surface, Strategy::Random, 100, 4).expect("samples") {
            let p = s.point;
            let (around, along) = if p.k1.abs() >= p.k2.abs() {
                ((p.k1, p.t1), (p.k2, p.t2))
            } else {
                ((p.k2, p.t2), (p.k1, p.t1))
            };
            assert!((around.0 - 1.0).abs() < 0.02, "k around {}", around.0);
            assert!(along.0.abs() < 0.02, "k along {}", along.0);
            assert!(along.1.dot(Vec3::Y).abs() > 0.999, "{}", along.1);
        }
    }

    #[test]
    fn meshes_without_area_are_refused() {
        let mesh = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X],
            normals: vec![Vec3::Y; 3],
            indices: vec![0, 1, 2],
        };
        assert_eq!(Surface::triangles(&mesh).err(), Some(SamplingError::NoArea));
    }
}
