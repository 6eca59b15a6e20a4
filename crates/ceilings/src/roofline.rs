//! A roofline per pass: each pass's counted work read against the adapter's measured
//! ceilings ([`crate::measure`]), the fraction of each ceiling it reaches, and the
//! bound it is nearest.
//!
//! A pass's time is modelled from below by what the harness counts for it:
//!
//! - **fill**: `fragments · t_fragment + primitives · t_triangle`. `t_fragment` is the
//!   inverse of the full-screen fill ceiling of the pass's target (format and blending);
//!   `t_triangle` is what a triangle costs beyond its fragments, from the small- against
//!   the full-screen probe of the same target (the small probe's triangles cover 8
//!   pixels). Both probes are then read exactly by this model, and a pass of large
//!   triangles reads against the full-screen ceiling, one of tiny triangles against the
//!   small one. Fragments are fragment-shader invocations (helper lanes included), the
//!   unit both the probes and the passes are counted in.
//! - **bandwidth**: the bytes of the attachments a render pass clears (a clear writes
//!   every texel), against the clear ceiling (render passes that clear an RGBA32F
//!   target; the sequential-copy ceiling, bytes read + written, in records without
//!   it). A
//!   fragment's own target traffic is not counted again: the fill probe of the same
//!   format and blending already pays it (and on lavapipe, which blends in cached
//!   tiles, blended RGBA32F fill moves 4× more bytes per second than a buffer copy,
//!   so a per-fragment byte count would read above 100% of the copy ceiling).
//! - **overhead**: the pass's instances (cube faces, layers) times the per-pass
//!   overhead (an empty compute pass).
//!
//! Each model time over the measured time is that ceiling's fraction. The pass's
//! `bound` is the kind with the largest fraction when that fraction is at least
//! [`BOUND_SHARE`]; below it most of the pass's time is in its own shader (instructions,
//! memory accesses, atomics), which pipeline statistics cannot split, and the bound is
//! [`Bound::Shader`]. The FP32, strided-bandwidth and atomics ceilings are measured
//! but no pass counts FLOPs, gathers or atomics, so they place no pass.

use caustics_gpu::{PassShape, PassStatistics};
use serde::{Deserialize, Serialize};

/// The share of its time a modelled ceiling must explain to name a pass's bound.
pub const BOUND_SHARE: f64 = 0.5;

/// Pixels covered by one small-probe triangle (half a [`crate::SMALL_CELL_PX`]² cell).
pub const SMALL_TRIANGLE_PX: f64 = (crate::SMALL_CELL_PX * crate::SMALL_CELL_PX) as f64 / 2.0;

/// One probe's measured figure, as a ceilings record keeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeFigure {
    /// The figure in the probe's unit (`Gfragments/s`, `GB/s`, `us/pass`, ...).
    pub figure: f64,
    /// Closed-form work of one trial.
    pub work: f64,
    /// Counted work of one trial (pipeline statistics), when the adapter has them.
    pub counted_work: Option<f64>,
}

/// One fill ceiling: a target format written with or without blending.
#[derive(Clone, Debug, PartialEq)]
pub struct FillCeiling {
    /// The probe it comes from.
    pub probe: &'static str,
    /// Target format.
    pub format: wgpu::TextureFormat,
    /// Additive blending on.
    pub blended: bool,
    /// Full-screen fragments per second.
    pub fragments_per_s: f64,
}

/// The ceilings a roofline reads passes against.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ceilings {
    /// Full-screen fill ceilings.
    pub fill: Vec<FillCeiling>,
    /// Seconds a triangle costs beyond its fragments, and the probes it comes from.
    pub triangle_s: Option<(f64, String)>,
    /// Bytes cleared per second, and the probe it comes from.
    pub clear_bytes_per_s: Option<(f64, &'static str)>,
    /// Seconds of one empty pass.
    pub pass_overhead_s: Option<f64>,
}

const FILL_PROBES: [(&str, &str, wgpu::TextureFormat, bool); 3] = [
    (
        "fill_blend_rgba32f_fullscreen",
        "fill_blend_rgba32f_small",
        wgpu::TextureFormat::Rgba32Float,
        true,
    ),
    (
        "fill_blend_rgba16f_fullscreen",
        "fill_blend_rgba16f_small",
        wgpu::TextureFormat::Rgba16Float,
        true,
    ),
    (
        "fill_unblended_rgba32f_fullscreen",
        "",
        wgpu::TextureFormat::Rgba32Float,
        false,
    ),
];

impl Ceilings {
    /// The ceilings from a record's probe figures (`figure(name)` gives a probe's, or
    /// `None` if the record lacks it). Non-finite or non-positive figures are ignored.
    pub fn from_probes(figure: impl Fn(&str) -> Option<ProbeFigure>) -> Self {
        let usable = |name: &str| figure(name).filter(|f| f.figure.is_finite() && f.figure > 0.0);
        let mut ceilings = Self::default();
        for (full, small, format, blended) in FILL_PROBES {
            let Some(full_fig) = usable(full) else {
                continue;
            };
            let full_rate = full_fig.figure * 1e9;
            ceilings.fill.push(FillCeiling {
                probe: full,
                format,
                blended,
                fragments_per_s: full_rate,
            });
            // The first pair with both probes gives the per-triangle cost (setup and
            // rasterization do not depend on the target's format).
            if ceilings.triangle_s.is_none()
                && let Some(small_fig) = usable(small)
            {
                let triangles = small_fig.work / SMALL_TRIANGLE_PX;
                let counted = small_fig.counted_work.unwrap_or(small_fig.work);
                if triangles > 0.0 {
                    let per_triangle = counted / triangles;
                    let small_rate = small_fig.figure * 1e9;
                    let t = per_triangle * (1.0 / small_rate - 1.0 / full_rate);
                    ceilings.triangle_s = Some((t.max(0.0), format!("{small} against {full}")));
                }
            }
        }
        ceilings.clear_bytes_per_s = ["bandwidth_clear", "bandwidth_copy"]
            .into_iter()
            .find_map(|name| usable(name).map(|f| (f.figure * 1e9, name)));
        ceilings.pass_overhead_s = usable("overhead_pass").map(|f| f.figure * 1e-6);
        ceilings
    }

    /// The fill ceiling for a target: the same format and blending if measured, else
    /// the same blending at the nearest texel size (unknown blending reads as
    /// unblended, the faster ceiling, so its fill fraction is a lower bound; a
    /// depth-only pass reads as unblended too).
    pub fn fill_for(
        &self,
        format: Option<wgpu::TextureFormat>,
        blended: Option<bool>,
    ) -> Option<&FillCeiling> {
        let blended = blended.unwrap_or(false);
        let texel = |f: wgpu::TextureFormat| f.block_copy_size(None).unwrap_or(4);
        let wanted = format.map_or(4, texel);
        self.fill
            .iter()
            .filter(|c| c.blended == blended)
            .min_by_key(|c| {
                let exact = Some(c.format) != format;
                (exact, texel(c.format).abs_diff(wanted))
            })
            .or_else(|| self.fill.first())
    }

    /// The fill ceiling of the methods' caustic targets: additive blending into
    /// [`caustics_gpu::textures::HDR_FORMAT`] (RGBA32F).
    pub fn method_target_fill(&self) -> Option<&FillCeiling> {
        self.fill_for(Some(caustics_gpu::textures::HDR_FORMAT), Some(true))
    }

    /// Whether any ceiling is known at all.
    pub fn is_empty(&self) -> bool {
        self.fill.is_empty() && self.clear_bytes_per_s.is_none() && self.pass_overhead_s.is_none()
    }
}

/// What one named pass did in a frame, summed over its instances.
#[derive(Clone, Debug, PartialEq)]
pub struct PassWork {
    /// `"<owner>/<pass>"`.
    pub name: String,
    /// Median GPU time per frame (ms), all instances together.
    pub gpu_ms: f64,
    /// Instances of the pass in one frame (6 for a cube map's faces).
    pub instances: u32,
    /// Compute or render, and its target (the first instance's).
    pub shape: PassShape,
    /// Pipeline statistics of the count frame, summed over the instances.
    pub statistics: Option<PassStatistics>,
}

/// The kind of work a pass is nearest to the ceiling of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// Rasterization and blending of its fragments and triangles.
    Fill,
    /// Bytes to and from its targets.
    Bandwidth,
    /// Fixed cost of opening and ending the pass.
    Overhead,
    /// The pass's own shader work (instructions, memory accesses, atomics): no
    /// counted ceiling explains [`BOUND_SHARE`] of its time.
    Shader,
}

impl Bound {
    /// The lower-case name written in results and tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Bound::Fill => "fill",
            Bound::Bandwidth => "bandwidth",
            Bound::Overhead => "overhead",
            Bound::Shader => "shader",
        }
    }
}

/// One ceiling's share of a pass's time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CeilingShare {
    /// The probe(s) the ceiling comes from.
    pub ceiling: String,
    /// The pass's work in the ceiling's unit (fragments, bytes, passes).
    pub work: f64,
    /// The time the pass would take at the ceiling (ms).
    pub model_ms: f64,
    /// `model_ms / gpu_ms`: the fraction of the ceiling the pass reaches.
    pub fraction: f64,
}

/// A pass read against the ceilings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PassRoofline {
    /// `"<owner>/<pass>"`.
    pub name: String,
    /// Median GPU time per frame (ms).
    pub gpu_ms: f64,
    /// The nearest ceiling's kind, or `shader` when none explains half the time.
    pub bound: Bound,
    /// The largest of the ceiling fractions below (0 when none applies).
    pub fraction: f64,
    /// Fill (render passes with statistics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<CeilingShare>,
    /// Target bandwidth (render passes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bandwidth: Option<CeilingShare>,
    /// Pass overhead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub overhead: Option<CeilingShare>,
    /// Fragment-shader invocations per second achieved (render passes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fragments_per_s: Option<f64>,
    /// Fragments per primitive (render passes that rasterized any): the x of the
    /// fill roofline plot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fragments_per_primitive: Option<f64>,
    /// Compute-shader invocations per second achieved (compute passes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invocations_per_s: Option<f64>,
}

/// Reads one pass against `ceilings`. `None` when the pass has no positive time.
pub fn pass_roofline(work: &PassWork, ceilings: &Ceilings) -> Option<PassRoofline> {
    if !(work.gpu_ms.is_finite() && work.gpu_ms > 0.0) {
        return None;
    }
    let share = |ceiling: String, amount: f64, model_s: f64| CeilingShare {
        ceiling,
        work: amount,
        model_ms: model_s * 1e3,
        fraction: model_s * 1e3 / work.gpu_ms,
    };
    let seconds = work.gpu_ms * 1e-3;
    let stats = work.statistics;
    let mut out = PassRoofline {
        name: work.name.clone(),
        gpu_ms: work.gpu_ms,
        bound: Bound::Shader,
        fraction: 0.0,
        fill: None,
        bandwidth: None,
        overhead: None,
        fragments_per_s: None,
        fragments_per_primitive: None,
        invocations_per_s: None,
    };
    match work.shape {
        PassShape::Render {
            color_format,
            blended,
            cleared_bytes,
        } => {
            let fragments = stats.map(|s| s.fragment_invocations as f64);
            let primitives = stats.map(|s| s.primitives_out as f64);
            if let (Some(frags), Some(prims), Some(fill)) = (
                fragments,
                primitives,
                ceilings.fill_for(color_format, blended),
            ) {
                let (triangle_s, triangle_probe) = ceilings
                    .triangle_s
                    .as_ref()
                    .map_or((0.0, String::new()), |(t, p)| {
                        (*t, format!(" + triangles: {p}"))
                    });
                let model_s = frags / fill.fragments_per_s + prims * triangle_s;
                out.fill = Some(share(
                    format!("{}{triangle_probe}", fill.probe),
                    frags,
                    model_s,
                ));
                out.fragments_per_s = Some(frags / seconds);
                out.fragments_per_primitive = (prims > 0.0).then(|| frags / prims);
            }
            if let Some((bw, probe)) = ceilings.clear_bytes_per_s {
                let bytes = cleared_bytes as f64;
                if bytes > 0.0 {
                    out.bandwidth = Some(share(probe.into(), bytes, bytes / bw));
                }
            }
        }
        PassShape::Compute => {
            out.invocations_per_s = stats.map(|s| s.compute_invocations as f64 / seconds);
        }
    }
    if let Some(t) = ceilings.pass_overhead_s {
        let passes = f64::from(work.instances.max(1));
        out.overhead = Some(share("overhead_pass".into(), passes, passes * t));
    }
    let candidates = [
        (Bound::Fill, &out.fill),
        (Bound::Bandwidth, &out.bandwidth),
        (Bound::Overhead, &out.overhead),
    ];
    if let Some((bound, fraction)) = candidates
        .iter()
        .filter_map(|(b, s)| s.as_ref().map(|s| (*b, s.fraction)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        out.fraction = fraction;
        out.bound = if fraction >= BOUND_SHARE {
            bound
        } else {
            Bound::Shader
        };
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record like lavapipe's: 1 Gfragments/s full screen, 0.1 small (16 counted
    /// fragments per 8-pixel triangle), 10 GB/s, 25 µs per pass.
    fn ceilings() -> Ceilings {
        Ceilings::from_probes(|name| {
            let fig = |figure, work, counted| {
                Some(ProbeFigure {
                    figure,
                    work,
                    counted_work: counted,
                })
            };
            match name {
                "fill_blend_rgba32f_fullscreen" => fig(1.0, 1e6, Some(1e6)),
                "fill_blend_rgba32f_small" => fig(0.1, 8e4, Some(16e4)),
                "fill_blend_rgba16f_fullscreen" => fig(2.0, 1e6, None),
                "fill_unblended_rgba32f_fullscreen" => fig(5.0, 1e6, None),
                "bandwidth_copy" => fig(10.0, 1e8, None),
                "overhead_pass" => fig(25.0, 64.0, None),
                "compute_fp32" => fig(f64::NAN, 1.0, None),
                _ => None,
            }
        })
    }

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() <= 1e-9 * b.abs())
    }

    fn render(frags: u64, prims: u64, gpu_ms: f64, format: wgpu::TextureFormat) -> PassWork {
        PassWork {
            name: "m/p".into(),
            gpu_ms,
            instances: 1,
            shape: PassShape::Render {
                color_format: Some(format),
                blended: Some(true),
                cleared_bytes: 0,
            },
            statistics: Some(PassStatistics {
                primitives_out: prims,
                fragment_invocations: frags,
                ..Default::default()
            }),
        }
    }

    #[test]
    fn triangle_cost_comes_from_the_small_probe() {
        let c = ceilings();
        let (t, probes) = c.triangle_s.clone().expect("triangle cost");
        // 16 fragments per triangle at 0.1 G/s = 160 ns, less 16 ns of fill.
        assert!((t - 144e-9).abs() < 1e-12, "{t}");
        assert!(probes.contains("fill_blend_rgba32f_small"), "{probes}");
        assert!(close(c.clear_bytes_per_s.map(|c| c.0), 10e9));
        assert_eq!(c.clear_bytes_per_s.map(|c| c.1), Some("bandwidth_copy"));
        assert!(close(c.pass_overhead_s, 25e-6));
    }

    #[test]
    fn the_probes_read_exactly_at_their_own_ceiling() {
        let c = ceilings();
        // Full-screen probe: 1e9 fragments in one triangle take 1 s.
        let full = pass_roofline(
            &render(1_000_000_000, 1, 1000.0, wgpu::TextureFormat::Rgba32Float),
            &c,
        )
        .expect("roofline");
        assert_eq!(full.bound, Bound::Fill);
        assert!((full.fraction - 1.0).abs() < 1e-6, "{}", full.fraction);
        // Small probe: 1e8 counted fragments in 6.25e6 triangles take 1 s.
        let small = pass_roofline(
            &render(
                100_000_000,
                6_250_000,
                1000.0,
                wgpu::TextureFormat::Rgba32Float,
            ),
            &c,
        )
        .expect("roofline");
        assert!((small.fill.as_ref().expect("fill").fraction - 1.0).abs() < 1e-6);
        assert!(close(small.fragments_per_primitive, 16.0));
    }

    #[test]
    fn a_slow_shader_is_shader_bound_and_the_format_picks_the_ceiling() {
        let c = ceilings();
        // 1e6 RGBA16F fragments at 2 G/s = 0.5 ms of fill in a 10 ms pass.
        let r = pass_roofline(
            &render(1_000_000, 1, 10.0, wgpu::TextureFormat::Rgba16Float),
            &c,
        )
        .expect("roofline");
        assert_eq!(r.bound, Bound::Shader);
        let fill = r.fill.as_ref().expect("fill");
        assert!(
            fill.ceiling.starts_with("fill_blend_rgba16f_fullscreen"),
            "{}",
            fill.ceiling
        );
        assert!((fill.fraction - 0.05).abs() < 1e-3, "{}", fill.fraction);
        assert!((r.fraction - 0.05).abs() < 1e-3, "{}", r.fraction);
        // Nothing cleared: no bandwidth term (the fill ceiling pays the target's bytes).
        assert!(r.bandwidth.is_none());
    }

    #[test]
    fn empty_passes_are_overhead_bound_and_compute_passes_report_invocations() {
        let c = ceilings();
        let pass = PassWork {
            name: "m/trace".into(),
            gpu_ms: 0.04,
            instances: 1,
            shape: PassShape::Compute,
            statistics: Some(PassStatistics {
                compute_invocations: 4_000,
                ..Default::default()
            }),
        };
        let r = pass_roofline(&pass, &c).expect("roofline");
        assert_eq!(r.bound, Bound::Overhead);
        assert!((r.fraction - 0.625).abs() < 1e-9);
        assert!(close(r.invocations_per_s, 1e8));
        assert!(r.fill.is_none() && r.bandwidth.is_none());
        let slow = PassWork {
            gpu_ms: 10.0,
            instances: 6,
            ..pass
        };
        let r = pass_roofline(&slow, &c).expect("roofline");
        assert_eq!(r.bound, Bound::Shader);
        assert_eq!(r.overhead.as_ref().map(|o| o.work), Some(6.0));
        assert!(
            pass_roofline(
                &PassWork {
                    gpu_ms: 0.0,
                    ..slow
                },
                &c
            )
            .is_none()
        );
    }

    #[test]
    fn a_clear_is_bandwidth_work_and_unknown_blending_reads_unblended() {
        let c = ceilings();
        let pass = PassWork {
            name: "base/clear".into(),
            gpu_ms: 1.0,
            instances: 1,
            shape: PassShape::Render {
                color_format: Some(wgpu::TextureFormat::Rgba32Float),
                blended: None,
                cleared_bytes: 8_000_000,
            },
            statistics: Some(PassStatistics::default()),
        };
        let r = pass_roofline(&pass, &c).expect("roofline");
        assert_eq!(r.bound, Bound::Bandwidth);
        assert!((r.fraction - 0.8).abs() < 1e-9, "{}", r.fraction);
        assert!(
            r.fill
                .as_ref()
                .expect("fill")
                .ceiling
                .starts_with("fill_unblended_rgba32f_fullscreen")
        );
        assert!(Ceilings::default().is_empty());
        assert!(!c.is_empty());
    }
}
