//! The figures an experiment declares ([`crate::figure_spec`]), drawn from its summary
//! rows into `<experiment>/figures/<name>.png`, with the numbers behind them (fits,
//! ratios, tables) as [`DrawnFigure`]s that `summary.md`, `summary.json` and the report
//! show. Only done runs are drawn; a figure with none says so instead of failing.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use caustics_metrics::{Rgb8Image, ToneMap, draw_text, text_width};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use crate::experiment::Experiment;
use crate::figure_spec::{
    Column, Defaults, Figure, Key, Kind, Measure, RunInfo, distinguishing, grid, labels, pairs,
    value_text,
};
use crate::plots::{
    GUIDE, INK, PALETTE, Plot, Scale, Series, Style, colour, plot_err, scale_for, scatter,
};
use crate::summary::{Row, Summary, num};

/// One declared figure as drawn.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DrawnFigure {
    /// Its name (file stem).
    pub name: String,
    /// `image_grid`, `line`, `ratio` or `table`.
    pub kind: String,
    /// Heading.
    pub title: String,
    /// The declaration's caption.
    pub caption: String,
    /// `figures/<name>.png`, relative to the experiment folder (none for a table, or
    /// when nothing could be drawn).
    pub file: Option<String>,
    /// What the figure shows, in sentences: layout, fits, ratios, what is missing.
    pub notes: Vec<String>,
    /// The numbers (tables and ratios).
    pub table: Option<FigureTable>,
}

/// A table of text cells.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FigureTable {
    /// Column heads.
    pub head: Vec<String>,
    /// Rows of cells, as many as heads.
    pub rows: Vec<Vec<String>>,
}

/// A run's value of a measure; `None` when the run does not have it. `pass:` sums the
/// passes the run has of those named (`<method>/<name>`, or a full name with `/`).
pub fn measure_value(m: &Measure, row: &Row, run: &RunInfo) -> Option<f64> {
    let passes = |names: &[String], get: &dyn Fn(&str) -> Option<f64>| -> Option<f64> {
        let v: Vec<f64> = names
            .iter()
            .filter_map(|n| {
                if n.contains('/') {
                    get(n)
                } else {
                    get(&format!("{}/{n}", row.method))
                }
            })
            .collect();
        (!v.is_empty()).then(|| v.iter().sum())
    };
    let v = match m {
        Measure::Named(n) => row.measure(n),
        Measure::Counter(c) => row.counters.get(c).map(|&v| v as f64),
        Measure::Pass(p) => passes(p, &|n| row.pass_gpu_ms.get(n).map(|s| s.median)),
        Measure::PassFragments(p) => passes(p, &|n| row.pass_fragments.get(n).map(|&v| v as f64)),
        Measure::Param(p) => run.params.get(p).and_then(serde_json::Value::as_f64),
    };
    v.filter(|v| v.is_finite())
}

/// Draws every figure of `e` from the done runs of `s` into `<dir>/figures/` (PNGs of
/// an earlier summary that this one does not draw are removed).
pub fn draw(
    dir: &Path,
    e: &Experiment,
    s: &Summary,
    references: &Path,
) -> Result<Vec<DrawnFigure>> {
    let mut defaults = Defaults::default();
    let done: Vec<(&Row, RunInfo)> = s
        .runs
        .iter()
        .filter(|r| r.status == "done")
        .filter_map(|r| {
            let spec = e.runs.get(r.index).filter(|spec| spec.key() == r.key)?;
            Some((r, defaults.run(spec)))
        })
        .collect();
    let fig_dir = dir.join("figures");
    let mut out = Vec::new();
    for f in &e.figures {
        let runs: Vec<&(&Row, RunInfo)> = done.iter().filter(|(_, i)| f.selects(i)).collect();
        let mut d = DrawnFigure {
            name: f.name.clone(),
            kind: f.kind.name().into(),
            title: f.title.clone(),
            caption: f.caption.clone(),
            file: None,
            notes: Vec::new(),
            table: None,
        };
        if runs.is_empty() {
            d.notes
                .push("none of the figure's runs is done: nothing to draw".into());
            out.push(d);
            continue;
        }
        let png = fig_dir.join(format!("{}.png", f.name));
        let rows: Vec<&Row> = runs.iter().map(|r| r.0).collect();
        let caption = crate::plots::caption(s, &rows);
        let drew = match &f.kind {
            Kind::ImageGrid { .. } => {
                let place = Place {
                    png: &png,
                    caption: &caption,
                };
                image_grid(dir, e, f, &runs, references, &place, &mut d)?
            }
            Kind::Line { .. } => line(f, &runs, &done, &png, &caption, &mut d)?,
            Kind::Ratio { .. } => ratio(f, &runs, &png, &caption, &mut d)?,
            Kind::Table { columns } => {
                d.table = Some(table(columns, &runs));
                false
            }
        };
        if drew {
            d.file = Some(format!("figures/{}.png", f.name));
        }
        out.push(d);
    }
    if fig_dir.is_dir() {
        for entry in std::fs::read_dir(&fig_dir)?.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            // An SVG stays with its PNG.
            let png = match name.strip_suffix(".svg") {
                Some(stem) => format!("{stem}.png"),
                None => name.clone(),
            };
            let kept = out
                .iter()
                .any(|d| d.file.as_deref() == Some(&format!("figures/{png}")));
            if (name.ends_with(".png") || name.ends_with(".svg")) && !kept {
                std::fs::remove_file(entry.path())?;
            }
        }
    }
    Ok(out)
}

/// A grey image with a word on it, where a run's image is missing.
fn placeholder(w: u32, h: u32, text: &str) -> Rgb8Image {
    let mut img = Rgb8Image::filled(w, h, [200; 3]);
    draw_text(&mut img, 2, h / 2, text, INK);
    img
}

/// Nearest-neighbour enlargement by an integer factor.
fn enlarge(img: &Rgb8Image, k: u32) -> Rgb8Image {
    if k <= 1 {
        return img.clone();
    }
    let mut out = Rgb8Image::new(img.width * k, img.height * k);
    for y in 0..out.height {
        for x in 0..out.width {
            out.set(x, y, img.get(x / k, y / k));
        }
    }
    out
}

/// Where a figure goes and what stands under it.
struct Place<'a> {
    png: &'a Path,
    caption: &'a str,
}

fn image_grid(
    dir: &Path,
    e: &Experiment,
    f: &Figure,
    runs: &[&(&Row, RunInfo)],
    references: &Path,
    place: &Place<'_>,
    d: &mut DrawnFigure,
) -> Result<bool> {
    let png = place.png;
    let Kind::ImageGrid {
        rows,
        cols,
        image,
        reference,
    } = &f.kind
    else {
        return Ok(false);
    };
    let infos: Vec<&RunInfo> = runs.iter().map(|r| &r.1).collect();
    let g = grid(rows, cols, &infos, &f.select)
        .map_err(|m| anyhow::anyhow!("figure {}: {m}", f.name))?;
    let mut images: BTreeMap<(usize, usize), (String, Option<Rgb8Image>)> = BTreeMap::new();
    for (row, col, pos, label) in &g.cells {
        let r = runs[*pos].0;
        let img = r
            .dir
            .as_ref()
            .map(|rel| dir.join(rel).join(format!("{image}.png")))
            .filter(|p| p.is_file())
            .map(|p| {
                caustics_metrics::read_png(&p).with_context(|| format!("reading {}", p.display()))
            })
            .transpose()?;
        if img.is_none() {
            d.notes.push(format!("{}: no {image}.png", r.key));
        }
        images.insert((*row, *col), (label.clone(), img));
    }
    let n_cols = g.cells.iter().map(|c| c.1 + 1).max().unwrap_or(1);
    // The reference's caustic at each row's exposure, as a last column.
    let mut ref_col = false;
    if *reference {
        for (row, label) in g.rows.iter().enumerate() {
            let Some((_, _, pos, _)) = g.cells.iter().find(|c| c.0 == row) else {
                continue;
            };
            let (r, info) = runs[*pos];
            let Some(spec) = e.runs.get(info.index) else {
                continue;
            };
            match crate::references::find(references, &spec.scene)? {
                Some(c) => {
                    let mut img = caustics_metrics::read_exr(&c.caustic())?;
                    if let Some(v) = c.volume() {
                        img = img.add(&caustics_metrics::read_exr(&v)?)?;
                    }
                    let tone = ToneMap::new(r.exposure_scale.unwrap_or(1.0));
                    images.insert((row, n_cols), ("reference".into(), Some(tone.apply(&img))));
                    ref_col = true;
                }
                None => d.notes.push(format!(
                    "no reference of {} at {}x{} in {}: row {label:?} has no reference column",
                    spec.scene.name,
                    spec.scene.camera.width,
                    spec.scene.camera.height,
                    references.display()
                )),
            }
        }
    }
    let total_cols = n_cols + usize::from(ref_col);
    let (w0, h0) = images
        .values()
        .filter_map(|(_, i)| i.as_ref().map(|i| (i.width, i.height)))
        .fold((0, 0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    let (w0, h0) = if w0 == 0 { (64, 48) } else { (w0, h0) };
    // Small runs (a 64x48 quick pass) are enlarged so that a caustic can be seen.
    let k = (192 / w0).clamp(1, 8);
    let (cw, ch) = (w0 * k, h0 * k);
    let gap = 6;
    let row_w = g.rows.iter().map(|l| text_width(l)).max().unwrap_or(0);
    let row_w = if row_w > 0 { row_w + 10 } else { 0 };
    // Cell labels wrap at spaces to the image's width (a long parameter set takes lines,
    // not the width of the figure).
    let cell_w = cw + gap;
    let wrapped: BTreeMap<(usize, usize), Vec<String>> = images
        .iter()
        .map(|(k, (l, _))| (*k, crate::plots::wrap(l, cw)))
        .collect();
    let label_h = wrapped.values().map(Vec::len).max().unwrap_or(1) as u32 * crate::plots::LINE_H;
    let cell_h = ch + label_h + gap;
    let title_h = 20;
    let width = (8 + row_w + total_cols as u32 * cell_w + 8).max(text_width(&f.title) + 16);
    let height = title_h + g.rows.len() as u32 * cell_h + 8;
    let mut img = Rgb8Image::filled(width, height, [255; 3]);
    draw_text(&mut img, 8, 6, &f.title, INK);
    for (row, label) in g.rows.iter().enumerate() {
        let y0 = title_h + row as u32 * cell_h;
        draw_text(&mut img, 8, y0 + label_h + ch / 2, label, INK);
        for col in 0..total_cols {
            let Some((_, tile)) = images.get(&(row, col)) else {
                continue;
            };
            let x0 = 8 + row_w + col as u32 * cell_w;
            let lines = wrapped.get(&(row, col)).map_or(&[][..], Vec::as_slice);
            for (k, line) in lines.iter().enumerate() {
                draw_text(
                    &mut img,
                    x0,
                    y0 + 2 + k as u32 * crate::plots::LINE_H,
                    line,
                    INK,
                );
            }
            let tile = match tile {
                Some(t) => enlarge(t, k),
                None => placeholder(cw, ch, "missing"),
            };
            for y in 0..tile.height.min(ch) {
                for x in 0..tile.width.min(cw) {
                    img.set(x0 + x, y0 + label_h + y, tile.get(x, y));
                }
            }
        }
    }
    std::fs::create_dir_all(png.parent().unwrap_or(Path::new(".")))?;
    caustics_metrics::write_png(png, &crate::plots::with_caption(&img, place.caption))?;
    let layout = match &g.cols {
        Some(c) => format!(
            "rows: {}; columns: {}{}",
            if rows.is_empty() {
                "one".into()
            } else {
                g.rows.join(", ")
            },
            c.join(", "),
            if ref_col { ", reference" } else { "" }
        ),
        None => format!(
            "rows: {}; each row's runs in experiment order{}",
            if rows.is_empty() {
                "one".into()
            } else {
                g.rows.join(", ")
            },
            if ref_col { ", then the reference" } else { "" }
        ),
    };
    d.notes.push(format!(
        "{image}.png of each run ({layout}){}{}",
        if image == "caustic" {
            "; surface + volume caustic, tone-mapped at the run's exposure (one per scene: the reference's 99th percentile at white unless the experiment sets one)"
        } else {
            ""
        },
        if k > 1 { format!("; enlarged {k}x") } else { String::new() }
    ));
    Ok(true)
}

fn line(
    f: &Figure,
    runs: &[&(&Row, RunInfo)],
    all: &[(&Row, RunInfo)],
    png: &Path,
    caption: &str,
    d: &mut DrawnFigure,
) -> Result<bool> {
    let Kind::Line {
        x,
        y,
        series,
        relative_to,
        fit,
    } = &f.kind
    else {
        return Ok(false);
    };
    // Per scene, the smallest y among the baseline runs.
    let base: Option<BTreeMap<&str, f64>> = relative_to.as_ref().map(|sel| {
        let mut m: BTreeMap<&str, f64> = BTreeMap::new();
        for (r, i) in all.iter().filter(|(_, i)| sel.iter().any(|s| s.matches(i))) {
            if let Some(v) = measure_value(y, r, i).filter(|v| *v > 0.0) {
                let e = m.entry(i.scene.as_str()).or_insert(v);
                *e = e.min(v);
            }
        }
        m
    });
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut skipped = Vec::new();
    for (r, i) in runs {
        let xv = measure_value(x, r, i);
        let mut yv = measure_value(y, r, i);
        if let Some(b) = &base {
            yv = yv.and_then(|v| b.get(i.scene.as_str()).map(|b| v / b));
        }
        let (Some(xv), Some(yv)) = (xv, yv) else {
            skipped.push(r.key.clone());
            continue;
        };
        let label = labels(series, i);
        let label = if label.is_empty() {
            "all runs".into()
        } else {
            label
        };
        match lines.iter_mut().find(|l| l.0 == label) {
            Some(l) => l.1.push((xv, yv)),
            None => lines.push((label, vec![(xv, yv)])),
        }
    }
    if !skipped.is_empty() {
        d.notes.push(format!(
            "left out (no {x} or {y}{}): {}",
            if base.is_some() {
                ", or no baseline"
            } else {
                ""
            },
            skipped.join(", ")
        ));
    }
    if lines.is_empty() {
        return Ok(false);
    }
    let mut drawn: Vec<Series> = lines
        .iter()
        .enumerate()
        .map(|(i, (label, pts))| {
            let mut pts = pts.clone();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let style = if pts.len() > 1 {
                Style::Line
            } else {
                Style::Points
            };
            Series::new(label.clone(), PALETTE[i % PALETTE.len()], pts, style)
        })
        .collect();
    let points: Vec<(f64, f64)> = lines.iter().flat_map(|l| l.1.iter().copied()).collect();
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.0), a.1.max(p.0))
        });
    if relative_to.is_some() {
        drawn.push(Series::new(
            "1 = the baseline",
            GUIDE,
            vec![(lo, 1.0), (hi, 1.0)],
            Style::Dashed,
        ));
        d.notes.push(format!(
            "y: each run's {y} divided by the smallest {y} among the `relative_to` runs of its scene (below 1: better than the best of them where {y} is an error or a cost)"
        ));
    }
    if *fit {
        match least_squares(&points) {
            Some((a, b, r2)) => {
                let n = 48;
                let pts: Vec<(f64, f64)> = (0..=n)
                    .map(|k| {
                        let t = lo + (hi - lo) * k as f64 / n as f64;
                        (t, a + b * t)
                    })
                    .collect();
                drawn.push(Series::new("least squares", GUIDE, pts, Style::Dashed));
                d.notes.push(format!(
                    "least squares over the {} points: {y} = {} + {} × {x}, R² = {:.4}",
                    points.len(),
                    num(a),
                    num(b),
                    r2
                ));
            }
            None => d
                .notes
                .push("no least-squares fit: fewer than two distinct x".into()),
        }
    }
    let y_label = if base.is_some() {
        format!("{y} / the baseline's")
    } else {
        y.to_string()
    };
    std::fs::create_dir_all(png.parent().unwrap_or(Path::new(".")))?;
    let (x_name, y_name) = (x.to_string(), y.to_string());
    let xs: Vec<f64> = drawn
        .iter()
        .flat_map(|d| d.points.iter().map(|p| p.0))
        .collect();
    let ys: Vec<f64> = drawn
        .iter()
        .flat_map(|d| d.points.iter().map(|p| p.1))
        .collect();
    // A quotient of two runs' figures is a ratio whatever it divides: linear.
    let y_scale = if base.is_some() {
        Scale::Linear
    } else {
        scale_for(&y_name, &ys)
    };
    scatter(
        png,
        &Plot {
            title: &f.title,
            caption,
            x: (&x_name, scale_for(&x_name, &xs)),
            y: (&y_label, y_scale),
        },
        &drawn,
    )?;
    Ok(true)
}

/// y = a + b·x by least squares, with R²; `None` without two distinct x.
pub fn least_squares(p: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let n = p.len() as f64;
    let (mx, my) = p
        .iter()
        .fold((0.0, 0.0), |a, q| (a.0 + q.0 / n, a.1 + q.1 / n));
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    let syy: f64 = p.iter().map(|q| (q.1 - my).powi(2)).sum();
    if p.len() < 2 || sxx <= 0.0 {
        return None;
    }
    let b = sxy / sxx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    Some((my - b * mx, b, r2))
}

fn ratio(
    f: &Figure,
    runs: &[&(&Row, RunInfo)],
    png: &Path,
    caption: &str,
    d: &mut DrawnFigure,
) -> Result<bool> {
    let Kind::Ratio {
        of,
        numerator,
        denominator,
        measures,
    } = &f.kind
    else {
        return Ok(false);
    };
    let infos: Vec<&RunInfo> = runs.iter().map(|r| &r.1).collect();
    let p = pairs(of, numerator, denominator, &infos)
        .map_err(|m| anyhow::anyhow!("figure {}: {m}", f.name))?;
    // Pairs are told apart by what varies among their numerator sides.
    let numerators: Vec<&RunInfo> = p.iter().map(|(i, _)| infos[*i]).collect();
    let dist = distinguishing(&numerators, std::slice::from_ref(of));
    let side = |v: &serde_json::Value| match of {
        Key::Param(p) => format!("{p}={}", value_text(v)),
        _ => value_text(v),
    };
    let (num_label, den_label) = (side(numerator), side(denominator));
    let mut rows = Vec::new();
    let mut bars = Vec::new();
    for (i, j) in &p {
        let (rn, ni) = runs[*i];
        let (rd, di) = runs[*j];
        let pair = labels(&dist, ni);
        let pair = if pair.is_empty() {
            ni.scene.clone()
        } else {
            pair
        };
        let mut said = Vec::new();
        for (mi, m) in measures.iter().enumerate() {
            let (a, b) = (measure_value(m, rn, ni), measure_value(m, rd, di));
            let q = match (a, b) {
                (Some(a), Some(b)) if b != 0.0 => Some(a / b),
                _ => None,
            };
            rows.push(vec![
                pair.clone(),
                m.to_string(),
                a.map(cell).unwrap_or("–".into()),
                b.map(cell).unwrap_or("–".into()),
                q.map(ratio_text).unwrap_or("–".into()),
            ]);
            if let Some(q) = q.filter(|q| *q > 0.0) {
                said.push(format!("{m} {}×", ratio_text(q)));
                bars.push((format!("{pair}: {m}"), q, PALETTE[mi % PALETTE.len()]));
            }
        }
        d.notes.push(format!(
            "{pair}: {num_label} ÷ {den_label}: {}",
            if said.is_empty() {
                "no measure on both sides".into()
            } else {
                said.join(", ")
            }
        ));
        // Time ratios hold only if the machine stayed the same between the two runs:
        // the harness's own passes are the same work in both, so their ratio is
        // what the machine changed (or what one method's memory traffic cost the
        // other passes), beside every time ratio of the pair.
        let same_work = rn.scene == rd.scene && (rn.width, rn.height) == (rd.width, rd.height);
        if same_work && measures.iter().any(is_time) {
            let (a, b) = (base_gpu_ms(rn), base_gpu_ms(rd));
            if let (Some(a), Some(b)) = (a, b) {
                let q = a / b;
                rows.push(vec![
                    pair.clone(),
                    BASE_PASSES.into(),
                    cell(a),
                    cell(b),
                    ratio_text(q),
                ]);
                if !(1.0 / DRIFT_BOUND..=DRIFT_BOUND).contains(&q) {
                    d.notes.push(format!(
                        "{pair}: the harness's own passes, the same work in both runs, took {}× as long in the {num_label} run (the machine drifted between the two, or one method's memory traffic slowed the passes around it): its time ratios are uncertain by as much",
                        ratio_text(q)
                    ));
                }
            }
        }
    }
    d.table = Some(FigureTable {
        head: vec![
            "pair".into(),
            "measure".into(),
            num_label.clone(),
            den_label.clone(),
            "ratio".into(),
        ],
        rows,
    });
    if bars.is_empty() {
        return Ok(false);
    }
    ratio_bars(png, &f.title, &bars, caption)?;
    Ok(true)
}

/// The ratio table's row of the harness's own passes.
const BASE_PASSES: &str = "base passes (same work)";

/// How far the base passes' ratio may stray from 1 before a ratio figure says that its
/// time ratios are uncertain by as much.
const DRIFT_BOUND: f64 = 1.1;

/// Whether a measure is a time (or a rate from one).
fn is_time(m: &Measure) -> bool {
    match m {
        Measure::Pass(_) => true,
        Measure::Named(n) => ["method_gpu_ms", "frame_gpu_ms", "fps"].contains(&n.as_str()),
        _ => false,
    }
}

/// The summed median GPU ms of the harness's own passes (`base/…`: clearing the
/// targets, the camera G-buffer, the shadow map, direct light), the same work in every
/// run of a scene at one resolution whatever the method.
fn base_gpu_ms(row: &Row) -> Option<f64> {
    let v: Vec<f64> = row
        .pass_gpu_ms
        .iter()
        .filter(|(name, _)| name.starts_with("base/"))
        .map(|(_, s)| s.median)
        .collect();
    (!v.is_empty()).then(|| v.iter().sum())
}

/// A ratio with three decimals, or three significant digits when far from 1.
fn ratio_text(q: f64) -> String {
    if (1e-3..1e4).contains(&q.abs()) {
        format!("{q:.3}")
    } else {
        format!("{q:.3e}")
    }
}

/// Horizontal bars of ratios about a centre line at 1, log scale (a ratio of 2 and one
/// of ½ are bars of one length), each with its value.
fn ratio_bars(
    path: &Path,
    title: &str,
    bars: &[(String, f64, [u8; 3])],
    caption: &str,
) -> Result<()> {
    let label_w = bars
        .iter()
        .map(|b| text_width(&b.0) as i32)
        .max()
        .unwrap_or(0)
        + 16;
    std::fs::create_dir_all(path.parent().unwrap_or(Path::new(".")))?;
    crate::plots::render(
        path,
        &RatioBars {
            title,
            bars,
            label_w,
        },
        caption,
    )
}

/// The shapes of [`ratio_bars`].
struct RatioBars<'a> {
    title: &'a str,
    bars: &'a [(String, f64, [u8; 3])],
    label_w: i32,
}

impl RatioBars<'_> {
    const BAR_H: i32 = 12;
    const HALF: i32 = 220;
}

impl crate::plots::Shapes for RatioBars<'_> {
    fn size(&self) -> (u32, u32) {
        (
            (self.label_w + 2 * Self::HALF + 70).max(text_width(self.title) as i32 + 16) as u32,
            (44 + self.bars.len() as i32 * (Self::BAR_H + 4) + 24) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<crate::plots::Labels> {
        let (bar_h, half, label_w, bars) = (Self::BAR_H, Self::HALF, self.label_w, self.bars);
        let span = bars
            .iter()
            .map(|b| b.1.log10().abs())
            .fold(1.25f64.log10(), f64::max);
        let centre = label_w + half;
        let mut text: crate::plots::Labels = vec![(8, 8, self.title.to_owned(), false)];
        root.fill(&WHITE).map_err(plot_err)?;
        let top = 30;
        for (i, (label, q, c)) in bars.iter().enumerate() {
            let y = top + i as i32 * (bar_h + 4);
            let len = ((q.log10() / span) * half as f64).round() as i32;
            let (x0, x1) = if len >= 0 {
                (centre, centre + len.max(1))
            } else {
                (centre + len, centre)
            };
            root.draw(&Rectangle::new(
                [(x0, y), (x1, y + bar_h)],
                colour(*c).filled(),
            ))
            .map_err(plot_err)?;
            text.push((8, y + 2, label.clone(), false));
            let v = ratio_text(*q);
            let tx = if len >= 0 {
                x1 + 4
            } else {
                x0 - 4 - text_width(&v) as i32
            };
            text.push((tx, y + 2, v, false));
        }
        let bottom = top + bars.len() as i32 * (bar_h + 4);
        root.draw(&PathElement::new(
            vec![(centre, top - 4), (centre, bottom)],
            colour(INK),
        ))
        .map_err(plot_err)?;
        let lo = ratio_text(10f64.powf(-span));
        let hi = ratio_text(10f64.powf(span));
        text.push((
            centre - half - text_width(&lo) as i32 / 2,
            bottom + 6,
            lo,
            false,
        ));
        text.push((centre - 2, bottom + 6, "1".into(), false));
        text.push((
            centre + half - text_width(&hi) as i32 / 2,
            bottom + 6,
            hi,
            false,
        ));
        Ok(text)
    }
}

/// A number in a table: counts as integers, others as [`num`] writes them.
fn cell(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        num(v)
    }
}

fn table(columns: &[Column], runs: &[&(&Row, RunInfo)]) -> FigureTable {
    let mut head = vec!["scene".to_owned(), "method".to_owned(), "params".to_owned()];
    head.extend(columns.iter().map(Column::to_string));
    let rows = runs
        .iter()
        .map(|(r, i)| {
            let mut cells = vec![
                r.scene.clone(),
                r.method.clone(),
                if r.params.is_empty() {
                    "defaults".into()
                } else {
                    r.params
                        .iter()
                        .map(|(k, v)| format!("{k}={}", value_text(v)))
                        .collect::<Vec<_>>()
                        .join(" ")
                },
            ];
            cells.extend(columns.iter().map(|c| match c {
                Column::Key(k) => k.value(i).map(|v| value_text(&v)).unwrap_or("–".into()),
                Column::Measure(m) => measure_value(m, r, i).map(cell).unwrap_or("–".into()),
            }));
            cells
        })
        .collect();
    FigureTable { head, rows }
}

/// The `## Figures` section of `summary.md` (empty without figures).
pub fn markdown(figures: &[DrawnFigure]) -> String {
    let mut md = String::new();
    if figures.is_empty() {
        return md;
    }
    let _ = writeln!(md, "## Figures\n");
    for f in figures {
        let _ = writeln!(md, "### {}\n", f.title);
        if !f.caption.is_empty() {
            let _ = writeln!(md, "{}\n", f.caption);
        }
        if let Some(file) = &f.file {
            let _ = writeln!(md, "![{}]({file})\n", f.name);
        }
        for n in &f.notes {
            let _ = writeln!(md, "- {n}");
        }
        if !f.notes.is_empty() {
            let _ = writeln!(md);
        }
        if let Some(t) = &f.table {
            let cell = |s: &String| s.replace('|', "/");
            let _ = writeln!(
                md,
                "| {} |",
                t.head.iter().map(cell).collect::<Vec<_>>().join(" | ")
            );
            let _ = writeln!(md, "|{}", "---|".repeat(t.head.len()));
            for r in &t.rows {
                let _ = writeln!(
                    md,
                    "| {} |",
                    r.iter().map(cell).collect::<Vec<_>>().join(" | ")
                );
            }
            let _ = writeln!(md);
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::summary::{Spread, test_row};
    use caustics_metrics::HdrImage;

    const EXPERIMENT: &str = r#"{
      "name": "synthetic", "resolution": {"width": 16, "height": 12}, "frames": 1, "warmup": 0,
      "runs": [{"label": "sweep", "scenes": ["ring"], "methods": ["pinhole"],
                "params": {"sampling": ["random", "grid"], "samples": [100, 1000], "filtering": ["off", "full"]}}],
      "figures": [
        {"name": "grid", "kind": "image_grid", "where": {"params": {"filtering": "full", "sampling": ["grid", "random"]}},
         "rows": "param:sampling", "cols": "param:samples", "reference": true},
        {"name": "time", "kind": "line", "x": "counter:sample_pixel_pairs", "y": "method_gpu_ms",
         "series": "param:filtering", "fit": "linear"},
        {"name": "relative", "kind": "line", "x": "param:samples", "y": "rel_mse", "series": "param:sampling",
         "where": {"params": {"filtering": "off"}}, "relative_to": {"params": {"filtering": "full"}}},
        {"name": "filter", "kind": "ratio", "of": "param:filtering", "numerator": "full", "denominator": "off",
         "measures": ["method_gpu_ms", "rel_mse"]},
        {"name": "numbers", "kind": "table", "columns": ["param:sampling", "counter:samples", "pass:gather+prepare_samples"]}
      ]}"#;

    /// The colour of run `i`'s caustic.png.
    fn shade(i: usize) -> [u8; 3] {
        [40 + 20 * i as u8, 200 - 20 * i as u8, 90]
    }

    /// The experiment above with synthetic results: run i's time is 1 ms + 1 µs per
    /// sample-pixel pair (twice that with filtering full), its relMSE 1/samples (half
    /// that with filtering full), its caustic.png one colour.
    fn synthetic(dir: &Path, refs: &Path) -> (Experiment, Summary) {
        std::fs::create_dir_all(dir).expect("mkdir");
        let file = dir.join("synthetic.json");
        std::fs::write(&file, EXPERIMENT).expect("write");
        let e = Experiment::load(&file, 1.0).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(e.runs.len(), 8);
        let mut rows = Vec::new();
        for spec in &e.runs {
            let i = spec.index;
            let mut r = test_row("pinhole");
            r.index = i;
            r.key = spec.key();
            r.group = spec.group.clone();
            r.scene = "ring".into();
            r.params = spec.params.clone();
            r.width = 16;
            r.height = 12;
            r.dir = Some(format!("runs/{i}"));
            r.exposure_scale = Some(1.0);
            let samples = spec.params["samples"].as_u64().expect("samples");
            let full = spec.params["filtering"] == "full";
            let k = if full { 2.0 } else { 1.0 };
            let pairs = samples * 10;
            r.counters.insert("samples".into(), samples);
            r.counters.insert("sample_pixel_pairs".into(), pairs);
            let ms = k * (1.0 + 1e-3 * pairs as f64);
            r.method_gpu_ms = Some(Spread {
                median: ms,
                p10: ms,
                p90: ms,
            });
            // The harness's passes: 10 ms, but 13 ms in one run (full, 1000, random):
            // the machine slowed down while it ran.
            let slow = full && samples == 1000 && spec.params["sampling"] == "random";
            let base_ms = if slow { 13.0 } else { 10.0 };
            for (p, v) in [
                ("pinhole/gather", 0.75 * ms),
                ("pinhole/prepare_samples", 0.25 * ms),
                ("base/shadow_map", 0.5 * base_ms),
                ("base/direct", 0.5 * base_ms),
            ] {
                r.pass_gpu_ms.insert(
                    p.into(),
                    Spread {
                        median: v,
                        p10: v,
                        p90: v,
                    },
                );
            }
            let mut errors: caustics_metrics::Errors =
                serde_json::from_value(serde_json::json!({"rmse": 0.1, "rel_mse": 1.0 / (k * samples as f64),
                    "psnr_db": 30.0, "ssim": 0.9, "flip": 0.1, "best_scale": 1.0, "rmse_after_best_scale": 0.1}))
                .expect("errors");
            errors.hdr_flip = Some(0.1);
            r.errors = Some(errors);
            r.score_spp = Some(16);
            let run = dir.join(format!("runs/{i}"));
            std::fs::create_dir_all(&run).expect("mkdir");
            caustics_metrics::write_png(
                &run.join("caustic.png"),
                &Rgb8Image::filled(16, 12, shade(i)),
            )
            .expect("png");
            rows.push(r);
        }
        // A cached reference of ring at 16x12: radiance 0.5 everywhere.
        let scene = &e.runs[0].scene;
        let cache = crate::references::cache_dir(refs, scene);
        std::fs::create_dir_all(&cache).expect("mkdir");
        let mut img = HdrImage::new(16, 12);
        for p in &mut img.pixels {
            *p = [0.5; 3];
        }
        caustics_metrics::write_exr(&cache.join("caustic.exr"), &img).expect("exr");
        caustics_metrics::write_exr(&cache.join("stderr.exr"), &HdrImage::new(16, 12))
            .expect("exr");
        let meta = crate::references::ReferenceMeta {
            schema_version: 2,
            transport_version: caustics_reference::TRANSPORT_VERSION,
            scene: scene.name.clone(),
            scene_hash: scene.hash_hex(),
            width: 16,
            height: 12,
            photons: 1,
            seconds: 1.0,
            photons_per_second: 1.0,
            seed: 1,
            batches: 2,
            commit: "test".into(),
            relative_stderr: 0.0,
            time_s: None,
        };
        std::fs::write(
            cache.join("meta.json"),
            serde_json::to_vec(&meta).expect("json"),
        )
        .expect("meta");
        let s = Summary {
            experiment: "synthetic".into(),
            ..crate::summary::test_summary(rows)
        };
        (e, s)
    }

    #[test]
    fn declared_figures_are_drawn_from_synthetic_runs() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let (dir, refs) = (tmp.path().join("exp"), tmp.path().join("refs"));
        std::fs::create_dir_all(dir.join("figures")).expect("mkdir");
        std::fs::write(dir.join("figures/stale.png"), b"old").expect("write");
        let (e, s) = synthetic(&dir, &refs);
        let figs = draw(&dir, &e, &s, &refs).expect("draw");
        let by = |n: &str| {
            figs.iter()
                .find(|f| f.name == n)
                .unwrap_or_else(|| panic!("{n} missing"))
        };
        assert!(
            !dir.join("figures/stale.png").exists(),
            "an old figure stays"
        );

        // Image grid: rows grid, random (as `where` lists them); columns 100, 1000 (by
        // number), reference; 16x12 enlarged 8x.
        let g = by("grid");
        assert_eq!(g.file.as_deref(), Some("figures/grid.png"));
        let img = caustics_metrics::read_png(&dir.join("figures/grid.png")).expect("png");
        let find = |c: [u8; 3]| {
            (0..img.height)
                .flat_map(|y| (0..img.width).map(move |x| (x, y)))
                .find(|&(x, y)| img.get(x, y) == c)
        };
        // The sweep expands filtering, samples, sampling (sorted keys), the last fastest:
        // run 6 is full, 1000, random; run 7 full, 1000, grid; run 4 full, 100, random.
        let (x6, y6) = find(shade(6)).expect("run 6 drawn");
        let (x7, y7) = find(shade(7)).expect("run 7 drawn");
        assert!(
            y7 < y6 && x6 == x7,
            "grid above random in one column: {x6},{y6} {x7},{y7}"
        );
        let (x4, y4) = find(shade(4)).expect("run 4 drawn");
        assert!(x4 < x6 && y4 == y6, "100 samples left of 1000 in one row");
        for off in 0..4 {
            assert!(
                find(shade(off)).is_none(),
                "run {off} (filtering off) drawn"
            );
        }
        let grey = caustics_metrics::ToneMap::new(1.0).apply(&{
            let mut i = HdrImage::new(1, 1);
            i.set(0, 0, [0.5; 3]);
            i
        });
        // A block of it, not an anti-aliased text pixel of the same grey.
        let c = grey.get(0, 0);
        let (xr, _) = (1..img.height - 1)
            .flat_map(|y| (1..img.width - 1).map(move |x| (x, y)))
            .find(|&(x, y)| (0..3).all(|d| (0..3).all(|e| img.get(x + d - 1, y + e - 1) == c)))
            .expect("the reference column");
        assert!(xr > x6 + 127, "the reference is the last column");
        assert!(
            g.notes.iter().any(|n| n.contains("enlarged 8x")),
            "{:?}",
            g.notes
        );

        // Line with a fit: exact, so R² = 1.
        let t = by("time");
        assert_eq!(t.file.as_deref(), Some("figures/time.png"));
        assert!(
            t.notes
                .iter()
                .any(|n| n.contains("least squares over the 8 points") && n.contains("R² = ")),
            "{:?}",
            t.notes
        );
        // Relative: filtering off's relMSE over full's best (smallest) on ring.
        let r = by("relative");
        assert!(
            r.file.is_some()
                && r.notes
                    .iter()
                    .any(|n| n.contains("divided by the smallest")),
            "{r:?}"
        );

        // Ratio: full takes twice the time and has half the relMSE of off, per pair.
        let q = by("filter");
        let table = q.table.as_ref().expect("ratio table");
        // Each pair: its two measures and, as one is a time, the base passes' ratio.
        assert_eq!(table.rows.len(), 4 * 3, "{table:?}");
        for row in &table.rows {
            let want = match row[1].as_str() {
                "method_gpu_ms" => "2.000",
                BASE_PASSES if row[0].contains("1000") && row[0].contains("random") => "1.300",
                BASE_PASSES => "1.000",
                _ => "0.500",
            };
            assert_eq!(row[4], want, "{row:?}");
        }
        let drift: Vec<&String> = q.notes.iter().filter(|n| n.contains("uncertain")).collect();
        assert_eq!(drift.len(), 1, "{:?}", q.notes);
        assert!(
            drift[0].contains("1.300×") && drift[0].contains("1000") && drift[0].contains("random"),
            "{drift:?}"
        );
        assert!(dir.join("figures/filter.png").is_file());

        // Table: one row per run, the chosen columns.
        let n = by("numbers");
        let t = n.table.as_ref().expect("table");
        assert_eq!(
            t.head[3..],
            [
                "param:sampling",
                "counter:samples",
                "pass:gather+prepare_samples"
            ]
        );
        assert_eq!(t.rows.len(), 8);
        assert_eq!(t.rows[0][4], "100");
        let ms: f64 = t.rows[0][5].parse().expect("number");
        assert!(
            (ms - 2.0).abs() < 1e-9,
            "gather + prepare = the method's 2 ms: {ms}"
        );
        assert!(n.file.is_none());

        let md = markdown(&figs);
        assert!(
            md.starts_with("## Figures") && md.contains("![grid](figures/grid.png)"),
            "{md}"
        );
        assert!(
            md.contains("| scene | method | params | param:sampling |"),
            "{md}"
        );
    }

    #[test]
    fn a_figure_without_done_runs_says_so_and_a_missing_reference_is_a_note() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = tmp.path().join("exp");
        let (e, mut s) = synthetic(&dir, &tmp.path().join("refs"));
        for r in &mut s.runs {
            if r.params["filtering"] == "full" {
                r.status = "skipped".into();
            }
        }
        let figs = draw(&dir, &e, &s, &tmp.path().join("elsewhere")).expect("draw");
        let g = &figs[0];
        assert!(
            g.file.is_none() && g.notes[0].contains("none of the figure's runs is done"),
            "{g:?}"
        );
        let mut s2 = s.clone();
        for r in &mut s2.runs {
            r.status = "done".into();
        }
        let figs = draw(&dir, &e, &s2, &tmp.path().join("elsewhere")).expect("draw");
        assert!(
            figs[0]
                .notes
                .iter()
                .any(|n| n.contains("no reference of ring at 16x12")),
            "{:?}",
            figs[0].notes
        );
        assert!(figs[0].file.is_some());
    }

    #[test]
    fn least_squares_recovers_a_line() {
        let (a, b, r2) = least_squares(&[(1.0, 3.0), (2.0, 5.0), (4.0, 9.0)]).expect("fit");
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
        assert!(least_squares(&[(1.0, 1.0), (1.0, 2.0)]).is_none());
    }
}
