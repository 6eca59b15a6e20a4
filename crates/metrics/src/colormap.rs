//! Compact perceptual colour maps: inferno (sequential) for heatmaps and unsigned error
//! maps, Moreland's cool-warm (diverging) for signed error maps.

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
    lerp_table(&INFERNO, t)
}

/// Moreland's "smooth cool warm" diverging map, the 33-entry 8-bit table of K. Moreland,
/// "Diverging Color Maps for Scientific Visualization" (ISVC 2009), file
/// `CoolWarmUChar33.csv` (positions 0, 1/32, …, 1). Blue (59, 76, 192) → neutral grey
/// (221, 221, 221) at ½ → red (180, 4, 38); the lightness of both halves falls off
/// symmetrically from the middle, so equal |error| reads as equal strength on either side.
const COOL_WARM: [[u8; 3]; 33] = [
    [59, 76, 192],
    [68, 90, 204],
    [77, 104, 215],
    [87, 117, 225],
    [98, 130, 234],
    [108, 142, 241],
    [119, 154, 247],
    [130, 165, 251],
    [141, 176, 254],
    [152, 185, 255],
    [163, 194, 255],
    [174, 201, 253],
    [184, 208, 249],
    [194, 213, 244],
    [204, 217, 238],
    [213, 219, 230],
    [221, 221, 221],
    [229, 216, 209],
    [236, 211, 197],
    [241, 204, 185],
    [245, 196, 173],
    [247, 187, 160],
    [247, 177, 148],
    [247, 166, 135],
    [244, 154, 123],
    [241, 141, 111],
    [236, 127, 99],
    [229, 112, 88],
    [222, 96, 77],
    [213, 80, 66],
    [203, 62, 56],
    [192, 40, 47],
    [180, 4, 38],
];

/// Linear interpolation in an 8-bit colour table at `t` in `[0, 1]` (clamped; NaN is 0).
fn lerp_table(table: &[[u8; 3]], t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let pos = t * (table.len() - 1) as f32;
    let i = (pos.floor() as usize).min(table.len() - 2);
    let f = pos - i as f32;
    let (a, b) = (table[i], table[i + 1]);
    [0, 1, 2].map(|c| (f32::from(a[c]) + f * (f32::from(b[c]) - f32::from(a[c]))).round() as u8)
}

/// Moreland's cool-warm diverging colour at `t` in `[0, 1]` (clamped; NaN maps to 0):
/// blue at 0 (negative), neutral grey [`COOL_WARM_NEUTRAL`] at ½ (zero), red at 1
/// (positive).
pub fn cool_warm(t: f32) -> [u8; 3] {
    lerp_table(&COOL_WARM, t)
}

/// The colour of [`cool_warm`] at ½: what a zero error looks like in a signed map.
pub const COOL_WARM_NEUTRAL: [u8; 3] = [221, 221, 221];

#[cfg(test)]
mod tests {
    use super::{COOL_WARM_NEUTRAL, cool_warm, inferno};

    #[test]
    fn cool_warm_is_blue_grey_red() {
        assert_eq!(cool_warm(0.0), [59, 76, 192]);
        assert_eq!(cool_warm(0.5), COOL_WARM_NEUTRAL);
        assert_eq!(cool_warm(1.0), [180, 4, 38]);
        assert_eq!(cool_warm(f32::NAN), cool_warm(0.0));
        // Blue below the middle, red above it.
        for d in [0.1f32, 0.25, 0.5] {
            let (lo, hi) = (cool_warm(0.5 - d), cool_warm(0.5 + d));
            assert!(lo[2] > lo[0] && hi[0] > hi[2], "{d}: {lo:?} {hi:?}");
        }
    }

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
