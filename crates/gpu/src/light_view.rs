//! The one place where a light's view is fitted (STYLE: shared things live once): to
//! bounds (shadow maps, [`LightView::fit`]), to points (the beam generators'
//! vertices, [`LightView::fit_points`]) or to a sphere around a caustic generator while
//! keeping the occluders between it and the light ([`LightView::fit_sphere`], the
//! photon-hit image), and the one cube-face convention ([`CUBE_FACES`]) of point-light
//! cube views and distance impostors alike.

use caustics_scene::{Aabb, Light, Mat4, Vec3, Vec4};

/// Right, up and forward axes of the six cube faces, in the order +X, −X, +Y, −Y, +Z,
/// −Z, chosen so that the projection puts a direction where the GPU's cube-map
/// convention (and `impostor_face_uv` in impostor_trace.wgsl) looks for it: Vulkan's
/// u = (sc/|ma| + 1)/2, v = (tc/|ma| + 1)/2 with row 0 at the top, so up = −t axis.
pub const CUBE_FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    (Vec3::Z, Vec3::Y, Vec3::NEG_X),
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::X, Vec3::Z, Vec3::NEG_Y),
    (Vec3::X, Vec3::Y, Vec3::Z),
    (Vec3::NEG_X, Vec3::Y, Vec3::NEG_Z),
];

/// World-to-view matrix of cube face `face` (0..6) around `center`: a camera at
/// `center` looking down its −z at the face's forward axis.
pub fn cube_face_view(face: usize, center: Vec3) -> Mat4 {
    let (right, up, forward) = CUBE_FACES[face % 6];
    let rotation = Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        (-forward).extend(0.0),
        Vec4::W,
    )
    .transpose();
    rotation * Mat4::from_translation(-center)
}

/// World-to-clip matrix of cube face `face` around `center` (90° square frustum).
pub fn cube_face_view_proj(face: usize, center: Vec3, near: f32, far: f32) -> Mat4 {
    Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far) * cube_face_view(face, center)
}

/// How a light G-buffer projects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightProjection {
    /// Directional light: one orthographic face.
    Orthographic,
    /// Spot light: one perspective face covering the cone.
    Perspective,
    /// Point light: six 90° perspective faces, order +X, −X, +Y, −Y, +Z, −Z.
    Cube,
}

/// One face of a light's view.
#[derive(Clone, Copy, Debug)]
pub struct LightFace {
    /// World to view.
    pub view: Mat4,
    /// View to clip (depth 0..1).
    pub proj: Mat4,
    /// World to clip.
    pub view_proj: Mat4,
}

/// A light's view: faces, resolution and texel footprint.
#[derive(Clone, Debug)]
pub struct LightView {
    /// Projection kind.
    pub projection: LightProjection,
    /// 1 or 6 faces.
    pub faces: Vec<LightFace>,
    /// Square resolution of each face (texels).
    pub resolution: u32,
    /// World size of a texel: in metres for orthographic views, per metre of distance
    /// from the light for perspective ones.
    pub texel_size: f32,
    /// Light position (point/spot) or the centre of the fitted volume (directional).
    pub origin: Vec3,
    /// Tangent of half the field of view of a face: 0 for an orthographic view, 1 for
    /// the 90° cube faces, tan(fov/2) for a perspective face.
    pub tan_half_fov: f32,
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() < 0.99 { Vec3::Y } else { Vec3::Z }
}

impl LightView {
    /// Fits the light's view around `bounds` (e.g. the whole scene for shadows, or
    /// only the specular objects for photon generation).
    pub fn fit(light: &Light, bounds: &Aabb, resolution: u32) -> Self {
        let center = bounds.center();
        let radius = bounds.bounding_sphere_radius().max(1e-3);
        let far_from = |p: Vec3| {
            let far = bounds
                .corners()
                .iter()
                .map(|c| (*c - p).length())
                .fold(0.0, f32::max);
            far * 1.01 + 1e-3
        };
        match *light {
            Light::Directional { direction, .. } => {
                let eye = center - direction * (2.0 * radius);
                let view = Mat4::look_at_rh(eye, center, any_up(direction));
                let proj =
                    Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.0, 4.0 * radius);
                Self {
                    projection: LightProjection::Orthographic,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * radius / resolution as f32,
                    origin: center,
                    tan_half_fov: 0.0,
                }
            }
            Light::Spot {
                position,
                direction,
                cone_deg,
                ..
            } => {
                let fov = (2.0 * cone_deg).clamp(1.0, 170.0).to_radians();
                let far = far_from(position);
                let near = (far * 1e-4).max(1e-4);
                let view = Mat4::look_at_rh(position, position + direction, any_up(direction));
                let proj = Mat4::perspective_rh(fov, 1.0, near, far);
                Self {
                    projection: LightProjection::Perspective,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * (fov * 0.5).tan() / resolution as f32,
                    origin: position,
                    tan_half_fov: (fov * 0.5).tan(),
                }
            }
            // GpuScene::upload refuses extended lights; their arms keep the match
            // total: a sphere light seen from its centre, an environment from above.
            Light::Environment { .. } => Self::fit(
                &Light::Directional {
                    direction: Vec3::NEG_Y,
                    irradiance: Vec3::ZERO,
                },
                bounds,
                resolution,
            ),
            Light::Point { position, .. } | Light::Sphere { position, .. } => {
                let far = far_from(position);
                let near = (far * 1e-4).max(1e-4);
                let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
                let faces = (0..6)
                    .map(|face| {
                        let view = cube_face_view(face, position);
                        LightFace {
                            view,
                            proj,
                            view_proj: proj * view,
                        }
                    })
                    .collect();
                Self {
                    projection: LightProjection::Cube,
                    faces,
                    resolution,
                    texel_size: 2.0 / resolution as f32,
                    origin: position,
                    tan_half_fov: 1.0,
                }
            }
        }
    }
}

impl LightView {
    /// The light's view of a sphere (`center`, `radius`, e.g. a caustic generator's
    /// bounding sphere), `resolution` texels per side: every texel looks at the sphere
    /// where possible, so the resolution is spent on it (Umenhoffer et al. render the
    /// generator from the light). The view reaches back from the sphere to the far side
    /// of `scene_bounds`, so objects between the light and the sphere are drawn (they
    /// shadow it). A positional light inside or too close to the sphere (half angle over
    /// 80°) gets the whole cube ([`LightView::fit`]).
    pub fn fit_sphere(
        light: &Light,
        center: Vec3,
        radius: f32,
        scene_bounds: &Aabb,
        resolution: u32,
    ) -> Self {
        let r = radius * 1.02;
        let back =
            (scene_bounds.center() - center).length() + scene_bounds.bounding_sphere_radius();
        let single = |projection, view: Mat4, proj: Mat4, tan_half_fov: f32, origin| Self {
            projection,
            faces: vec![LightFace {
                view,
                proj,
                view_proj: proj * view,
            }],
            resolution,
            texel_size: if projection == LightProjection::Orthographic {
                2.0 * r / resolution as f32
            } else {
                2.0 * tan_half_fov / resolution as f32
            },
            origin,
            tan_half_fov,
        };
        match *light {
            Light::Directional { direction, .. } => {
                let eye = center - direction * (back + r);
                let view = Mat4::look_at_rh(eye, center, any_up(direction));
                let proj = Mat4::orthographic_rh(-r, r, -r, r, 0.0, back + 2.0 * r);
                single(LightProjection::Orthographic, view, proj, 0.0, center)
            }
            Light::Environment { .. } => Self::fit(light, scene_bounds, resolution),
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Sphere { position, .. } => {
                let to = center - position;
                let dist = to.length();
                if dist > r * 1.01 && (r / dist).asin() < 80f32.to_radians() {
                    let half = (r / dist).asin();
                    let far = dist + r;
                    let near = (far * 1e-4).max(1e-4);
                    let view = Mat4::look_at_rh(position, center, any_up(to / dist));
                    let proj = Mat4::perspective_rh(2.0 * half, 1.0, near, far);
                    single(
                        LightProjection::Perspective,
                        view,
                        proj,
                        half.tan(),
                        position,
                    )
                } else {
                    Self::fit(light, scene_bounds, resolution)
                }
            }
        }
    }

    /// One face of the light that just covers `points` (e.g. the vertices of the
    /// caustic generators): an orthographic square around their projection for a
    /// directional light, a perspective square cone towards them for a point or spot
    /// light (a point light is treated as a spot aimed at them, so the specular objects
    /// get the whole resolution instead of a sixth of a cube). None when `points` is
    /// empty or a positional light sits among them (no cone can hold them).
    pub fn fit_points(light: &Light, points: &[Vec3], resolution: u32) -> Option<Self> {
        points.first()?;
        match *light {
            Light::Directional { direction, .. } => {
                let dir = direction.normalize();
                let up = any_up(dir);
                let right = dir.cross(up).normalize();
                let up = right.cross(dir);
                let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
                for p in points {
                    let q = Vec3::new(p.dot(right), p.dot(up), p.dot(dir));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                // No margin: grid corners on the border of the view land on the generators' edges.
                let half = 0.5 * (hi.x - lo.x).max(hi.y - lo.y) * (1.0 + 1e-5) + 1e-6;
                let mid = 0.5 * (lo + hi);
                let depth = (hi.z - lo.z).max(1e-3);
                // The eye sits one depth before the nearest point, on the centre line.
                let eye = right * mid.x + up * mid.y + dir * (lo.z - depth);
                let view = Mat4::look_at_rh(eye, eye + dir, up);
                let proj = Mat4::orthographic_rh(-half, half, -half, half, 0.0, 3.0 * depth);
                Some(Self {
                    projection: LightProjection::Orthographic,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * half / resolution as f32,
                    origin: eye + dir * depth,
                    tan_half_fov: 0.0,
                })
            }
            Light::Environment { .. } => None,
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Sphere { position, .. } => {
                let centroid = points.iter().fold(Vec3::ZERO, |a, p| a + *p) / points.len() as f32;
                let axis = (centroid - position).try_normalize()?;
                let up = any_up(axis);
                let right = axis.cross(up).normalize();
                let up = right.cross(axis);
                let (mut tan_max, mut near, mut far) = (0.0f32, f32::MAX, 0.0f32);
                for p in points {
                    let v = *p - position;
                    let z = v.dot(axis);
                    if z <= 1e-4 * v.length().max(1e-6) {
                        return None;
                    }
                    tan_max = tan_max.max(v.dot(right).abs() / z).max(v.dot(up).abs() / z);
                    near = near.min(z);
                    far = far.max(v.length());
                }
                let fov = 2.0 * (tan_max * (1.0 + 1e-5) + 1e-6).atan();
                if fov >= std::f32::consts::PI * 0.95 {
                    return None;
                }
                let view = Mat4::look_at_rh(position, position + axis, up);
                let proj = Mat4::perspective_rh(fov, 1.0, (near * 0.5).max(1e-4), far * 1.01);
                Some(Self {
                    projection: LightProjection::Perspective,
                    faces: vec![LightFace {
                        view,
                        proj,
                        view_proj: proj * view,
                    }],
                    resolution,
                    texel_size: 2.0 * (fov * 0.5).tan() / resolution as f32,
                    origin: position,
                    tan_half_fov: (fov * 0.5).tan(),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_look_along_their_axes_with_the_gpu_convention() {
        let center = Vec3::new(1.0, 2.0, 3.0);
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (face, axis) in axes.iter().enumerate() {
            let clip = cube_face_view_proj(face, center, 0.01, 10.0) * (center + *axis).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!(
                ndc.x.abs() < 1e-5 && ndc.y.abs() < 1e-5,
                "face {face}: {ndc}"
            );
            assert!(clip.w > 0.0, "face {face} looks away from its axis");
            // Up on the face is the cube map's −t axis: +Y for the side faces.
            let (_, up, _) = CUBE_FACES[face];
            let clip = cube_face_view_proj(face, center, 0.01, 10.0)
                * (center + *axis + 0.1 * up).extend(1.0);
            assert!(clip.y / clip.w > 0.0, "face {face}: up is not up");
        }
    }

    #[test]
    fn a_point_light_cube_uses_the_cube_convention() {
        let light = Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        };
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let v = LightView::fit(&light, &bounds, 64);
        assert_eq!(v.projection, LightProjection::Cube);
        assert_eq!(v.tan_half_fov, 1.0);
        for (face, f) in v.faces.iter().enumerate() {
            assert!(
                f.view.abs_diff_eq(cube_face_view(face, Vec3::ZERO), 1e-6),
                "face {face}"
            );
        }
    }

    #[test]
    fn sphere_view_of_a_directional_light_is_centred_and_reaches_back() {
        let light = Light::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::ONE,
        };
        let bounds = Aabb {
            min: Vec3::splat(-10.0),
            max: Vec3::splat(10.0),
        };
        let v = LightView::fit_sphere(&light, Vec3::Y, 1.0, &bounds, 100);
        assert_eq!(v.projection, LightProjection::Orthographic);
        assert_eq!(v.tan_half_fov, 0.0);
        assert!((v.texel_size - 2.04 / 100.0).abs() < 1e-6);
        let c = v.faces[0].view_proj.project_point3(Vec3::Y);
        assert!(c.x.abs() < 1e-5 && c.y.abs() < 1e-5 && (0.0..=1.0).contains(&c.z));
        // An occluder above the sphere, within the scene, is inside the view's depth.
        let above = v.faces[0]
            .view_proj
            .project_point3(Vec3::new(0.0, 9.0, 0.0));
        assert!((0.0..=1.0).contains(&above.z), "{above}");
    }

    #[test]
    fn sphere_view_of_a_point_light_is_a_cone_or_the_cube_from_inside() {
        let bounds = Aabb {
            min: Vec3::splat(-3.0),
            max: Vec3::splat(3.0),
        };
        let inside = Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        };
        let v = LightView::fit_sphere(&inside, Vec3::ZERO, 1.0, &bounds, 8);
        assert_eq!((v.projection, v.faces.len()), (LightProjection::Cube, 6));
        let outside = Light::Point {
            position: Vec3::new(0.0, 2.5, 0.0),
            intensity: Vec3::ONE,
        };
        let v = LightView::fit_sphere(&outside, Vec3::ZERO, 1.0, &bounds, 8);
        assert_eq!(v.projection, LightProjection::Perspective);
        let half = (1.02f32 / 2.5).asin();
        assert!((v.tan_half_fov - half.tan()).abs() < 1e-5);
    }
}
