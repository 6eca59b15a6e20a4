//! `caustics report [DIR]`: a static, self-contained HTML report (one folder:
//! `index.html` plus the images it shows, copied beside it) of every reproduced
//! experiment under DIR. One landing page: what the numbers are, the experiments with
//! their adapters and resolutions, the paper's numbers beside ours with their ratios
//! (hardware and resolution of both, mismatches flagged), then per experiment its
//! figures, tables (surface errors beside the costs, volume errors apart), plots, and a
//! gallery: per scene the reference's caustic beside each run's caustic and signed
//! error map (≥ 256 px wide), with links to its composite and fill-rate heatmap; last a
//! glossary of every table column and every method counter. No script, stylesheet or
//! font is fetched from anywhere; a tiny inline script only marks, for automated checks,
//! whether every image loaded (in a hidden element).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use caustics_metrics::ToneMap;

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
    /// Reference cache the runs were scored against: the gallery shows each scene's
    /// reference from it (a run names its reference by its place in the cache).
    #[arg(long, value_name = "DIR", default_value = crate::references::DEFAULT_ROOT)]
    pub references: PathBuf,
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

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1500px;color:#222;line-height:1.4}\
table{border-collapse:collapse;margin:1em 0;font-size:13px}\
td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}\
td:nth-child(-n+3),th{text-align:left}th{background:#f0f0f0}\
.runs{display:flex;flex-wrap:wrap;gap:12px}.run{border:1px solid #ddd;padding:6px;max-width:560px}\
.run img{display:block;image-rendering:pixelated;margin:2px 0}.run.ref{background:#f4f8ff}\
.meta{color:#555;font-size:13px}.paper{background:#fff8e0}.flag{color:#b00;font-weight:bold}\
dt{font-weight:bold;margin-top:.4em}dd{margin-left:1.5em}";

const CHECK_SCRIPT: &str = "<script>window.addEventListener('load',function(){\
var bad=[].filter.call(document.images,function(i){return !(i.complete&&i.naturalWidth>0)})\
.map(function(i){return i.getAttribute('src')});\
var d=document.getElementById('render-check');\
d.textContent=bad.length?('broken images: '+bad.join(' ')):('all '+document.images.length+' images loaded');\
if(bad.length){d.hidden=false;}\
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

/// The method passes of every run against the adapter's ceilings (summary.md's
/// `## Roofline`); nothing when no run has a roofline.
fn roofline_table(html: &mut String, s: &Summary) {
    let Some(table) = crate::summary::roofline_rows(s) else {
        return;
    };
    let _ = writeln!(
        html,
        "<h3>Roofline</h3>\n<p class=meta>{}</p>\n<table><tr><th>scene</th><th>method</th><th>params</th><th>method passes: GPU ms, bound, share of its ceiling</th></tr>",
        esc(&table.caption)
    );
    for (r, cells) in &table.rows {
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&r.scene),
            esc(&r.method),
            esc(&params_cell(r)),
            cells
                .iter()
                .map(|c| esc(c))
                .collect::<Vec<_>>()
                .join("<br>")
        );
    }
    html.push_str("</table>\n");
}

fn experiment_section(html: &mut String, dir: &Path, out: &Path, references: &Path) -> Result<()> {
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
        let done = s
            .runs
            .iter()
            .filter(|r| r.group == *g && r.status == "done");
        let sequences: Vec<&Row> = done.clone().filter(|r| r.sequence.is_some()).collect();
        let rows: Vec<&Row> = done.filter(|r| r.sequence.is_none()).collect();
        if !sequences.is_empty() {
            let _ = writeln!(html, "<h3>{}: animated sequences</h3>", esc(g));
            sequence_table(html, &s, &sequences, dir, out)?;
        }
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
    roofline_table(html, &s);
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
    gallery(html, &s, dir, out, references)?;
    Ok(())
}

/// The animated runs of a group: their sequence figures (as the summary's table) and the
/// caustic of each scored instant, tone-mapped at the sequence's one exposure.
fn sequence_table(
    html: &mut String,
    s: &Summary,
    rows: &[&Row],
    dir: &Path,
    out: &Path,
) -> Result<()> {
    html.push_str("<p class=meta>Each frame a new instant (scene posed, uploaded, method created anew). GPU ms: median (p10–p90) over the instants; rebuild: CPU ms of each instant's upload and setup. Errors: means over the scored instants. Temporal relRMSE: the method's frame-to-frame change against the reference's (flicker), beside the same frames' still relRMSE; change ratio Σ Δm² / Σ Δr².</p>\n<table><tr><th>scene</th><th>method</th><th>params</th><th>frames</th><th>method GPU ms</th><th>rebuild CPU ms</th><th>flux</th><th>relMSE</th><th>HDR-FLIP</th><th>temporal relRMSE</th><th>still relRMSE</th><th>change ratio</th><th>scored instants</th></tr>\n");
    let spread = |v: &Option<crate::summary::Spread>| {
        v.map_or("–".into(), |v| {
            format!("{:.2} ({:.2}–{:.2})", v.median, v.p10, v.p90)
        })
    };
    for r in rows {
        let (Some(q), Some(rel_dir)) = (&r.sequence, &r.dir) else {
            continue;
        };
        let a = crate::summary::read_sequence(&dir.join(rel_dir))?;
        let mut images = String::new();
        for f in &a.frames {
            let Some(img) = &f.image else { continue };
            let from = dir.join(rel_dir).join(img);
            if !from.is_file() {
                continue;
            }
            let rel = copy(&from, out, &format!("img/{}/{rel_dir}/{img}", s.experiment))?;
            let _ = write!(
                images,
                "<img src=\"{}\" width={} alt=\"t = {:.3} s\" title=\"t = {:.3} s\">",
                esc(&rel),
                display_width(a.scene.width) / 2,
                f.time_s,
                f.time_s
            );
        }
        let [frames, errors @ ..] = q.cells();
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{images}</td></tr>",
            esc(&r.scene),
            esc(&r.method),
            esc(&params_cell(r)),
            esc(&frames),
            spread(&r.method_gpu_ms),
            spread(&q.rebuild_ms),
            errors.map(|e| esc(&e)).join("</td><td>"),
        );
    }
    html.push_str("</table>\n");
    Ok(())
}

/// Display width of an image `w` px wide in the gallery: small runs enlarged by a whole
/// factor to at least 256 px (pixelated), large ones shown at most 512 px wide.
fn display_width(w: u32) -> u32 {
    if w == 0 {
        return 256;
    }
    if w < 256 {
        w * 256u32.div_ceil(w)
    } else {
        w.min(512)
    }
}

/// The reference caustic of `r`'s scene (surface + volume, tone-mapped at the run's
/// exposure, as its `caustic.png`) written into the report; `Err` says why there is none.
fn reference_image(
    run_dir: &Path,
    r: &Row,
    references: &Path,
    out: &Path,
    experiment: &str,
) -> Result<std::result::Result<(String, u32), String>> {
    let result = crate::summary::read_result(run_dir)?;
    let Some(e) = result.errors.as_ref().or(result.errors_1spp.as_ref()) else {
        return Ok(Err("not scored: no reference".into()));
    };
    let path = if e.reference_source == "cache" {
        references.join(&e.reference)
    } else {
        PathBuf::from(&e.reference)
    };
    if !path.is_file() {
        return Ok(Err(format!(
            "its reference {} is not in {} (`caustics report --references DIR` names the cache the runs used)",
            e.reference,
            references.display()
        )));
    }
    let mut img = caustics_metrics::read_exr(&path)?;
    let volume = path.with_file_name("volume.exr");
    if e.reference_source == "cache" && volume.is_file() {
        img = img.add(&caustics_metrics::read_exr(&volume)?)?;
    }
    let rel = format!(
        "img/{experiment}/references/{}_{}x{}.png",
        crate::plots::file_safe(&r.scene),
        r.width,
        r.height
    );
    let to = out.join(&rel);
    if let Some(p) = to.parent() {
        std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
    }
    caustics_metrics::write_png(
        &to,
        &ToneMap::new(r.exposure_scale.unwrap_or(1.0)).apply(&img),
    )?;
    Ok(Ok((rel, img.width)))
}

/// Per scene: the reference's caustic, then every done run's caustic over its signed
/// error map, with its composite and heatmap linked.
fn gallery(
    html: &mut String,
    s: &Summary,
    dir: &Path,
    out: &Path,
    references: &Path,
) -> Result<()> {
    // Sequences show their scored instants in their own table.
    let done: Vec<&Row> = s
        .runs
        .iter()
        .filter(|r| r.status == "done" && r.dir.is_some() && r.sequence.is_none())
        .collect();
    if done.is_empty() {
        return Ok(());
    }
    html.push_str("<h3>Gallery</h3><p class=meta>Per scene: the reference's caustic (the CPU light tracer, tone-mapped at the runs' exposure), then each run's caustic at that exposure over its signed error against the reference (blue: too dark, red: too bright; one scale per scene, the bar in W·m⁻²·sr⁻¹), the volume caustic's error where there is one; composite and fill-rate heatmap linked. Runs smaller than 256 px are shown enlarged, pixel for pixel.</p>\n");
    let mut scenes: Vec<&str> = Vec::new();
    for r in &done {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    for scene in scenes {
        let runs: Vec<&Row> = done.iter().copied().filter(|r| r.scene == scene).collect();
        let _ = writeln!(html, "<h4>{}</h4><div class=runs>", esc(scene));
        // The reference, from the first run scored against one.
        let mut shown = Err("no run of the scene was scored".to_owned());
        for r in &runs {
            let run_dir = dir.join(r.dir.as_deref().unwrap_or_default());
            shown = reference_image(&run_dir, r, references, out, &s.experiment)?;
            if shown.is_ok() {
                break;
            }
        }
        match shown {
            Ok((rel, w)) => {
                let _ = writeln!(
                    html,
                    "<div class=\"run ref\"><b>reference</b><img src=\"{}\" width={} alt=\"{} reference\"></div>",
                    esc(&rel),
                    display_width(w),
                    esc(scene)
                );
            }
            Err(why) => {
                let _ = writeln!(
                    html,
                    "<div class=\"run ref\"><b>reference</b><p class=meta>{}</p></div>",
                    esc(&why)
                );
            }
        }
        for r in runs {
            let Some(rel_dir) = &r.dir else { continue };
            let label = format!("{} {}", r.method, params_cell(r));
            let _ = write!(html, "<div class=run><b>{}</b>", esc(&label));
            let mut scale = None;
            for img in ["caustic.png", "error.png", "volume_error.png"] {
                let from = dir.join(rel_dir).join(img);
                if !from.is_file() {
                    continue;
                }
                let rel = copy(
                    &from,
                    out,
                    &format!("img/{}/{}/{img}", s.experiment, rel_dir),
                )?;
                let w = caustics_metrics::read_png(&from)
                    .map(|p| p.width)
                    .with_context(|| format!("reading {}", from.display()))?;
                // Maps are the image plus their colour bar: shown at the caustic's scale.
                let k = *scale.get_or_insert(f64::from(display_width(w)) / f64::from(w.max(1)));
                let _ = write!(
                    html,
                    "<img src=\"{}\" width={} alt=\"{} {img}\">",
                    esc(&rel),
                    (f64::from(w) * k).round() as u32,
                    esc(&r.key)
                );
            }
            let mut links = Vec::new();
            for (img, what) in [
                ("composite.png", "composite"),
                ("fill_heatmap.png", "fragments/px"),
            ] {
                let from = dir.join(rel_dir).join(img);
                if from.is_file() {
                    let rel = copy(
                        &from,
                        out,
                        &format!("img/{}/{}/{img}", s.experiment, rel_dir),
                    )?;
                    links.push(format!("<a href=\"{}\">{what}</a>", esc(&rel)));
                }
            }
            if let Some(e) = &r.errors {
                links.push(format!(
                    "flux {} · relMSE {} · HDR-FLIP {}",
                    e.flux_ratio.map(num).unwrap_or_else(|| "–".into()),
                    num(e.rel_mse),
                    e.hdr_flip.map(num).unwrap_or_else(|| "–".into())
                ));
            }
            let _ = writeln!(html, "<p class=meta>{}</p></div>", links.join(" · "));
        }
        html.push_str("</div>\n");
    }
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

const INTRO: &str = "<p>Every number below was measured by <code>caustics reproduce</code> on the adapter each section names: GPU time per pass from timestamp queries (median, 10th–90th percentile over the timed frames), fragments from pipeline-statistics queries, and errors of the caustic images against an unbiased CPU light tracer (the <em>reference</em>), scored on a pixel-averaged frame of 16 sub-pixel samples per pixel. On a software adapter (lavapipe) times are CPU times: compare ratios within one experiment, not absolute values. The <a href=#glossary>glossary</a> says what each column and counter is.</p>\n";

/// Each experiment with its adapter(s), resolution(s) and run counts (the adapter once
/// above the table when every experiment ran on the same one).
fn experiments_table(html: &mut String, summaries: &[Summary]) {
    let one_adapter = summaries
        .first()
        .map(|s| &s.adapters)
        .filter(|first| summaries.iter().all(|s| &s.adapters == *first));
    html.push_str("<h2>Experiments</h2>\n");
    if let Some(a) = one_adapter {
        let _ = writeln!(
            html,
            "<p class=meta>Every experiment ran on {}.</p>",
            esc(&a.join("; "))
        );
    }
    let _ = writeln!(
        html,
        "<table><tr><th>experiment</th><th>what it reproduces</th><th>paper</th>{}<th>resolution</th><th>runs</th></tr>",
        if one_adapter.is_some() {
            ""
        } else {
            "<th>adapter</th>"
        }
    );
    for s in summaries {
        let adapter = if one_adapter.is_some() {
            String::new()
        } else {
            format!("<td>{}</td>", esc(&s.adapters.join("; ")))
        };
        let _ = writeln!(
            html,
            "<tr><td><a href=\"#{0}\">{0}</a></td><td>{1}</td><td>{2}</td>{adapter}<td>{3}</td><td>{4} done, {5} skipped, {6} failed</td></tr>",
            esc(&s.experiment),
            esc(&s.description),
            esc(s.paper.as_ref().map_or("–", |p| p.source.as_str())),
            esc(&resolutions(&s.runs.iter().collect::<Vec<_>>()).join(", ")),
            s.done,
            s.skipped,
            s.failed
        );
    }
    html.push_str("</table>\n");
}

/// The distinct `W×H` of runs, in order.
fn resolutions(rows: &[&Row]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        let size = format!("{}×{}", r.width, r.height);
        if !out.contains(&size) {
            out.push(size);
        }
    }
    out
}

/// The first `W×H` (or `WxH`) in a paper's hardware line, e.g. "GTX 470, 1024x768".
fn paper_resolution(hardware: &str) -> Option<(u32, u32)> {
    let chars: Vec<char> = hardware.chars().collect();
    for (i, c) in chars.iter().enumerate() {
        if !matches!(c, 'x' | '×') || i == 0 {
            continue;
        }
        let before: String = chars[..i]
            .iter()
            .rev()
            .take_while(|c| c.is_ascii_digit())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        let after: String = chars[i + 1..]
            .iter()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        if let (Ok(w), Ok(h)) = (before.parse(), after.parse()) {
            return Some((w, h));
        }
    }
    None
}

/// The paper's numbers beside ours, per experiment that states them: ratio ours ÷ paper,
/// hardware and resolution of both, a flagged line where the settings differ.
fn paper_section(html: &mut String, summaries: &[Summary]) {
    let with: Vec<&Summary> = summaries
        .iter()
        .filter(|s| s.paper.is_some() && s.runs.iter().any(|r| !r.paper.is_empty()))
        .collect();
    if with.is_empty() {
        return;
    }
    html.push_str("<h2>The papers' numbers beside ours</h2><p class=meta>Each paper value stated in an experiment file, beside the same measure of the matching run and their ratio. Different hardware makes absolute times incomparable: read the ratios between rows of one experiment, and the flagged settings.</p>\n");
    for s in with {
        let Some(p) = &s.paper else { continue };
        let rows: Vec<&Row> = s.runs.iter().filter(|r| !r.paper.is_empty()).collect();
        let ours = resolutions(&rows);
        let _ = write!(
            html,
            "<h3><a href=\"#{0}\">{0}</a></h3><p class=meta>Paper: {1}, on {2}. Ours: {3}, at {4}.",
            esc(&s.experiment),
            esc(&p.source),
            esc(&p.hardware),
            esc(&s.adapters.join("; ")),
            esc(&ours.join(", "))
        );
        if let Some((w, h)) = paper_resolution(&p.hardware) {
            let mismatched: Vec<&String> =
                ours.iter().filter(|o| **o != format!("{w}×{h}")).collect();
            if !mismatched.is_empty() {
                let _ = write!(
                    html,
                    " <span class=flag>Resolution differs: the paper's {w}×{h}, ours {}.</span>",
                    esc(&mismatched
                        .iter()
                        .map(|m| m.as_str())
                        .collect::<Vec<_>>()
                        .join(", "))
                );
            }
        }
        html.push_str("</p><table><tr><th>scene</th><th>method</th><th>params</th><th>measure</th><th>paper</th><th>ours</th><th>ours ÷ paper</th><th>where in the paper</th></tr>\n");
        for r in rows {
            for v in &r.paper {
                let ours = r.measure(&v.measure);
                let ratio = ours.filter(|_| v.value != 0.0).map(|o| o / v.value);
                // Times differ with the hardware; a count (beams, fragments) should not:
                // one far from the paper's says the run is not the paper's setting.
                let is_count = v.measure.starts_with("counter:") || v.measure == "fragments";
                let flag = match ratio {
                    Some(q) if is_count && !(0.5..=2.0).contains(&q) => format!(
                        " <span class=flag>settings differ: {q:.1}× the paper's count</span>"
                    ),
                    _ => String::new(),
                };
                let _ = writeln!(
                    html,
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}{flag}</td><td>{}</td></tr>",
                    esc(&r.scene),
                    esc(&r.method),
                    esc(&params_cell(r)),
                    esc(&v.measure),
                    num(v.value),
                    ours.map(num).unwrap_or_else(|| "–".into()),
                    ratio
                        .map(|q| format!("{q:.3}"))
                        .unwrap_or_else(|| "–".into()),
                    esc(&v.note)
                );
            }
        }
        html.push_str("</table>\n");
    }
}

/// What each column of the tables means.
const COLUMNS: &[(&str, &str)] = &[
    (
        "method GPU ms, frame GPU ms",
        "GPU time of the method's own passes, and of the whole frame (shared G-buffers, shadow map, direct light and the method), from timestamp queries: median over the timed frames, 10th–90th percentile in brackets.",
    ),
    (
        "fragments",
        "Fragment-shader invocations of the method's passes in the count frame (pipeline-statistics query): the fill work the method asked of the rasterizer.",
    ),
    (
        "spp",
        "Samples per pixel of the scoring frame whose errors the pixel-averaged columns give (N×N sub-pixel camera offsets, averaged on the GPU; the reference averages each pixel's area).",
    ),
    (
        "flux, flux (image)",
        "The method's luminance summed over the reference's caustic region (pixels at least 1% of its 99th-percentile luminance), and over the whole image, divided by the reference's: 1 means all the light is there.",
    ),
    (
        "relMSE",
        "Mean over pixels of (test − ref)² / (ref² + 0.01), luminance: every pixel weighed by its own brightness, so a dim wide caustic counts as much as the focus.",
    ),
    (
        "relMSE after flux",
        "relMSE after dividing the image by its whole-image flux ratio: is the light in the right place, whatever its total.",
    ),
    (
        "HDR-FLIP, HDR-FLIP after flux",
        "HDR-FLIP (Andersson et al. 2021): the per-pixel maximum of LDR-FLIP over an exposure bracket of ACES-tone-mapped images, from the reference's brightest pixel to its caustic region's median; mean over pixels, 0 = indistinguishable.",
    ),
    (
        "LDR-FLIP @exposure",
        "LDR-FLIP of the images tone-mapped at the stated exposure: what a viewer sees at that exposure.",
    ),
    (
        "relMSE 1spp, HDR-FLIP 1spp, LDR-FLIP 1spp",
        "The same errors of the timed frame (one sample at each pixel centre).",
    ),
    (
        "aliasing: relMSE 1spp − relMSE",
        "How much of the 1-spp error is camera aliasing (a focus narrower than a pixel hit or missed), not the method.",
    ),
    (
        "RMSE, RMSE 1spp",
        "Root-mean-square error of linear radiance (W·m⁻²·sr⁻¹): set by the brightest pixels, a diagnostic.",
    ),
    (
        "s, RMSE·s",
        "The least-squares scale of the image onto the reference and the RMSE after it: set by the focus, a diagnostic.",
    ),
    (
        "σ_ref",
        "RMS of the reference's own per-pixel standard error (from independent batches): error differences below it mean nothing.",
    ),
];

/// Every table column, and every counter the reported methods produced, with its doc.
fn glossary(html: &mut String, summaries: &[Summary]) {
    html.push_str("<h2 id=glossary>Glossary</h2><h3>Columns</h3><dl>\n");
    for (name, doc) in COLUMNS {
        let _ = writeln!(html, "<dt>{}</dt><dd>{}</dd>", esc(name), esc(doc));
    }
    html.push_str("</dl>\n<h3>Counters</h3><p class=meta>Each method's counters of its last frame, as its crate documents them (<code>caustics list</code> prints them too).</p>\n");
    let mut methods: Vec<&str> = Vec::new();
    for r in summaries.iter().flat_map(|s| &s.runs) {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    for m in methods {
        let Ok(info) = crate::registry::find(m) else {
            continue;
        };
        let _ = writeln!(html, "<h4>{}</h4><dl>", esc(m));
        for c in info.counters {
            let _ = writeln!(html, "<dt>{}</dt><dd>{}</dd>", esc(c.name), esc(c.doc));
        }
        html.push_str("</dl>\n");
    }
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
        "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>caustics-bench report</title><style>{STYLE}</style>{CHECK_SCRIPT}</head><body>\n<h1>caustics-bench report</h1>\n<p id=render-check data-ok=pending hidden>images not checked yet</p>\n"
    );
    html.push_str(INTRO);
    experiments_table(&mut html, &summaries);
    paper_section(&mut html, &summaries);
    for d in &dirs {
        experiment_section(&mut html, d, &out, &args.references)?;
    }
    glossary(&mut html, &summaries);
    html.push_str("</body></html>\n");
    let index = out.join("index.html");
    caustics_metrics::atomic_write(&index, html.as_bytes())?;
    Ok(index)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_lists_the_roofline_of_runs_that_have_one() {
        let mut with = crate::summary::test_row("beams");
        with.roofline = Some(crate::summary::test_roofline("beams"));
        let mut s = crate::summary::test_summary(vec![with, crate::summary::test_row("splatting")]);
        let mut html = String::new();
        roofline_table(&mut html, &s);
        assert!(html.contains("<h3>Roofline</h3>"), "{html}");
        assert!(
            html.contains("<tr><td>s</td><td>beams</td><td>defaults</td><td>rasterize 10.000 ms shader 5.0%</td></tr>"),
            "{html}"
        );
        assert!(!html.contains("splatting"), "{html}");
        s.runs.iter_mut().for_each(|r| r.roofline = None);
        let mut none = String::new();
        roofline_table(&mut none, &s);
        assert!(none.is_empty());
    }
}
