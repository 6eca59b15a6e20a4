//! Shared helpers for the integration tests.
#![allow(dead_code, unreachable_pub)]

use caustics_metrics::HdrImage;

/// A deterministic image with smooth structure plus a bright spot (a toy caustic).
pub fn structured(width: u32, height: u32) -> HdrImage {
    let mut img = HdrImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let (fx, fy) = (x as f32 / width as f32, y as f32 / height as f32);
            let d2 = (fx - 0.5).powi(2) + (fy - 0.5).powi(2);
            let spot = 2.0 * (-d2 * 40.0).exp();
            img.set(
                x,
                y,
                [0.2 * fx + spot, 0.1 + 0.3 * fy + spot, 0.15 + spot * 0.5],
            );
        }
    }
    img
}

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// `img` with multiplicative noise of relative amplitude `amp`.
pub fn noisy(img: &HdrImage, amp: f32, seed: u64) -> HdrImage {
    let mut rng = Lcg(seed);
    let mut out = img.clone();
    for p in &mut out.pixels {
        for c in p.iter_mut() {
            *c *= 1.0 + amp * rng.next_f32();
        }
    }
    out
}
