//! A compact perceptual colour map (inferno) for error maps and heatmaps.

/// Inferno, sampled at every 15th of its 256 entries (indices 0, 15, …, 255) and rounded
/// to 8 bits. Source: matplotlib's `_cm_listed.py` (`_inferno_data`), by Nathaniel J. Smith
/// and Stéfan van der Walt, CC0. Linear interpolation between these 18 points stays within
/// a few code values of the full table.
const INFERNO: [[u8; 3]; 18] = [
    [0, 0, 4],
    [10, 7, 34],
    [30, 12, 69],
    [56, 9, 98],
    [81, 14, 108],
    [105, 22, 110],
    [128, 31, 108],
    [152, 39, 102],
    [176, 49, 91],
    [198, 61, 77],
    [217, 77, 61],
    [233, 97, 43],
    [244, 121, 24],
    [250, 148, 7],
    [252, 176, 20],
    [248, 205, 55],
    [242, 234, 105],
    [252, 255, 164],
];

/// The inferno colour at `t` in `[0, 1]` (clamped; NaN maps to 0): dark purple-black at 0,
/// red at ½, pale yellow at 1. Perceptually uniform and readable in greyscale.
pub fn inferno(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let pos = t * (INFERNO.len() - 1) as f32;
    let i = (pos.floor() as usize).min(INFERNO.len() - 2);
    let f = pos - i as f32;
    let (a, b) = (INFERNO[i], INFERNO[i + 1]);
    [0, 1, 2].map(|c| (f32::from(a[c]) + f * (f32::from(b[c]) - f32::from(a[c]))).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::inferno;

    #[test]
    fn endpoints_and_midpoint_match_matplotlib() {
        assert_eq!(inferno(0.0), [0, 0, 4]);
        assert_eq!(inferno(1.0), [252, 255, 164]);
        // matplotlib inferno(0.5) = (0.735683, 0.215906, 0.330245) → (188, 55, 84).
        let mid = inferno(0.5);
        for (got, want) in mid.iter().zip([188u8, 55, 84]) {
            assert!(got.abs_diff(want) <= 2, "{mid:?}");
        }
        assert_eq!(inferno(-1.0), inferno(0.0));
        assert_eq!(inferno(2.0), inferno(1.0));
        assert_eq!(inferno(f32::NAN), inferno(0.0));
    }
}
