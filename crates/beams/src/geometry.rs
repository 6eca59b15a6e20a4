//! Beam space on the CPU (Ernst et al. 2005, as used in Sect. 4.3): the same
//! construction as `beam_geometry` in types.wgsl, for tests and for reading beams back.

use caustics_scene::Vec3;

/// A beam's frame: base vertices, base normal (the y axis), edge directions scaled to
/// unit height, and the area function A(y) = a0 + a1·y + a2·y².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamSpace {
    /// Base vertices v_i.
    pub v: [Vec3; 3],
    /// Unit base normal, oriented along the rays.
    pub n: Vec3,
    /// d_i / (d_i · n).
    pub d: [Vec3; 3],
    /// (a0, a1, a2).
    pub a: [f32; 3],
}

impl BeamSpace {
    /// None when the base is degenerate or a ray runs within ~1° of the base plane or
    /// against it (no parallel cross-sections).
    pub fn new(v: [Vec3; 3], dirs: [Vec3; 3]) -> Option<Self> {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = c.length();
        if len < 1e-12 {
            return None;
        }
        let mut n = c / len;
        if (dirs[0] + dirs[1] + dirs[2]).dot(n) < 0.0 {
            n = -n;
        }
        let h = dirs.map(|d| d.dot(n));
        if h.iter().any(|&x| x < 0.02) {
            return None;
        }
        let d = [dirs[0] / h[0], dirs[1] / h[1], dirs[2] / h[2]];
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let (f1, f2) = (d[1] - d[0], d[2] - d[0]);
        let a = [
            0.5 * e1.cross(e2).dot(n),
            0.5 * (e1.cross(f2) + f1.cross(e2)).dot(n),
            0.5 * f1.cross(f2).dot(n),
        ];
        Some(Self { v, n, d, a })
    }

    /// A(y) from the coefficients (signed: negative past a focus).
    pub fn area(&self, y: f32) -> f32 {
        self.a[0] + y * (self.a[1] + y * self.a[2])
    }

    /// The cross-section at height y, built from the geometry itself.
    pub fn cross_section(&self, y: f32) -> [Vec3; 3] {
        std::array::from_fn(|i| self.v[i] + self.d[i] * y)
    }

    /// Signed area of the cross-section triangle at height y, measured directly.
    pub fn measured_area(&self, y: f32) -> f32 {
        let [q0, q1, q2] = self.cross_section(y);
        0.5 * (q1 - q0).cross(q2 - q0).dot(self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A(y) from its three coefficients equals the area of the triangle cut from the
    /// beam at height y, for a diverging, a converging (through its focus) and a
    /// twisted beam.
    #[test]
    fn area_function_matches_the_geometric_cross_section() {
        let v = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.1),
            Vec3::new(0.2, 0.0, 0.9),
        ];
        let centroid = (v[0] + v[1] + v[2]) / 3.0;
        let focus = centroid + Vec3::new(0.1, -2.0, 0.0);
        let cases: [[Vec3; 3]; 3] = [
            // Diverging: away from a point above the base.
            v.map(|p| (p - (centroid + Vec3::Y)).normalize()),
            // Converging through a focus 2 m below.
            v.map(|p| (focus - p).normalize()),
            // Twisted: each edge leans a different way.
            [
                Vec3::new(0.3, -1.0, 0.0).normalize(),
                Vec3::new(-0.2, -1.0, 0.4).normalize(),
                Vec3::new(0.1, -1.0, -0.5).normalize(),
            ],
        ];
        for dirs in cases {
            let b = BeamSpace::new(v, dirs).expect("valid beam");
            for k in 0..=40 {
                let y = k as f32 * 0.1;
                let (f, m) = (b.area(y), b.measured_area(y));
                assert!(
                    (f - m).abs() <= 1e-5 * (1.0 + m.abs()),
                    "A({y}) = {f} but the cross-section has area {m}"
                );
            }
        }
        // The converging beam shrinks to a point at the focus height and is the same
        // size again (turned by 180°) as far beyond it.
        let b = BeamSpace::new(v, cases[1]).expect("valid");
        let y_focus = (focus - b.v[0]).dot(b.n);
        assert!(
            b.area(y_focus).abs() < 1e-4 * b.a[0],
            "A(focus) = {}",
            b.area(y_focus)
        );
        assert!((b.area(2.0 * y_focus) - b.a[0]).abs() < 1e-3 * b.a[0]);
    }

    #[test]
    fn grazing_and_degenerate_beams_are_refused() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Z];
        assert!(BeamSpace::new(v, [Vec3::X; 3]).is_none());
        assert!(BeamSpace::new([Vec3::ZERO, Vec3::X, 2.0 * Vec3::X], [Vec3::Y; 3]).is_none());
    }
}
