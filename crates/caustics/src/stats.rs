//! Robust summaries of per-frame samples.

use serde::{Deserialize, Serialize};

/// Median and 10th/90th percentiles over measured frames, and the samples themselves.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct Summary {
    /// Median.
    pub median: f64,
    /// 10th percentile.
    pub p10: f64,
    /// 90th percentile.
    pub p90: f64,
    /// Smallest sample.
    pub min: f64,
    /// Largest sample.
    pub max: f64,
    /// Number of samples summarized.
    pub samples: usize,
    /// The per-frame samples in measured order, for noise-aware comparisons
    /// (`caustics compare`). Added after schema 1 was first written: absent in older
    /// files (empty here), which compare then judges by their percentiles alone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<f64>,
}

/// Percentile by linear interpolation between order statistics (`q` in 0..=1).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Summary of `samples`, `None` when empty (a timing the adapter cannot give is absent).
pub fn summarize(samples: &[f64]) -> Option<Summary> {
    if samples.is_empty() {
        return None;
    }
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    Some(Summary {
        median: percentile(&s, 0.5),
        p10: percentile(&s, 0.1),
        p90: percentile(&s, 0.9),
        min: s[0],
        max: s[s.len() - 1],
        samples: s.len(),
        values: samples.to_vec(),
    })
}

/// Result of a two-sided Mann-Whitney U test of `a` against `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MannWhitney {
    /// U statistic of `b` (number of pairs where the `b` sample is larger, ties ½).
    pub u_b: f64,
    /// Probability that a random `b` sample exceeds a random `a` sample (ties ½): the
    /// common-language effect size, 0.5 for equal distributions.
    pub prob_b_greater: f64,
    /// Two-sided p-value of the normal approximation with tie correction and
    /// continuity correction (1.0 when either side has no samples or all values tie).
    pub p_value: f64,
}

/// Two-sided Mann-Whitney U (Wilcoxon rank-sum) test: are `b`'s samples
/// stochastically larger or smaller than `a`'s? Distribution-free, so one slow
/// outlier frame cannot fake a difference the way it moves a mean.
pub fn mann_whitney(a: &[f64], b: &[f64]) -> MannWhitney {
    let (n1, n2) = (a.len() as f64, b.len() as f64);
    if a.is_empty() || b.is_empty() {
        return MannWhitney {
            u_b: 0.0,
            prob_b_greater: 0.5,
            p_value: 1.0,
        };
    }
    // Ranks of the pooled samples, ties get their mean rank.
    let mut pooled: Vec<(f64, bool)> = a
        .iter()
        .map(|&v| (v, false))
        .chain(b.iter().map(|&v| (v, true)))
        .collect();
    pooled.sort_by(|x, y| x.0.total_cmp(&y.0));
    let n = pooled.len();
    let (mut rank_sum_b, mut tie_term) = (0.0, 0.0);
    let mut i = 0;
    while i < n {
        let mut j = i + 1;
        while j < n && pooled[j].0 == pooled[i].0 {
            j += 1;
        }
        let mean_rank = (i + 1 + j) as f64 / 2.0;
        let t = (j - i) as f64;
        tie_term += t * t * t - t;
        rank_sum_b += mean_rank * pooled[i..j].iter().filter(|p| p.1).count() as f64;
        i = j;
    }
    let u_b = rank_sum_b - n2 * (n2 + 1.0) / 2.0;
    let mean = n1 * n2 / 2.0;
    let nn = n1 + n2;
    let var = n1 * n2 / 12.0 * ((nn + 1.0) - tie_term / (nn * (nn - 1.0)).max(1.0));
    let p_value = if var <= 0.0 {
        1.0
    } else {
        let z = ((u_b - mean).abs() - 0.5).max(0.0) / var.sqrt();
        (2.0 * normal_upper_tail(z)).min(1.0)
    };
    MannWhitney {
        u_b,
        prob_b_greater: u_b / (n1 * n2),
        p_value,
    }
}

/// P(Z > z) for a standard normal Z (Abramowitz & Stegun 7.1.26 erfc, |error| < 1.5e-7).
fn normal_upper_tail(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erfc = poly * (-x * x).exp();
    if z >= 0.0 {
        erfc / 2.0
    } else {
        1.0 - erfc / 2.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_percentiles() {
        let s = summarize(&[5.0, 1.0, 3.0, 2.0, 4.0]).expect("non-empty");
        assert_eq!(s.median, 3.0);
        assert!((s.p10 - 1.4).abs() < 1e-12);
        assert!((s.p90 - 4.6).abs() < 1e-12);
        assert_eq!((s.min, s.max, s.samples), (1.0, 5.0, 5));
        assert!(summarize(&[]).is_none());
        assert_eq!(summarize(&[2.0]).map(|s| s.median), Some(2.0));
        assert_eq!(
            summarize(&[3.0, 1.0]).map(|s| s.values),
            Some(vec![3.0, 1.0])
        );
    }

    #[test]
    fn mann_whitney_separates_shifted_samples_and_not_equal_ones() {
        let a: Vec<f64> = (0..20).map(|i| 10.0 + 0.01 * (i % 7) as f64).collect();
        let b: Vec<f64> = a.iter().map(|v| v * 1.1).collect();
        let shifted = mann_whitney(&a, &b);
        assert!(shifted.p_value < 1e-6, "{shifted:?}");
        assert_eq!(shifted.prob_b_greater, 1.0);
        let same = mann_whitney(&a, &a);
        assert!(same.p_value > 0.9, "{same:?}");
        assert!((same.prob_b_greater - 0.5).abs() < 1e-12);
        // All values tied: no evidence at all.
        assert_eq!(mann_whitney(&[1.0; 5], &[1.0; 5]).p_value, 1.0);
        assert_eq!(mann_whitney(&[], &[1.0]).p_value, 1.0);
        // Textbook value: a = 1..=5, b = 6..=10 gives U_b = 25, exact two-sided p = 0.0079;
        // the normal approximation with continuity correction gives 0.012.
        let t = mann_whitney(&[1.0, 2.0, 3.0, 4.0, 5.0], &[6.0, 7.0, 8.0, 9.0, 10.0]);
        assert_eq!(t.u_b, 25.0);
        assert!((t.p_value - 0.0122).abs() < 1e-3, "{t:?}");
    }
}
