//! Plots of a summary, drawn with `plotters` on its bitmap backend, written as PNG. Every
//! label is drawn with the metrics crate's text (DejaVu Sans, embedded, rasterized by
//! `ab_glyph`, the crate behind plotters' own `ab_glyph` text feature): our layouts
//! measure text before placing it, so text is drawn by us after plotters has drawn the
//! shapes, never from system fonts. Each axis' scale is fixed by what it shows
//! ([`scale_for`]: times, relMSE and counts log; FLIP and ratios linear), and every plot
//! carries a caption with the adapter, resolution and build ([`caption`]):
//!
//! - `<y>_vs_time_<scene>.png`: an error of the pixel-averaged scoring frame against the
//!   method's GPU time, one colour per method, with the Pareto front (runs no other run
//!   beats in both), for each y axis of [`error_axes`]: `error` (relMSE), `hdr_flip`
//!   (HDR-FLIP), and `volume_error`, `volume_hdr_flip` when runs have volume errors;
//! - `<y>_vs_<param>_<scene>.png`: the same errors against each numeric parameter swept
//!   over 3+ values;
//! - `heatmaps_<scene>.png`, `heatmaps_log_<scene>.png`: the fill-rate heatmaps of every
//!   run of a scene side by side on one colour scale (the largest count over the
//!   panels), linear and log;
//! - `fragments.png`: fragment-shader invocations of the method's passes per run.

use std::path::Path;

use anyhow::{Result, anyhow};
use caustics_metrics::{
    GLYPH_H, HeatmapOptions, Rgb8Image, draw_text, draw_text_vertical, heatmap_with, text_width,
};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::summary::{Row, Summary, num};

pub(crate) const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
];
pub(crate) const INK: [u8; 3] = [20, 20, 20];
const GRID: [u8; 3] = [225, 225, 225];
/// Colour of fits and reference lines.
pub(crate) const GUIDE: [u8; 3] = [120, 120, 120];

/// How an axis maps its values. Fixed by what the axis shows ([`scale_for`]), never by
/// the data's range, so every plot of one kind in an experiment reads the same way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scale {
    /// Linear.
    Linear,
    /// log10: values <= 0 cannot be shown and are left out.
    Log,
}

/// The scale of an axis that shows `name` (a measure, `counter:<name>`, `param:<name>`,
/// or an axis label) with the values `values`: times, relMSE/RMSE-like errors and counts
/// span decades between methods and go log; FLIP, flux and other ratios live near [0, 2]
/// and stay linear; anything else (a parameter) goes log when its values are all positive
/// and grow geometrically (a sweep 1, 2, 4 … 32), else linear.
pub(crate) fn scale_for(name: &str, values: &[f64]) -> Scale {
    let n = name.to_ascii_lowercase();
    let has = |k: &str| n.contains(k);
    if has("flip") || has("flux") || has("ratio") || has("the baseline") || has("share") {
        return Scale::Linear;
    }
    let decades = [
        "gpu ms",
        "_ms",
        "time",
        "relmse",
        "rel_mse",
        "rmse",
        "fragments",
        "beams",
        "photons",
        "triangles",
        "samples",
    ];
    if !n.starts_with("param:") && (n.starts_with("counter:") || decades.iter().any(|k| has(k))) {
        return Scale::Log;
    }
    let mut v: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    let geometric = v.len() >= 3 && v[0] > 0.0 && v.windows(2).all(|w| w[1] / w[0] >= 1.9);
    if geometric { Scale::Log } else { Scale::Linear }
}

/// An axis: value range, linear or log10.
#[derive(Clone, Copy, Debug)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    /// Every value is a whole number (a count, a level): ticks are whole too.
    integer: bool,
}

impl Axis {
    /// Fits values (finite ones; positive ones only on a log axis), padded by 5%. A log
    /// axis without a positive value falls back to linear.
    fn fit(values: &[f64], scale: Scale) -> Axis {
        let shown: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0))
            .collect();
        if scale == Scale::Log && shown.is_empty() {
            return Axis::fit(values, Scale::Linear);
        }
        let (mut lo, mut hi) = shown
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        let log = scale == Scale::Log;
        let integer = shown.iter().all(|v| v.fract() == 0.0);
        if log {
            let (mut l, mut h) = (lo.log10(), hi.log10());
            if h - l < 0.3 {
                // Less than a factor of 2: widen to one around the middle.
                let mid = 0.5 * (l + h);
                (l, h) = (mid - 0.15, mid + 0.15);
            }
            let pad = 0.05 * (h - l);
            return Axis {
                lo: 10f64.powf(l - pad),
                hi: 10f64.powf(h + pad),
                log,
                integer,
            };
        }
        if hi - lo <= f64::EPSILON * hi.abs().max(1.0) {
            let d = if hi == 0.0 { 1.0 } else { 0.1 * hi.abs() };
            lo -= d;
            hi += d;
        }
        let pad = 0.05 * (hi - lo);
        Axis {
            lo: if lo >= 0.0 {
                (lo - pad).max(0.0)
            } else {
                lo - pad
            },
            hi: hi + pad,
            log,
            integer,
        }
    }
    fn map(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.map(self.lo)..self.map(self.hi)
    }
    fn ticks(&self) -> Vec<f64> {
        if self.log {
            let mut t = Vec::new();
            let (a, b) = (
                self.lo.log10().floor() as i32,
                self.hi.log10().ceil() as i32,
            );
            // Decades; 1-2-5 within two decades; every digit when even that gives < 3.
            let every: &[f64] = &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
            for per_decade in [&[1.0][..], &[1.0, 2.0, 5.0], every] {
                if per_decade.len() == 1 && b - a <= 2 {
                    continue;
                }
                t.clear();
                for e in a..=b {
                    for m in per_decade {
                        let v = m * 10f64.powi(e);
                        if v >= self.lo && v <= self.hi {
                            t.push(v);
                        }
                    }
                }
                if t.len() >= 3 {
                    return t;
                }
            }
            // Under a factor of about 3: plain ticks inside the range.
            return self.linear_ticks((self.hi - self.lo) / 4.0);
        }
        self.linear_ticks((self.hi - self.lo) / 5.0)
    }

    /// Ticks of a linear axis about `raw` apart, on 1-2-5 steps.
    fn linear_ticks(&self, raw: f64) -> Vec<f64> {
        let mag = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * mag)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * mag);
        // Counts and levels tick on whole numbers (no "1.5 levels").
        let step = if self.integer {
            step.max(1.0).round()
        } else {
            step
        };
        let mut v = (self.lo / step).ceil() * step;
        let mut t = Vec::new();
        while v <= self.hi + 1e-9 * step {
            t.push(if v.abs() < 1e-12 * step { 0.0 } else { v });
            v += step;
        }
        t
    }
}

/// A tick value with at most 4 significant digits and no trailing zeros; outside
/// [0.001, 100000) as `m·10ⁿ` (`10ⁿ` when m = 1) with a true superscript, and negative
/// values with a true minus sign.
fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let text = if v.abs() >= 1e5 || v.abs() < 1e-3 {
        let mut e = v.abs().log10().floor() as i32;
        let mut m = v.abs() / 10f64.powi(e);
        if m >= 9.995 {
            (m, e) = (m / 10.0, e + 1);
        }
        let sup: String = e
            .to_string()
            .chars()
            .map(|c| match c.to_digit(10) {
                Some(d) => ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'][d as usize],
                None => '⁻',
            })
            .collect();
        let mantissa = format!("{m:.2}");
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        if mantissa == "1" {
            format!("10{sup}")
        } else {
            format!("{mantissa}·10{sup}")
        }
    } else {
        let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        let s = format!("{:.decimals$}", v.abs());
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            s
        }
    };
    if v < 0.0 { format!("−{text}") } else { text }
}

pub(crate) fn colour(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

pub(crate) fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing a plot: {e:?}")
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Style {
    /// Dots.
    Points,
    /// Dots joined by a line.
    Line,
    /// A dashed line without dots (fits, reference lines).
    Dashed,
}

/// A named series of points.
#[derive(Clone, Debug)]
pub(crate) struct Series {
    /// Legend text.
    pub(crate) name: String,
    /// Its colour.
    pub(crate) colour: [u8; 3],
    /// (x, y) in data units.
    pub(crate) points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub(crate) style: Style,
}

impl Series {
    pub(crate) fn new(
        name: impl Into<String>,
        colour: [u8; 3],
        points: Vec<(f64, f64)>,
        style: Style,
    ) -> Self {
        Series {
            name: name.into(),
            colour,
            points,
            style,
        }
    }
}

/// Text to draw after plotters is done: (x, y, text, vertical).
pub(crate) type Labels = Vec<(i32, i32, String, bool)>;

/// A plot's shapes, drawn by plotters on any backend (the PNG's bitmap, the SVG), with
/// the labels to set over them ([`render`]).
pub(crate) trait Shapes {
    /// Width and height in pixels, without the caption.
    fn size(&self) -> (u32, u32);
    /// Draws the shapes onto `root` (white first) and returns the labels.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<Labels>;
}

/// Writes `shapes` as `path` (PNG, labels rasterized in DejaVu Sans) and beside it the
/// same plot as SVG (`path` with `.svg`: vector shapes, labels as `<text>` in DejaVu
/// Sans, for papers), both with `caption` under them.
pub(crate) fn render(path: &Path, shapes: &impl Shapes, caption: &str) -> Result<()> {
    let (w, h) = shapes.size();
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let labels = {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let labels = shapes.draw(&root)?;
        root.present().map_err(plot_err)?;
        labels
    };
    finish(buf, w, h, &labels, caption, path)?;
    let width = w.max(text_width(caption) + 16);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, h + CAPTION_H)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let (top, _) = root.split_vertically(h);
        shapes.draw(&top)?;
        root.present().map_err(plot_err)?;
    }
    let mut text = String::new();
    let esc = |t: &str| {
        t.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let ink = |c: [u8; 3]| format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]);
    // The raster text's geometry: `y` is the capitals' top, the baseline GLYPH_H below.
    for (x, y, t, vertical) in &labels {
        let (x, y) = ((*x).max(0), (*y).max(0));
        let base = GLYPH_H as i32;
        text += &if *vertical {
            // Reading upwards from row y: the baseline on column x + GLYPH_H.
            format!(
                "<text transform=\"translate({} {y}) rotate(-90)\" {SVG_FONT} fill=\"{}\">{}</text>",
                x + base,
                ink(INK),
                esc(t)
            )
        } else {
            format!(
                "<text x=\"{x}\" y=\"{}\" {SVG_FONT} fill=\"{}\">{}</text>",
                y + base,
                ink(INK),
                esc(t)
            )
        };
    }
    text += &format!(
        "<text x=\"8\" y=\"{}\" {SVG_FONT} fill=\"{}\">{}</text>",
        h + 3 + GLYPH_H,
        ink(GUIDE),
        esc(caption)
    );
    let Some(end) = svg.rfind("</svg>") else {
        anyhow::bail!("plotters wrote no closing </svg>");
    };
    svg.insert_str(end, &text);
    caustics_metrics::atomic_write(&path.with_extension("svg"), svg.as_bytes())?;
    Ok(())
}

/// The SVG labels' font: the PNG's (DejaVu Sans at 12 px ascent-to-descent = 10.3 px em).
const SVG_FONT: &str = "font-family=\"DejaVu Sans, Verdana, sans-serif\" font-size=\"10.3\"";

/// Rows under every plot and figure for its caption.
pub(crate) const CAPTION_H: u32 = 16;

/// The caption of a plot of `rows`: the adapter(s), the resolution(s), the build (profile
/// and commit) they were made with, so a figure read apart from its summary still says
/// what it measured on.
pub(crate) fn caption(s: &Summary, rows: &[&Row]) -> String {
    let mut sizes: Vec<String> = Vec::new();
    for r in rows {
        let size = format!("{}×{}", r.width, r.height);
        if !sizes.contains(&size) {
            sizes.push(size);
        }
    }
    let commits: Vec<String> = s
        .commits
        .iter()
        .map(|c| c.chars().take(10).collect())
        .collect();
    let mut parts = vec![if s.adapters.is_empty() {
        "adapter not recorded".to_owned()
    } else {
        s.adapters.join(", ")
    }];
    if !sizes.is_empty() {
        parts.push(sizes.join(", "));
    }
    if !s.profiles.is_empty() {
        parts.push(format!("{} build", s.profiles.join("/")));
    }
    if !commits.is_empty() {
        parts.push(format!("commit {}", commits.join(", ")));
    }
    parts.join(" · ")
}

/// Copies `src` onto a white image `CAPTION_H` rows taller and writes `caption` in grey
/// along the bottom.
pub(crate) fn with_caption(src: &Rgb8Image, caption: &str) -> Rgb8Image {
    let width = src.width.max(text_width(caption) + 16);
    let mut img = Rgb8Image::filled(width, src.height + CAPTION_H, [255; 3]);
    for y in 0..src.height {
        for x in 0..src.width {
            img.set(x, y, src.get(x, y));
        }
    }
    draw_text(&mut img, 8, src.height + 3, caption, GUIDE);
    img
}

pub(crate) fn finish(
    buf: Vec<u8>,
    w: u32,
    h: u32,
    labels: &Labels,
    caption: &str,
    path: &Path,
) -> Result<()> {
    let mut img = Rgb8Image {
        width: w,
        height: h,
        pixels: buf.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
    };
    for (x, y, text, vertical) in labels {
        let (x, y) = ((*x).max(0) as u32, (*y).max(0) as u32);
        if *vertical {
            draw_text_vertical(&mut img, x, y, text, INK);
        } else {
            draw_text(&mut img, x, y, text, INK);
        }
    }
    caustics_metrics::write_png(path, &with_caption(&img, caption))?;
    Ok(())
}

/// What a scatter plot shows, besides its series.
pub(crate) struct Plot<'a> {
    /// Over the plot.
    pub(crate) title: &'a str,
    /// Under it ([`caption`]).
    pub(crate) caption: &'a str,
    /// The x axis' label and scale.
    pub(crate) x: (&'a str, Scale),
    /// The y axis' label and scale.
    pub(crate) y: (&'a str, Scale),
}

/// A scatter plot with axes, ticks, labels, a legend as wide as its longest entry and a
/// caption, as PNG and SVG. Points a log axis cannot show (≤ 0) are left out.
pub(crate) fn scatter(path: &Path, plot: &Plot<'_>, series: &[Series]) -> Result<()> {
    let legend_w = series
        .iter()
        .map(|s| text_width(&s.name) as i32)
        .max()
        .unwrap_or(0);
    let margin_right = (legend_w + 40).max(120);
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.points.clone()).collect();
    let shapes = Scatter {
        plot,
        series,
        xa: Axis::fit(&all.iter().map(|p| p.0).collect::<Vec<_>>(), plot.x.1),
        ya: Axis::fit(&all.iter().map(|p| p.1).collect::<Vec<_>>(), plot.y.1),
        margin_right,
    };
    render(path, &shapes, plot.caption)
}

/// The shapes of [`scatter`].
struct Scatter<'a> {
    plot: &'a Plot<'a>,
    series: &'a [Series],
    xa: Axis,
    ya: Axis,
    margin_right: i32,
}

impl Shapes for Scatter<'_> {
    fn size(&self) -> (u32, u32) {
        ((510 + self.margin_right) as u32, 420)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<Labels> {
        let (w, h) = self.size();
        let (plot, series, xa, ya, margin_right) =
            (self.plot, self.series, self.xa, self.ya, self.margin_right);
        let mut labels: Labels = Vec::new();
        root.fill(&WHITE).map_err(plot_err)?;
        let mut chart = ChartBuilder::on(root)
            .margin_top(28)
            .margin_right(margin_right)
            .margin_left(70)
            .margin_bottom(40)
            .build_cartesian_2d(xa.range(), ya.range())
            .map_err(plot_err)?;
        let (xr, yr) = (xa.range(), ya.range());
        for t in xa.ticks() {
            let x = xa.map(t);
            chart
                .draw_series(LineSeries::new([(x, yr.start), (x, yr.end)], colour(GRID)))
                .map_err(plot_err)?;
            let (px, py) = chart.backend_coord(&(x, yr.start));
            let s = tick_label(t);
            labels.push((px - text_width(&s) as i32 / 2, py + 6, s, false));
        }
        for t in ya.ticks() {
            let y = ya.map(t);
            chart
                .draw_series(LineSeries::new([(xr.start, y), (xr.end, y)], colour(GRID)))
                .map_err(plot_err)?;
            let (px, py) = chart.backend_coord(&(xr.start, y));
            let s = tick_label(t);
            labels.push((
                px - 6 - text_width(&s) as i32,
                py - GLYPH_H as i32 / 2,
                s,
                false,
            ));
        }
        let frame = [
            (xr.start, yr.start),
            (xr.end, yr.start),
            (xr.end, yr.end),
            (xr.start, yr.end),
            (xr.start, yr.start),
        ];
        chart
            .draw_series(LineSeries::new(frame, colour(INK)))
            .map_err(plot_err)?;
        for (i, s) in series.iter().enumerate() {
            let c = colour(s.colour);
            let shown = |v: f64, a: &Axis| v.is_finite() && (!a.log || v > 0.0);
            let mapped: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| shown(p.0, &xa) && shown(p.1, &ya))
                .map(|p| (xa.map(p.0), ya.map(p.1)))
                .collect();
            match s.style {
                Style::Line => {
                    chart
                        .draw_series(LineSeries::new(mapped.clone(), c.stroke_width(1)))
                        .map_err(plot_err)?;
                    chart
                        .draw_series(mapped.iter().map(|p| Circle::new(*p, 2, c.filled())))
                        .map_err(plot_err)?;
                }
                Style::Points => {
                    chart
                        .draw_series(mapped.iter().map(|p| Circle::new(*p, 4, c.filled())))
                        .map_err(plot_err)?;
                }
                Style::Dashed => {
                    // Dashes of about 6 px, cut in the chart's (linear) mapped space.
                    for seg in mapped.windows(2) {
                        let (a, b) = (seg[0], seg[1]);
                        let (pa, pb) = (chart.backend_coord(&a), chart.backend_coord(&b));
                        let len = f64::from((pb.0 - pa.0).pow(2) + (pb.1 - pa.1).pow(2)).sqrt();
                        let n = ((len / 6.0).ceil() as usize).max(1);
                        let at = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
                        for k in (0..n).step_by(2) {
                            let (t0, t1) =
                                (k as f64 / n as f64, ((k + 1) as f64 / n as f64).min(1.0));
                            chart
                                .draw_series(LineSeries::new([at(t0), at(t1)], c.stroke_width(1)))
                                .map_err(plot_err)?;
                        }
                    }
                }
            }
            // Legend entry in the right margin.
            let (lx, ly) = (w as i32 - margin_right + 10, 36 + 15 * i as i32);
            let legend_h = if s.style == Style::Points { 8 } else { 2 };
            let legend_w = if s.style == Style::Dashed { 4 } else { 10 };
            for dx in [0, 6]
                .into_iter()
                .take(if s.style == Style::Dashed { 2 } else { 1 })
            {
                root.draw(&Rectangle::new(
                    [(lx + dx, ly), (lx + dx + legend_w, ly + legend_h)],
                    c.filled(),
                ))
                .map_err(plot_err)?;
            }
            labels.push((lx + 16, ly - 3, s.name.clone(), false));
        }
        labels.push((70, 10, plot.title.to_owned(), false));
        let x_label = format!("{}{}", plot.x.0, if xa.log { " (log)" } else { "" });
        labels.push((
            70 + (w as i32 - 70 - margin_right) / 2 - text_width(&x_label) as i32 / 2,
            h as i32 - 16,
            x_label,
            false,
        ));
        let y_label = format!("{}{}", plot.y.0, if ya.log { " (log)" } else { "" });
        labels.push((
            6,
            h as i32 / 2 + text_width(&y_label) as i32 / 2,
            y_label,
            true,
        ));
        Ok(labels)
    }
}

/// The runs not beaten in both time and error by another run, sorted by time.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if front.last().is_none_or(|l| q.1 < l.1) {
            front.push(q);
        }
    }
    front
}

pub(crate) fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Horizontal bars of the method's fragments, one per run (PNG and SVG).
fn fragments_plot(
    path: &Path,
    rows: &[(&Row, u64)],
    methods: &[String],
    caption: &str,
) -> Result<()> {
    let label_w = rows
        .iter()
        .map(|(r, _)| text_width(&bar_label(r)) as i32)
        .max()
        .unwrap_or(0)
        + 16;
    render(
        path,
        &FragmentBars {
            rows,
            methods,
            label_w,
        },
        caption,
    )
}

/// The shapes of [`fragments_plot`].
struct FragmentBars<'a> {
    rows: &'a [(&'a Row, u64)],
    methods: &'a [String],
    label_w: i32,
}

impl FragmentBars<'_> {
    const BAR_H: i32 = 12;
}

impl Shapes for FragmentBars<'_> {
    fn size(&self) -> (u32, u32) {
        (
            (self.label_w + 420) as u32,
            (40 + self.rows.len() as i32 * (Self::BAR_H + 4) + 20) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<Labels> {
        let (bar_h, label_w) = (Self::BAR_H, self.label_w);
        let max = self.rows.iter().map(|r| r.1).max().unwrap_or(1).max(1) as f64;
        let mut labels: Labels = vec![(
            8,
            10,
            "fragments shaded by the method passes (count frame)".into(),
            false,
        )];
        root.fill(&WHITE).map_err(plot_err)?;
        let span = 330.0;
        for (i, (r, f)) in self.rows.iter().enumerate() {
            let y = 32 + i as i32 * (bar_h + 4);
            let m = self
                .methods
                .iter()
                .position(|m| *m == r.method)
                .unwrap_or(0);
            let len = ((*f as f64 / max) * span).round() as i32;
            root.draw(&Rectangle::new(
                [(label_w, y), (label_w + len.max(1), y + bar_h)],
                colour(PALETTE[m % PALETTE.len()]).filled(),
            ))
            .map_err(plot_err)?;
            labels.push((8, y + 2, bar_label(r), false));
            labels.push((label_w + len + 4, y + 2, num(*f as f64), false));
        }
        Ok(labels)
    }
}

/// `text` broken at spaces into lines of at most `max_w` pixels (a word longer than that
/// stands alone on its line).
pub(crate) fn wrap(text: &str, max_w: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        match lines.last_mut() {
            Some(l) if text_width(&format!("{l} {word}")) <= max_w => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_owned()),
        }
    }
    if lines.is_empty() {
        lines.push(String::new());
    }
    lines
}

/// Rows of one line of label text.
pub(crate) const LINE_H: u32 = GLYPH_H + caustics_metrics::DESCENT + 3;

/// Images in a grid (up to 4 a row), each under its label (wrapped to the image's
/// width), on white, with a caption.
fn tile(path: &Path, title: &str, tiles: &[(String, Rgb8Image)], caption: &str) -> Result<()> {
    let cols = tiles.len().min(4);
    let cell_w = tiles.iter().map(|t| t.1.width).max().unwrap_or(1) + 8;
    let wrapped: Vec<Vec<String>> = tiles.iter().map(|t| wrap(&t.0, cell_w - 8)).collect();
    let image_h = tiles.iter().map(|t| t.1.height).max().unwrap_or(1);
    // Each grid row is as tall as its longest label needs.
    let label_h: Vec<u32> = wrapped
        .chunks(cols)
        .map(|r| r.iter().map(Vec::len).max().unwrap_or(1) as u32 * LINE_H)
        .collect();
    let row_y: Vec<u32> = label_h
        .iter()
        .scan(22, |y, h| {
            let top = *y;
            *y += h + image_h + 8;
            Some(top)
        })
        .collect();
    let height =
        row_y.last().copied().unwrap_or(22) + label_h.last().copied().unwrap_or(0) + image_h + 8;
    let mut img = Rgb8Image::filled(
        (cols as u32 * cell_w + 8).max(text_width(title) + 16),
        height,
        [255; 3],
    );
    draw_text(&mut img, 8, 6, title, INK);
    for (i, ((_, t), lines)) in tiles.iter().zip(&wrapped).enumerate() {
        let (x0, y0) = (8 + (i % cols) as u32 * cell_w, row_y[i / cols]);
        for (k, line) in lines.iter().enumerate() {
            draw_text(&mut img, x0, y0 + k as u32 * LINE_H, line, INK);
        }
        for y in 0..t.height {
            for x in 0..t.width {
                img.set(x0 + x, y0 + label_h[i / cols] + y, t.get(x, y));
            }
        }
    }
    caustics_metrics::write_png(path, &with_caption(&img, caption))?;
    Ok(())
}

/// A run by its scene, method and parameters.
fn bar_label(r: &Row) -> String {
    format!("{} {}", r.scene, run_label(r))
}

/// A run of a known scene by its method and parameters.
fn run_label(r: &Row) -> String {
    let params: Vec<String> = r
        .params
        .iter()
        .map(|(k, v)| match v {
            serde_json::Value::String(s) => format!("{k}={s}"),
            v => format!("{k}={v}"),
        })
        .collect();
    if params.is_empty() {
        r.method.clone()
    } else {
        format!("{} {}", r.method, params.join(" "))
    }
}

/// A y axis of the error plots: file stem, axis label, and the figure of a run.
type ErrorAxis = (&'static str, &'static str, fn(&Row) -> Option<f64>);

/// The y axes of the error plots, all of the pixel-averaged scoring frame (a schema-1 run,
/// scored at 1 spp only, is left out rather than drawn among pixel-averaged ones).
///
/// relMSE as measured, not after flux normalization: a Pareto front of quality against
/// cost must charge a method for light it loses or adds, and relMSE after flux forgives
/// exactly that (the flux ratio in the summary says how much there is to forgive). relMSE,
/// not RMSE: RMSE in linear HDR is set by the brightest pixel (the focus), relMSE weighs
/// every pixel by its reference radiance. HDR-FLIP is the perceptual axis, over the
/// exposure bracket of the reference, so neither a dark receiver nor a clipped focus hides
/// an error.
pub fn error_axes() -> [ErrorAxis; 4] {
    [
        (
            "error",
            "relMSE of the surface caustic (pixel-averaged)",
            |r| r.errors.map(|e| e.rel_mse),
        ),
        (
            "hdr_flip",
            "HDR-FLIP of the surface caustic (pixel-averaged)",
            |r| r.errors.and_then(|e| e.hdr_flip),
        ),
        (
            "volume_error",
            "relMSE of the volume caustic (pixel-averaged)",
            |r| r.volume_errors.map(|e| e.rel_mse),
        ),
        (
            "volume_hdr_flip",
            "HDR-FLIP of the volume caustic (pixel-averaged)",
            |r| r.volume_errors.and_then(|e| e.hdr_flip),
        ),
    ]
}

/// The fill roofline's series: one set of points per method (its render passes that
/// rasterized anything), then the roof of the first run that has one, sampled across
/// the points' span. `None` when no run has a roofline with render passes.
fn fill_roofline_series<'r>(
    done: &[&'r Row],
    methods: &[String],
) -> Option<(Vec<Series>, Vec<&'r Row>)> {
    let mut series = Vec::new();
    let mut rows = Vec::new();
    let mut xs = Vec::new();
    for (i, m) in methods.iter().enumerate() {
        let mut pts = Vec::new();
        for r in done.iter().filter(|r| &r.method == m) {
            let Some(rl) = &r.roofline else { continue };
            let before = pts.len();
            pts.extend(
                rl.passes
                    .iter()
                    .filter(|p| crate::run::is_method_pass(&p.name, m))
                    .filter_map(|p| Some((p.fragments_per_primitive?, p.fragments_per_s? / 1e9)))
                    .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite()),
            );
            if pts.len() > before {
                rows.push(*r);
            }
        }
        if !pts.is_empty() {
            xs.extend(pts.iter().map(|p| p.0));
            series.push(Series::new(
                m.clone(),
                PALETTE[i % PALETTE.len()],
                pts,
                Style::Points,
            ));
        }
    }
    let roof = done
        .iter()
        .find_map(|r| r.roofline.as_ref()?.fill_roof.clone())?;
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min) / 2.0;
    let hi = xs.iter().copied().fold(0.0, f64::max) * 2.0;
    if series.is_empty() || !(lo > 0.0 && hi > lo) {
        return None;
    }
    let line: Vec<(f64, f64)> = (0..=48)
        .map(|k| {
            let x = lo * (hi / lo).powf(f64::from(k) / 48.0);
            (x, roof.at(x) / 1e9)
        })
        .collect();
    series.push(Series::new(
        format!("roof ({})", roof.probe),
        INK,
        line,
        Style::Dashed,
    ));
    Some((series, rows))
}

/// Writes the plots of `s` into `dir`; returns their paths relative to the summary.
pub fn write_plots(dir: &Path, s: &Summary) -> Result<Vec<String>> {
    let mut written = Vec::new();
    let done: Vec<&Row> = s.runs.iter().filter(|r| r.status == "done").collect();
    let mut methods: Vec<String> = Vec::new();
    for r in &done {
        if !methods.contains(&r.method) {
            methods.push(r.method.clone());
        }
    }
    let mut scenes: Vec<String> = Vec::new();
    for r in &done {
        if !scenes.contains(&r.scene) {
            scenes.push(r.scene.clone());
        }
    }
    let need = |written: &mut Vec<String>, name: String| -> Result<std::path::PathBuf> {
        std::fs::create_dir_all(dir)?;
        written.push(format!("plots/{name}"));
        Ok(dir.join(name))
    };
    for (stem, label, value) in error_axes() {
        for scene in &scenes {
            let mut series = Vec::new();
            let mut all = Vec::new();
            for (i, m) in methods.iter().enumerate() {
                let pts: Vec<(f64, f64)> = done
                    .iter()
                    .filter(|r| &r.scene == scene && &r.method == m)
                    .filter_map(|r| Some((r.method_gpu_ms?.median, value(r)?)))
                    .filter(|p| p.0.is_finite() && p.1.is_finite() && p.0 > 0.0 && p.1 >= 0.0)
                    .collect();
                if !pts.is_empty() {
                    all.extend(pts.iter().copied());
                    series.push(Series::new(
                        m.clone(),
                        PALETTE[i % PALETTE.len()],
                        pts,
                        Style::Points,
                    ));
                }
            }
            if all.is_empty() {
                continue;
            }
            series.push(Series::new(
                "pareto front",
                INK,
                pareto_front(&all),
                Style::Line,
            ));
            let path = need(
                &mut written,
                format!("{stem}_vs_time_{}.png", file_safe(scene)),
            )?;
            let of_scene: Vec<&Row> = done.iter().copied().filter(|r| &r.scene == scene).collect();
            scatter(
                &path,
                &Plot {
                    title: &format!("{}: {scene}: error against cost", s.experiment),
                    caption: &caption(s, &of_scene),
                    x: ("method GPU ms (median)", Scale::Log),
                    y: (label, scale_for(label, &[])),
                },
                &series,
            )?;
        }
        // Error against each numeric parameter swept over 3+ values, one line per method
        // and setting of the other parameters (e.g. relMSE against samples per strategy).
        for scene in &scenes {
            let runs: Vec<&Row> = done
                .iter()
                .copied()
                .filter(|r| &r.scene == scene && value(r).is_some())
                .collect();
            let mut names: Vec<&String> = runs.iter().flat_map(|r| r.params.keys()).collect();
            names.sort();
            names.dedup();
            for name in names {
                let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
                for r in &runs {
                    let (Some(x), Some(e)) =
                        (r.params.get(name).and_then(|v| v.as_f64()), value(r))
                    else {
                        continue;
                    };
                    if !e.is_finite() {
                        continue;
                    }
                    let mut rest: Vec<String> = r
                        .params
                        .iter()
                        .filter(|(k, _)| *k != name)
                        .map(|(k, v)| {
                            format!(
                                "{k}={}",
                                v.as_str().map(str::to_owned).unwrap_or(v.to_string())
                            )
                        })
                        .collect();
                    rest.insert(0, r.method.clone());
                    let label = rest.join(" ");
                    match lines.iter_mut().find(|l| l.0 == label) {
                        Some(l) => l.1.push((x, e)),
                        None => lines.push((label, vec![(x, e)])),
                    }
                }
                lines.retain(|l| l.1.len() >= 3);
                if lines.is_empty() {
                    continue;
                }
                let series: Vec<Series> = lines
                    .into_iter()
                    .enumerate()
                    .map(|(i, (label, mut pts))| {
                        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                        Series::new(label, PALETTE[i % PALETTE.len()], pts, Style::Line)
                    })
                    .collect();
                let path = need(
                    &mut written,
                    format!("{stem}_vs_{}_{}.png", file_safe(name), file_safe(scene)),
                )?;
                let xs: Vec<f64> = series
                    .iter()
                    .flat_map(|l| l.points.iter().map(|p| p.0))
                    .collect();
                scatter(
                    &path,
                    &Plot {
                        title: &format!("{}: {scene}: error against {name}", s.experiment),
                        caption: &caption(s, &runs),
                        x: (name, scale_for(&format!("param:{name}"), &xs)),
                        y: (label, scale_for(label, &[])),
                    },
                    &series,
                )?;
            }
        }
    }
    // The fill roofline: every method render pass at its fragments per primitive and
    // fragments per second, under the roof of the methods' target (additive RGBA32F).
    if let Some((series, caption_rows)) = fill_roofline_series(&done, &methods) {
        let path = need(&mut written, "roofline_fill.png".into())?;
        scatter(
            &path,
            &Plot {
                title: &format!(
                    "{}: fill roofline (method render passes against the adapter's fill ceiling)",
                    s.experiment
                ),
                caption: &caption(s, &caption_rows),
                x: ("fragments per primitive", Scale::Log),
                y: ("Gfragments/s (fragment-shader invocations)", Scale::Log),
            },
            &series,
        )?;
    }
    // Fill-rate heatmaps of every run of a scene side by side, on one colour scale.
    if let Some(root) = dir.parent() {
        for scene in &scenes {
            let panels: Vec<(String, Vec<u32>, u32, u32)> = done
                .iter()
                .filter(|r| &r.scene == scene)
                .filter_map(|r| {
                    // Runs made before `fill_counts.png` existed have no exact counts.
                    let p = root.join(r.dir.as_ref()?).join("fill_counts.png");
                    let (counts, w, h) = caustics_metrics::read_counts_png(&p).ok()?;
                    Some((run_label(r), counts, w, h))
                })
                .collect();
            if panels.len() < 2 {
                continue;
            }
            let counts: Vec<&[u32]> = panels.iter().map(|p| p.1.as_slice()).collect();
            for (log, name) in [(false, "heatmaps"), (true, "heatmaps_log")] {
                let options = HeatmapOptions::shared(&counts, log);
                let tiles = panels
                    .iter()
                    .map(|(label, c, w, h)| {
                        Ok((
                            label.clone(),
                            heatmap_with(c, *w, *h, "fragments/px", &options)?,
                        ))
                    })
                    .collect::<Result<Vec<_>>>()?;
                let path = need(&mut written, format!("{name}_{}.png", file_safe(scene)))?;
                let of_scene: Vec<&Row> =
                    done.iter().copied().filter(|r| &r.scene == scene).collect();
                tile(
                    &path,
                    &format!(
                        "{}: {scene}: fragments per pixel, one {} scale (0 to {})",
                        s.experiment,
                        if log { "log" } else { "linear" },
                        options.max.unwrap_or(0)
                    ),
                    &tiles,
                    &caption(s, &of_scene),
                )?;
            }
        }
    }
    let frags: Vec<(&Row, u64)> = done
        .iter()
        .filter_map(|r| Some((*r, r.fragments?)))
        .collect();
    if !frags.is_empty() {
        let path = need(&mut written, "fragments.png".into())?;
        fragments_plot(&path, &frags, &methods, &caption(s, &done))?;
    }
    // plots/ is output: a plot an earlier summary drew and this one does not (an RMSE
    // plot of before, a scene no longer run) would be shown by `caustics report` as if
    // it were current.
    if dir.is_dir() {
        for entry in std::fs::read_dir(dir)?.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            // An SVG stays with its PNG.
            let png = match name.strip_suffix(".svg") {
                Some(stem) => format!("{stem}.png"),
                None => name.clone(),
            };
            let ours = name.ends_with(".png") || name.ends_with(".svg");
            if ours && !written.contains(&format!("plots/{png}")) {
                std::fs::remove_file(entry.path())?;
            }
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fill_roofline_puts_method_passes_under_the_roof() {
        let mut beams = crate::summary::test_row("beams");
        beams.roofline = Some(crate::summary::test_roofline("beams"));
        let plain = crate::summary::test_row("splatting");
        let done = [&beams, &plain];
        let methods = ["beams".to_owned(), "splatting".to_owned()];
        let (series, rows) = fill_roofline_series(&done, &methods).expect("series");
        assert_eq!(rows.len(), 1, "only runs with a roofline");
        assert_eq!(series.len(), 2, "beams' points and the roof");
        // The base pass is left out: only beams/rasterize, at 100 fragments/primitive.
        assert_eq!(series[0].points, vec![(100.0, 0.1)]);
        let roof = &series[1];
        assert!(roof.name.contains("fill_blend_rgba32f_fullscreen"));
        let (x0, _) = roof.points[0];
        let (x1, y1) = *roof.points.last().expect("points");
        assert!((x0 - 50.0).abs() < 1e-9 && (x1 - 200.0).abs() < 1e-6);
        // 200 fragments per primitive: 200 / (100 ns + 200 / 2e9 s) = 1e9 per second.
        assert!((y1 - 1.0).abs() < 1e-9, "{y1}");
        assert!(fill_roofline_series(&[&plain], &methods[1..]).is_none());
    }
    use caustics_metrics::inferno;

    #[test]
    fn pareto_front_keeps_only_unbeaten_runs() {
        let f = pareto_front(&[(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (0.5, 9.0)]);
        assert_eq!(f, vec![(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
    }

    #[test]
    fn ticks_are_inside_the_axis_and_round() {
        let a = Axis::fit(&[0.0, 9.3], Scale::Linear);
        let t = a.ticks();
        assert!(
            t.len() >= 3 && t.iter().all(|v| *v >= a.lo && *v <= a.hi),
            "{t:?}"
        );
        assert!(t.contains(&2.0) || t.contains(&5.0), "{t:?}");
        let l = Axis::fit(&[0.01, 30.0], Scale::Log);
        assert!(l.log);
        assert!(l.ticks().contains(&1.0));
        // A log axis over less than a decade still gets three ticks or more.
        let narrow = Axis::fit(&[1500.0, 3100.0], Scale::Log);
        assert!(narrow.ticks().len() >= 3, "{:?}", narrow.ticks());
        assert_eq!(tick_label(500.0), "500");
        assert_eq!(tick_label(0.25), "0.25");
        assert_eq!(tick_label(1500.0), "1500");
        assert_eq!(tick_label(-0.5), "−0.5");
        assert_eq!(tick_label(1e-4), "10⁻⁴");
        assert_eq!(tick_label(2e-4), "2·10⁻⁴");
        assert_eq!(tick_label(3e6), "3·10⁶");
    }

    #[test]
    fn axis_scales_are_fixed_by_what_the_axis_shows() {
        // The same measure gets the same scale whatever range the data spans.
        for values in [&[1.0, 1.1][..], &[1.0, 1000.0]] {
            assert_eq!(scale_for("method GPU ms (median)", values), Scale::Log);
            assert_eq!(
                scale_for("relMSE of the surface caustic", values),
                Scale::Log
            );
            assert_eq!(scale_for("counter:beams", values), Scale::Log);
            assert_eq!(
                scale_for("HDR-FLIP of the surface caustic", values),
                Scale::Linear
            );
            assert_eq!(scale_for("flux_ratio", values), Scale::Linear);
        }
        // A parameter by its sweep: geometric goes log, evenly spaced stays linear.
        assert_eq!(
            scale_for("param:kernel_px", &[1.0, 2.0, 4.0, 8.0]),
            Scale::Log
        );
        assert_eq!(
            scale_for("param:levels", &[0.0, 1.0, 2.0, 3.0]),
            Scale::Linear
        );
        assert_eq!(scale_for("param:split_hit_rel", &[0.0, 0.1]), Scale::Linear);
        // Whole-numbered values tick on whole numbers only.
        let levels = Axis::fit(&[0.0, 1.0, 2.0, 3.0], Scale::Linear);
        assert!(
            levels.ticks().iter().all(|t| t.fract() == 0.0),
            "{:?}",
            levels.ticks()
        );
        assert!(levels.ticks().len() >= 3, "{:?}", levels.ticks());
        // A log axis of nothing positive falls back to linear rather than to nothing.
        assert!(!Axis::fit(&[0.0, 0.0], Scale::Log).log);
    }

    #[test]
    fn labels_wrap_at_spaces_to_the_width() {
        let long = "adaptive-beams bounces=2 max_beams=262144 tracer=bvh";
        let lines = wrap(long, 100);
        assert!(lines.len() >= 2, "{lines:?}");
        assert!(
            lines
                .iter()
                .all(|l| text_width(l) <= 100 || !l.contains(' ')),
            "{lines:?}"
        );
        assert_eq!(lines.join(" "), long);
    }

    #[test]
    fn a_scatter_plot_draws_points_text_and_a_whole_legend() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("p.png");
        let long = "adaptive, 3 levels, the oracle's relative hit bound swept";
        scatter(
            &p,
            &Plot {
                title: "title",
                caption: "llvmpipe · 64×48",
                x: ("x", Scale::Linear),
                y: ("y", Scale::Log),
            },
            &[
                Series::new("a", PALETTE[0], vec![(1.0, 2.0), (2.0, 1.0)], Style::Points),
                Series::new(long, PALETTE[1], vec![(1.0, 1.0), (2.0, 3.0)], Style::Line),
            ],
        )
        .expect("plot");
        let img = caustics_metrics::read_png(&p).expect("png");
        // The SVG beside it: vector marks, the labels and caption as text.
        let svg = std::fs::read_to_string(p.with_extension("svg")).expect("svg");
        assert!(
            svg.contains("<circle") && svg.contains("<polyline"),
            "no marks in the SVG"
        );
        for t in ["title", long, "llvmpipe · 64×48", "y (log)"] {
            assert!(
                svg.contains(&format!(">{t}</text>")),
                "{t:?} not in the SVG"
            );
        }
        // The legend's right margin holds its longest entry; the caption adds rows.
        assert!(img.width >= 510 + text_width(long) + 26, "{}", img.width);
        assert_eq!(img.height, 420 + CAPTION_H);
        assert!(img.pixels.contains(&PALETTE[0]), "no point drawn");
        assert!(img.pixels.contains(&INK), "no text or frame drawn");
        assert!(
            (420..img.height).any(|y| (0..img.width).any(|x| img.get(x, y) != [255; 3])),
            "no caption"
        );
    }

    fn row(dir: &str, method: &str, max: u32) -> Row {
        let mut r = crate::summary::test_row(method);
        r.width = 8;
        r.height = 4;
        r.dir = Some(dir.into());
        r.fill_max = Some(max);
        r
    }

    #[test]
    fn the_heatmap_panels_of_a_scene_share_one_colour_scale() {
        let tmp = tempfile::tempdir().expect("tempdir");
        // Run a's counts top out at 10, run b's at 100.
        for (d, max) in [("a", 10u32), ("b", 100)] {
            let counts: Vec<u32> = (0..32).map(|i| if i == 0 { max } else { i % 3 }).collect();
            std::fs::create_dir_all(tmp.path().join(d)).expect("mkdir");
            caustics_metrics::write_counts_png(
                &tmp.path().join(d).join("fill_counts.png"),
                &counts,
                8,
                4,
            )
            .expect("png");
        }
        let s = crate::summary::test_summary(vec![row("a", "m1", 10), row("b", "m2", 100)]);
        std::fs::create_dir_all(tmp.path().join("plots")).expect("mkdir");
        std::fs::write(tmp.path().join("plots/error_vs_time_old.png"), b"stale").expect("write");
        let written = write_plots(&tmp.path().join("plots"), &s).expect("plots");
        assert!(
            !tmp.path().join("plots/error_vs_time_old.png").exists(),
            "a plot of an earlier summary stays"
        );
        assert!(
            written.contains(&"plots/heatmaps_s.png".to_owned())
                && written.contains(&"plots/heatmaps_log_s.png".to_owned()),
            "{written:?}"
        );
        // Own scales: both runs' maxima are the top colour. Shared: only b's is.
        let top = inferno(1.0);
        let img =
            caustics_metrics::read_png(&tmp.path().join("plots/heatmaps_s.png")).expect("png");
        let cell_w = 8 + caustics_metrics::COLOR_BAR_WIDTH + 8;
        let label_h = wrap(&run_label(&s.runs[0]), cell_w - 8).len() as u32 * LINE_H;
        let (a, b) = (img.get(8, 22 + label_h), img.get(8 + cell_w, 22 + label_h));
        assert_eq!(b, top, "b's maximum tops the shared scale");
        assert_eq!(a, inferno(0.1), "a's maximum of 10 is a tenth of it");
    }
}
