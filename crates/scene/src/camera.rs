//! The pinhole camera and its conventions.

use glam::{Mat4, Vec3};

/// A pinhole camera (DESIGN.md, "Camera").
///
/// forward = normalize(target − eye), right = normalize(forward × up),
/// image up = right × forward; `fov_y_deg` is the full vertical angle; pixel row 0
/// is the top of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole, in metres.
    pub eye: Vec3,
    /// A point the camera looks at (≠ `eye`).
    pub target: Vec3,
    /// Approximate up direction (not parallel to the view direction); not necessarily unit.
    pub up: Vec3,
    /// Full vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Exposure scale of the tone-mapped images (linear × exposure, clamped, sRGB), when
    /// the scene file states one; otherwise the harness takes it from the reference.
    pub exposure: Option<f32>,
}

impl Camera {
    /// Unit view direction: normalize(target − eye).
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize()
    }

    /// Unit right vector of the image: normalize(forward × up).
    pub fn right(&self) -> Vec3 {
        self.forward().cross(self.up).normalize()
    }

    /// Unit up vector of the image: right × forward.
    pub fn image_up(&self) -> Vec3 {
        self.right().cross(self.forward())
    }

    /// Width / height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Vertical field of view in radians.
    pub fn fov_y_rad(&self) -> f32 {
        self.fov_y_deg.to_radians()
    }

    /// Right-handed world-to-view matrix (`Mat4::look_at_rh`): the camera looks down −z.
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye, self.target, self.up)
    }

    /// Right-handed perspective projection with depth in 0..1 (wgpu's clip space),
    /// `Mat4::perspective_rh`.
    pub fn projection(&self, near: f32, far: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_rad(), self.aspect(), near, far)
    }

    /// `projection(near, far) * view()`.
    pub fn view_projection(&self, near: f32, far: f32) -> Mat4 {
        self.projection(near, far) * self.view()
    }

    /// The primary ray through the continuous pixel position (`px`, `py`): (0, 0) is the
    /// top-left corner of the image, (width, height) the bottom-right, so the centre of
    /// pixel (i, j) is (i + 0.5, j + 0.5). Returns (origin = eye, unit direction).
    pub fn ray_through_pixel(&self, px: f32, py: f32) -> (Vec3, Vec3) {
        let ndc_x = 2.0 * px / self.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * py / self.height as f32;
        let tan_half = (0.5 * self.fov_y_rad()).tan();
        let dir = self.forward()
            + ndc_x * tan_half * self.aspect() * self.right()
            + ndc_y * tan_half * self.image_up();
        (self.eye, dir.normalize())
    }
}
