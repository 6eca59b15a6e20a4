//! `caustics report [DIR]`: a static, self-contained HTML report (one folder:
//! `index.html` plus the images it shows, copied beside it) of every reproduced
//! experiment under DIR: the machine and commit, the tables of `summary.md` (surface
//! errors beside the costs, volume errors in a table of their own), the figures the
//! experiment declares (images, notes, tables), the plots,
//! and per run the composite, the error map and the fill-rate heatmap (both with their
//! colour bars). No script, stylesheet or font is fetched from anywhere; a tiny inline
//! script only marks, for automated checks, whether every image loaded.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::summary::{Row, Summary, num, read_summary};

/// Flags of `caustics report`.
#[derive(Clone, Debug, clap::Args)]
pub struct ReportArgs {
    /// An experiment folder (with summary.json) or a folder of them.
    #[arg(default_value = "results/reproduce")]
    pub dir: PathBuf,
    /// Output folder (default: DIR/report). Replaced file by file; other files stay.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// The experiment folders under `dir` (itself, or its children with a summary.json).
fn experiments(dir: &Path) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("{}: no such folder", dir.display());
    }
    if dir.join("summary.json").is_file() {
        return Ok(vec![dir.to_path_buf()]);
    }
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("summary.json").is_file())
        .collect();
    out.sort();
    if out.is_empty() {
        bail!(
            "{}: no summary.json in it or its sub-folders (run `caustics reproduce` first)",
            dir.display()
        );
    }
    Ok(out)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1400px;color:#222}\
table{border-collapse:collapse;margin:1em 0;font-size:13px}\
td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}\
td:nth-child(-n+3),th{text-align:left}th{background:#f0f0f0}\
.runs{display:flex;flex-wrap:wrap;gap:12px}.run{border:1px solid #ddd;padding:6px}\
.run img{display:block;image-rendering:pixelated;margin:2px 0}\
.meta{color:#555;font-size:13px}.paper{background:#fff8e0}";

const CHECK_SCRIPT: &str = "<script>window.addEventListener('load',function(){\
var bad=[].filter.call(document.images,function(i){return !(i.complete&&i.naturalWidth>0)})\
.map(function(i){return i.getAttribute('src')});\
var d=document.getElementById('render-check');\
d.textContent=bad.length?('broken images: '+bad.join(' ')):('all '+document.images.length+' images loaded');\
d.dataset.ok=bad.length?'false':'true';});</script>";

/// Copies `from` to `out/rel` (atomically) and returns `rel` for the page.
fn copy(from: &Path, out: &Path, rel: &str) -> Result<String> {
    let to = out.join(rel);
    if let Some(p) = to.parent() {
        std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
    }
    let bytes = std::fs::read(from).with_context(|| format!("reading {}", from.display()))?;
    caustics_metrics::atomic_write(&to, &bytes)?;
    Ok(rel.to_owned())
}

fn spread(s: &Option<crate::summary::Spread>) -> String {
    s.map(|s| format!("{:.2} <small>({:.2}–{:.2})</small>", s.median, s.p10, s.p90))
        .unwrap_or_else(|| "–".into())
}

fn params_cell(r: &Row) -> String {
    let params = r
        .params
        .iter()
        .map(|(k, v)| {
            format!(
                "{k}={}",
                v.as_str().map(str::to_owned).unwrap_or(v.to_string())
            )
        })
        .collect::<Vec<_>>()
        .join(" ");
    if params.is_empty() {
        "defaults".into()
    } else {
        params
    }
}

/// The columns of [`crate::summary::ERROR_COLUMNS`] as table headers.
fn error_headers() -> String {
    crate::summary::ERROR_COLUMNS
        .iter()
        .map(|c| format!("<th>{}</th>", esc(c)))
        .collect()
}

fn error_tds(cells: &[String]) -> String {
    cells
        .iter()
        .map(|c| format!("<td>{}</td>", esc(c)))
        .collect()
}

fn table(html: &mut String, s: &Summary, rows: &[&Row]) {
    let paper = s
        .paper
        .as_ref()
        .filter(|_| rows.iter().any(|r| !r.paper.is_empty()));
    let _ = write!(
        html,
        "<table><tr><th>scene</th><th>method</th><th>params</th><th>size</th><th>method GPU ms</th><th>frame GPU ms</th><th>fragments</th>{}<th>σ<sub>ref</sub></th>",
        error_headers()
    );
    if let Some(p) = paper {
        let _ = write!(html, "<th class=paper>paper ({})</th>", esc(&p.hardware));
    }
    html.push_str("</tr>\n");
    for r in rows {
        let cells = crate::summary::error_cells(
            r.score_spp,
            r.errors.as_ref(),
            r.errors_1spp.as_ref(),
            r.exposure_scale,
        );
        let _ = write!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}×{}</td><td>{}</td><td>{}</td><td>{}</td>{}<td>{}</td>",
            esc(&r.scene),
            esc(&r.method),
            esc(&params_cell(r)),
            r.width,
            r.height,
            spread(&r.method_gpu_ms),
            spread(&r.frame_gpu_ms),
            r.fragments
                .map(|v| v.to_string())
                .unwrap_or_else(|| "–".into()),
            error_tds(&cells),
            r.reference_noise_rms.map(num).unwrap_or_else(|| "–".into()),
        );
        if paper.is_some() {
            let cell = r
                .paper
                .iter()
                .map(|p| {
                    let ours = r.measure(&p.measure).map(num).unwrap_or_else(|| "–".into());
                    format!("{} {} (ours {ours})", esc(&p.measure), p.value)
                })
                .collect::<Vec<_>>()
                .join("<br>");
            let _ = write!(html, "<td class=paper>{cell}</td>");
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</table>\n");
    let volume: Vec<&&Row> = rows
        .iter()
        .filter(|r| r.volume_errors.is_some() || r.volume_errors_1spp.is_some())
        .collect();
    if !volume.is_empty() {
        let _ = writeln!(
            html,
            "<p class=meta>Volume caustic errors:</p><table><tr><th>scene</th><th>method</th><th>params</th>{}</tr>",
            error_headers()
        );
        for r in volume {
            let cells = crate::summary::error_cells(
                r.score_spp,
                r.volume_errors.as_ref(),
                r.volume_errors_1spp.as_ref(),
                r.volume_exposure_scale,
            );
            let _ = writeln!(
                html,
                "<tr><td>{}</td><td>{}</td><td>{}</td>{}</tr>",
                esc(&r.scene),
                esc(&r.method),
                esc(&params_cell(r)),
                error_tds(&cells)
            );
        }
        html.push_str("</table>\n");
    }
}

fn experiment_section(html: &mut String, dir: &Path, out: &Path) -> Result<()> {
    let s = read_summary(dir)?;
    let id = esc(&s.experiment);
    let _ = write!(
        html,
        "<h2 id=\"{id}\">{id}</h2>\n<p>{}</p>\n",
        esc(&s.description)
    );
    let _ = writeln!(
        html,
        "<p class=meta>Adapter: {}<br>Commit: {}<br>Build: {} · scale {} · {} done, {} skipped, {} failed</p>",
        esc(&s.adapters.join("; ")),
        esc(&s.commits.join(", ")),
        esc(&s.profiles.join(", ")),
        s.scale,
        s.done,
        s.skipped,
        s.failed
    );
    if !s.missing_references.is_empty() {
        let _ = writeln!(
            html,
            "<p>No reference for {}: those runs have no errors.</p>",
            esc(&s.missing_references.join(", "))
        );
    }
    figures_section(html, &s, dir, out)?;
    let mut groups: Vec<&str> = Vec::new();
    for r in &s.runs {
        if !groups.contains(&r.group.as_str()) {
            groups.push(&r.group);
        }
    }
    for g in &groups {
        let rows: Vec<&Row> = s
            .runs
            .iter()
            .filter(|r| r.group == *g && r.status == "done")
            .collect();
        if !rows.is_empty() {
            let _ = writeln!(html, "<h3>{}</h3>", esc(g));
            table(html, &s, &rows);
        }
    }
    if let Some(p) = &s.paper {
        let _ = writeln!(
            html,
            "<p class=meta>Paper figures: {}, on {} — compare ratios, not absolute times.</p>",
            esc(&p.source),
            esc(&p.hardware)
        );
    }
    let skipped: Vec<&Row> = s.runs.iter().filter(|r| r.status != "done").collect();
    if !skipped.is_empty() {
        html.push_str(
            "<h3>Not run</h3><table><tr><th>run</th><th>status</th><th>reason</th></tr>\n",
        );
        for r in skipped {
            let _ = writeln!(
                html,
                "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&r.key),
                esc(&r.status),
                esc(r.reason.as_deref().unwrap_or(""))
            );
        }
        html.push_str("</table>\n");
    }
    // Plots.
    let plots = dir.join("plots");
    if plots.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&plots)?
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "png"))
            .collect();
        files.sort();
        if !files.is_empty() {
            html.push_str("<h3>Plots</h3>\n");
        }
        for f in files {
            let name = f
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let rel = copy(&f, out, &format!("img/{}/plots/{name}", s.experiment))?;
            let _ = writeln!(html, "<img src=\"{}\" alt=\"{}\">", esc(&rel), esc(&name));
        }
    }
    // Images of every run.
    html.push_str("<h3>Images</h3><p class=meta>Per run: composite (direct + caustics, tone-mapped), error against the reference, fragments per pixel; maps carry their colour bars.</p><div class=runs>\n");
    for r in s.runs.iter().filter(|r| r.status == "done") {
        let Some(rel_dir) = &r.dir else { continue };
        let _ = write!(html, "<div class=run><b>{}</b>", esc(&r.key));
        for img in ["composite.png", "error.png", "fill_heatmap.png"] {
            let from = dir.join(rel_dir).join(img);
            if from.is_file() {
                let rel = copy(
                    &from,
                    out,
                    &format!("img/{}/{}/{img}", s.experiment, rel_dir),
                )?;
                // Small images shown at twice their size (pixelated), so that a 96x72
                // run is legible.
                let width = caustics_metrics::read_png(&from)
                    .map(|p| if p.width < 300 { 2 * p.width } else { p.width })
                    .with_context(|| format!("reading {}", from.display()))?;
                let _ = write!(
                    html,
                    "<img src=\"{}\" width={width} alt=\"{} {img}\">",
                    esc(&rel),
                    esc(&r.key)
                );
            }
        }
        html.push_str("</div>\n");
    }
    html.push_str("</div>\n");
    Ok(())
}

/// The experiment's declared figures: title, caption, image, notes and table.
fn figures_section(html: &mut String, s: &Summary, dir: &Path, out: &Path) -> Result<()> {
    if s.figures.is_empty() {
        return Ok(());
    }
    html.push_str("<h3>Figures</h3>\n");
    for f in &s.figures {
        let _ = writeln!(html, "<h4>{}</h4>", esc(&f.title));
        if !f.caption.is_empty() {
            let _ = writeln!(html, "<p>{}</p>", esc(&f.caption));
        }
        if let Some(file) = &f.file {
            let from = dir.join(file);
            if from.is_file() {
                let rel = copy(&from, out, &format!("img/{}/{file}", s.experiment))?;
                let _ = writeln!(html, "<img src=\"{}\" alt=\"{}\">", esc(&rel), esc(&f.name));
            }
        }
        if !f.notes.is_empty() {
            html.push_str("<ul class=meta>");
            for n in &f.notes {
                let _ = write!(html, "<li>{}</li>", esc(n));
            }
            html.push_str("</ul>\n");
        }
        if let Some(t) = &f.table {
            html.push_str("<table><tr>");
            for h in &t.head {
                let _ = write!(html, "<th>{}</th>", esc(h));
            }
            html.push_str("</tr>\n");
            for r in &t.rows {
                html.push_str("<tr>");
                for c in r {
                    let _ = write!(html, "<td>{}</td>", esc(c));
                }
                html.push_str("</tr>\n");
            }
            html.push_str("</table>\n");
        }
    }
    Ok(())
}

/// Writes the report; returns the path of `index.html`.
pub fn report(args: &ReportArgs) -> Result<PathBuf> {
    let dirs = experiments(&args.dir)?;
    // Read every summary before writing anything.
    let summaries = dirs
        .iter()
        .map(|d| read_summary(d))
        .collect::<Result<Vec<_>>>()?;
    let out = args.out.clone().unwrap_or_else(|| args.dir.join("report"));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let mut html = String::new();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>caustics-bench report</title><style>{STYLE}</style>{CHECK_SCRIPT}</head><body>\n<h1>caustics-bench report</h1>\n<p id=render-check data-ok=pending>images not checked yet</p>\n<ul>"
    );
    for s in &summaries {
        let _ = write!(
            html,
            "<li><a href=\"#{0}\">{0}</a>: {1}</li>",
            esc(&s.experiment),
            esc(&s.description)
        );
    }
    html.push_str("</ul>\n");
    for d in &dirs {
        experiment_section(&mut html, d, &out)?;
    }
    html.push_str("</body></html>\n");
    let index = out.join("index.html");
    caustics_metrics::atomic_write(&index, html.as_bytes())?;
    Ok(index)
}
