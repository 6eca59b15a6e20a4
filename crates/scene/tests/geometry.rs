//! Tessellation, shape conventions, camera rays and the spot-light profile.

use std::f32::consts::PI;

use caustics_scene::{
    Aabb, Camera, Heightfield, Light, Shape, Tessellation, TriangleMesh, Vec2, Vec3, quad_axes,
};

fn heightfield() -> Heightfield {
    use caustics_scene::Wave;
    Heightfield {
        center: Vec3::new(0.5, 1.5, -0.25),
        size: Vec2::new(4.0, 3.0),
        resolution: [33, 17],
        waves: vec![
            Wave {
                amplitude: 0.03,
                wavelength: 0.9,
                direction: Vec2::new(1.0, 0.3).normalize(),
                phase: 0.0,
            },
            Wave {
                amplitude: 0.02,
                wavelength: 0.6,
                direction: Vec2::new(-0.4, 1.0).normalize(),
                phase: 1.1,
            },
        ],
    }
}

fn shapes() -> Vec<Shape> {
    vec![
        Shape::Sphere {
            center: Vec3::new(0.0, 1.5, 0.0),
            radius: 1.0,
        },
        Shape::Quad {
            center: Vec3::new(0.0, 1.0, -2.0),
            normal: Vec3::new(0.3, 0.2, 1.0).normalize(),
            size: Vec2::new(2.0, 4.0),
        },
        Shape::Quad {
            center: Vec3::ZERO,
            normal: Vec3::Y,
            size: Vec2::new(20.0, 10.0),
        },
        Shape::Heightfield(heightfield()),
        Shape::Cylinder {
            center: Vec3::new(0.0, 0.25, 0.0),
            axis: Vec3::new(0.2, 1.0, -0.1).normalize(),
            radius: 1.0,
            height: 0.5,
        },
    ]
}

/// Normals unit, indices in range, every triangle CCW seen from its normals' side.
fn check_mesh(name: &str, m: &TriangleMesh) {
    assert_eq!(m.positions.len(), m.normals.len(), "{name}");
    assert!(
        m.indices.len().is_multiple_of(3) && !m.indices.is_empty(),
        "{name}"
    );
    for n in &m.normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "{name}: normal {n} not unit"
        );
    }
    for &i in &m.indices {
        assert!(
            (i as usize) < m.positions.len(),
            "{name}: index {i} out of range"
        );
    }
    for t in 0..m.triangle_count() {
        let [a, b, c] = m.triangle(t);
        let face = (b - a).cross(c - a);
        assert!(face.length() > 0.0, "{name}: degenerate triangle {t}");
        let i = &m.indices[3 * t..3 * t + 3];
        let n = m.normals[i[0] as usize] + m.normals[i[1] as usize] + m.normals[i[2] as usize];
        assert!(
            face.dot(n) > 0.0,
            "{name}: triangle {t} wound against its normals"
        );
    }
}

#[test]
fn triangulations_are_well_formed() {
    let tess = Tessellation::default();
    assert_eq!((tess.sphere_segments, tess.cylinder_segments), (96, 128));
    for shape in shapes() {
        let m = shape.triangulate(&tess);
        check_mesh(shape.kind(), &m);
        // Bounds hold every vertex.
        let b = shape.bounds();
        let grown = Aabb {
            min: b.min - Vec3::splat(1e-5),
            max: b.max + Vec3::splat(1e-5),
        };
        for p in &m.positions {
            assert!(grown.contains(*p), "{}: {p} outside {b:?}", shape.kind());
        }
    }
    // Coarse tessellations too.
    let coarse = Tessellation {
        sphere_segments: 4,
        cylinder_segments: 3,
    };
    for shape in shapes() {
        check_mesh(shape.kind(), &shape.triangulate(&coarse));
    }
}

#[test]
fn sphere_area_within_one_percent() {
    let r = 1.7;
    let m = Shape::Sphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: r,
    }
    .triangulate(&Tessellation::default());
    let exact = 4.0 * PI * r * r;
    assert!(
        (m.area() - exact).abs() / exact < 0.01,
        "{} vs {exact}",
        m.area()
    );
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let analytic = (*p - Vec3::new(1.0, 2.0, 3.0)) / r;
        assert!((analytic - *n).length() < 1e-5);
    }
}

#[test]
fn cylinder_is_open_with_outward_normals() {
    let (center, axis) = (Vec3::new(0.0, 0.25, 0.0), Vec3::Y);
    let m = Shape::Cylinder {
        center,
        axis,
        radius: 1.0,
        height: 0.5,
    }
    .triangulate(&Tessellation::default());
    assert_eq!(m.triangle_count(), 2 * 128);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let radial = (*p - center) - (*p - center).dot(axis) * axis;
        assert!((radial.length() - 1.0).abs() < 1e-5);
        assert!((radial - *n).length() < 1e-5);
        assert!(((*p - center).dot(axis).abs() - 0.25).abs() < 1e-5);
    }
    let exact = 2.0 * PI * 1.0 * 0.5;
    assert!((m.area() - exact).abs() / exact < 0.01);
}

#[test]
fn heightfield_normal_matches_finite_differences() {
    let h = heightfield();
    let eps = 1e-3;
    for &(x, z) in &[(0.1f32, 0.2f32), (-1.3, 0.7), (2.0, -1.5), (0.77, 1.1)] {
        let dx = (h.height(x + eps, z) - h.height(x - eps, z)) / (2.0 * eps);
        let dz = (h.height(x, z + eps) - h.height(x, z - eps)) / (2.0 * eps);
        let fd = Vec3::new(-dx, 1.0, -dz).normalize();
        let n = h.normal(x, z);
        assert!((n - fd).length() < 2e-3, "{n} vs {fd}");
        assert!(n.y > 0.0 && (n.length() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn heightfield_grid_spans_size_around_center() {
    let h = heightfield();
    let first = h.vertex(0, 0);
    let last = h.vertex(32, 16);
    assert!((first.x - (0.5 - 2.0)).abs() < 1e-6 && (first.z - (-0.25 - 1.5)).abs() < 1e-6);
    assert!((last.x - (0.5 + 2.0)).abs() < 1e-6 && (last.z - (-0.25 + 1.5)).abs() < 1e-6);
    assert!((first.y - h.height(first.x, first.z)).abs() < 1e-7);
    let m = Shape::Heightfield(h.clone()).triangulate(&Tessellation::default());
    assert_eq!(m.positions.len(), 33 * 17);
    assert_eq!(m.triangle_count(), 2 * 32 * 16);
    // Normals are the analytic ones, not facet normals.
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!((h.normal(p.x, p.z) - *n).length() < 1e-6);
    }
    // y = center.y + Σ a·sin(2π/λ (d̂·(x, z)) + phase)
    let w = &h.waves;
    let (x, z) = (0.3f32, -0.6f32);
    let expected = 1.5
        + w.iter()
            .map(|w| {
                w.amplitude
                    * (2.0 * PI / w.wavelength * (w.direction.x * x + w.direction.y * z) + w.phase)
                        .sin()
            })
            .sum::<f32>();
    assert!((h.height(x, z) - expected).abs() < 1e-6);
}

#[test]
fn quad_axes_rule() {
    let (u, v) = quad_axes(Vec3::Y);
    assert!((u - Vec3::X).length() < 1e-6);
    assert!((v.abs() - Vec3::Z).length() < 1e-6);
    for n in [
        Vec3::X,
        -Vec3::X,
        Vec3::Z,
        -Vec3::Z,
        -Vec3::Y,
        Vec3::new(0.3, -0.5, 0.8).normalize(),
    ] {
        let (u, v) = quad_axes(n);
        assert!((u.length() - 1.0).abs() < 1e-6 && (v.length() - 1.0).abs() < 1e-6);
        assert!(u.dot(n).abs() < 1e-6 && v.dot(n).abs() < 1e-6 && u.dot(v).abs() < 1e-6);
        assert!((u.cross(v) - n).length() < 1e-5, "not right-handed for {n}");
    }
    // A floor quad of size (20, 10): 20 along x, 10 along z.
    let b = Shape::Quad {
        center: Vec3::ZERO,
        normal: Vec3::Y,
        size: Vec2::new(20.0, 10.0),
    }
    .bounds();
    assert!((b.extent() - Vec3::new(20.0, 0.0, 10.0)).length() < 1e-5);
}

#[test]
fn aabb_helpers() {
    let a = Aabb::from_points([Vec3::ZERO, Vec3::new(2.0, 4.0, 4.0)]);
    assert_eq!(a.center(), Vec3::new(1.0, 2.0, 2.0));
    assert_eq!(a.extent(), Vec3::new(2.0, 4.0, 4.0));
    assert!((a.bounding_sphere_radius() - 3.0).abs() < 1e-6);
    let b = a.union(&Aabb::from_points([Vec3::splat(-1.0)]));
    assert_eq!(b.min, Vec3::splat(-1.0));
    assert!(Aabb::EMPTY.is_empty() && !a.is_empty());
    assert_eq!(Aabb::EMPTY.union(&a), a);
}

fn camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 4.5, 6.5),
        target: Vec3::new(0.2, 0.6, 0.0),
        up: Vec3::Y,
        fov_y_deg: 40.0,
        width: 1024,
        height: 768,
        exposure: None,
    }
}

#[test]
fn camera_frame_and_rays() {
    let c = camera();
    let (f, r, u) = (c.forward(), c.right(), c.image_up());
    assert!((f.cross(r).length() - 1.0).abs() < 1e-5);
    assert!(f.dot(r).abs() < 1e-6 && f.dot(u).abs() < 1e-6 && r.dot(u).abs() < 1e-6);
    assert!(u.y > 0.0, "image up points up");
    let (o, d) = c.ray_through_pixel(512.0, 384.0);
    assert_eq!(o, c.eye);
    assert!((d - f).length() < 1e-6);
    // Top edge centre is fov/2 above the axis; row 0 is the top.
    let (_, top) = c.ray_through_pixel(512.0, 0.0);
    assert!((top.dot(f).acos().to_degrees() - 20.0).abs() < 1e-3);
    assert!(top.dot(u) > 0.0);
    let (_, left) = c.ray_through_pixel(0.0, 384.0);
    assert!(left.dot(r) < 0.0);
    // Rays agree with the projection: a point along the ray through pixel (px, py)
    // projects back to those pixel coordinates.
    let vp = c.view_projection(0.1, 100.0);
    for &(px, py) in &[(10.5f32, 20.5f32), (1000.0, 700.0), (512.0, 100.0)] {
        let (o, d) = c.ray_through_pixel(px, py);
        let clip = vp * (o + 5.0 * d).extend(1.0);
        let ndc = Vec3::new(clip.x, clip.y, clip.z) / clip.w;
        assert!((0.0..=1.0).contains(&ndc.z));
        let back_x = (ndc.x + 1.0) * 0.5 * 1024.0;
        let back_y = (1.0 - ndc.y) * 0.5 * 768.0;
        assert!(
            (back_x - px).abs() < 1e-2 && (back_y - py).abs() < 1e-2,
            "{back_x} {back_y}"
        );
    }
}

#[test]
fn spot_factor_profile() {
    let cos = |deg: f32| deg.to_radians().cos();
    assert_eq!(Light::spot_factor(30.0, None, cos(0.0)), 1.0);
    assert_eq!(Light::spot_factor(30.0, None, cos(29.9)), 1.0);
    assert_eq!(Light::spot_factor(30.0, None, cos(30.1)), 0.0);
    assert_eq!(Light::spot_factor(30.0, Some(0.0), cos(29.9)), 1.0);
    assert_eq!(Light::spot_factor(30.0, Some(10.0), cos(19.0)), 1.0);
    assert_eq!(Light::spot_factor(30.0, Some(10.0), cos(31.0)), 0.0);
    assert!((Light::spot_factor(30.0, Some(10.0), cos(25.0)) - 0.5).abs() < 1e-3);
    // smoothstep at t = 0.25 (θ = 27.5°): 0.25²·(3 − 0.5) = 0.15625
    assert!((Light::spot_factor(30.0, Some(10.0), cos(27.5)) - 0.15625).abs() < 1e-3);
    // Out-of-range cosines are clamped, not NaN.
    assert_eq!(Light::spot_factor(30.0, None, 1.0000001), 1.0);
    assert_eq!(Light::spot_factor(90.0, None, -1.5), 0.0);
}
