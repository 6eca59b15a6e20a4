//! The control buffer of beam generation, declared once (STYLE 13): [`CONTROL`] names
//! each word (or run of words), its index and what it holds. The WGSL constants
//! `C_*` of generate.wgsl are generated from it ([`wgsl`], prepended to the generate
//! source), and so are the counters the method reports ([`counters`]).

use caustics_method::{CounterDoc, Counters};

use crate::{MAX_BOUNCES, MAX_LEVELS};

/// Bins of the split-priority histogram of a level (`beam_budget`): priorities
/// 2^-8..2^24 in steps of 2^(1/32) (generate.wgsl `priority_bin`).
pub(crate) const SPLIT_BINS: usize = 1024;

/// Words of the control buffer (reset to zero every frame): the named words, then
/// the split-priority histogram.
pub(crate) const CONTROL_WORDS: usize = SPLIT_HISTOGRAM.index + SPLIT_BINS;

/// Words a lattice vertex holds per light-path family with `vertex_irradiance`, past
/// the [`CONTROL_WORDS`] (generate.wgsl `vertex_list`): how many beams of
/// the family have it as a corner, and their slots. The grid's triangles are right
/// isosceles at every level (midpoint subdivision keeps their shape), so at most
/// 360° / 45° = 8 leaves meet at a vertex, each with at most one beam per family.
pub(crate) const VERTEX_LIST_WORDS: usize = 1 + VERTEX_LIST_SLOTS;

/// Beam slots a lattice vertex lists per family (see [`VERTEX_LIST_WORDS`]).
pub(crate) const VERTEX_LIST_SLOTS: usize = 8;

/// Light-path families of a leaf (path.wgsl `FAMILY_*`): the main path, the Fresnel
/// reflection at the first interface, one per internal reflection count 1..=MAX_BOUNCES.
pub(crate) const FAMILIES: usize = 2 + MAX_BOUNCES as usize;

/// How many words a [`Word`] spans, and how its counters are named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Span {
    /// One word.
    One,
    /// One word per refinement level 0..=MAX_LEVELS, reported as `<counter>_<level>`
    /// for each level run.
    Levels,
    /// One word per light-path family, reported as `<counter>_main`,
    /// `<counter>_fresnel_reflection` and `<counter>_internal_<j>` for j = 1..=bounces.
    Families,
    /// [`SPLIT_BINS`] words, one per split-priority bin (state, not reported).
    Bins,
}

/// One word, or one word per refinement level, of the control buffer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Word {
    /// The WGSL constant holding its index (`C_…`).
    pub(crate) wgsl: &'static str,
    /// Its index in the control buffer.
    pub(crate) index: usize,
    /// The counter it is reported as, if any (a run of words: see [`Span`]).
    pub(crate) counter: Option<&'static str>,
    /// The words it spans.
    pub(crate) span: Span,
    /// What it holds.
    pub(crate) doc: &'static str,
}

/// A word the kernels use to pass the refinement along, not reported.
const fn state(wgsl: &'static str, index: usize, doc: &'static str) -> Word {
    Word {
        wgsl,
        index,
        counter: None,
        span: Span::One,
        doc,
    }
}

/// A word reported as the counter `name`.
const fn counter(wgsl: &'static str, index: usize, name: &'static str, doc: &'static str) -> Word {
    Word {
        counter: Some(name),
        ..state(wgsl, index, doc)
    }
}

/// Refinement levels run (the current level while generating).
pub(crate) const LEVEL: Word = counter("C_LEVEL", 8, "levels_run", "refinement levels run");
/// Beams written so far.
pub(crate) const BEAM_TOTAL: Word = counter("C_BEAM_TOTAL", 12, "beams", "beams after this level");

/// The split-priority histogram of the current level (`beam_budget`): per bin, the
/// leaves at stake in the splits asked with that priority.
const SPLIT_HISTOGRAM: Word = Word {
    span: Span::Bins,
    ..state(
        "C_SPLIT_HISTOGRAM",
        64,
        "split-priority histogram of the level (beam_budget)",
    )
};

/// Every word, by index (words 0 to 7 and 59 to 63 are unused).
#[rustfmt::skip]
pub(crate) const CONTROL: &[Word] = &[
    LEVEL,
    state("C_COUNT", 9, "candidates in the current list"),
    state("C_NEXT_COUNT", 10, "candidates of the next level"),
    state("C_BEAM_BASE", 11, "first beam slot of this level's leaves"),
    BEAM_TOTAL,
    counter("C_OVERFLOW_CANDIDATES", 13, "overflow_candidates", "children that found no room in the candidate list"),
    counter("C_OVERFLOW_BEAMS", 14, "overflow_beams", "beams that found no room in the beam buffer"),
    Word { span: Span::Levels, ..counter("C_BEAMS_PER_LEVEL", 15, "beams_level", "beams emitted at each level") },
    counter("C_TIGHT", 20, "hulls_tight", "beams with a tight six-triangle hull"),
    counter("C_PRISM", 21, "hulls_prism", "beams with a bounding prism"),
    counter("C_DROPPED_INVALID", 22, "dropped_invalid", "leaves none of whose corner paths is valid"),
    counter("C_DROPPED_DISCONTINUITY", 23, "dropped_discontinuity", "leaves whose corners follow different paths"),
    counter("C_SPLIT_DISCONTINUITY", 24, "splits_discontinuity", "splits asked by the discontinuity criterion"),
    counter("C_SPLIT_ENERGY", 25, "splits_energy", "splits asked by the energy criterion"),
    counter("C_SPLIT_CAMERA", 26, "splits_camera", "splits asked by the camera criterion"),
    counter("C_CANDIDATES_TOTAL", 27, "candidates", "grid triangles considered over all levels"),
    counter("C_DROPPED_NO_RECEIVER", 28, "dropped_no_receiver", "beam families that meet no receiver (without a medium)"),
    state("C_LEAF_COST", 29, "beams the level's candidates emit if none splits (beam_budget)"),
    state("C_SPLIT_MIN_BIN", 30, "lowest priority bin that splits at this level (beam_budget)"),
    counter("C_SPLITS_DEFERRED", 31, "splits_deferred", "splits asked for that the beam budget left undone"),
    Word { span: Span::Families, ..counter("C_BEAMS_PER_FAMILY", 32, "beams_path", "beams emitted of each light-path family") },
    counter("C_BEAMS_REHIT", 42, "beams_path_rehit", "beams whose path meets a generator again (bounces)"),
    counter("C_BEAMS_TIR", 43, "beams_path_tir", "beams whose path is totally internally reflected on the way (bounces)"),
    state("C_ORPHAN_BASE", 44, "first orphan record slot of this level's leaves (splat_orphans)"),
    counter("C_ORPHAN_TOTAL", 45, "orphans", "orphan records written (splat_orphans)"),
    counter("C_OVERFLOW_ORPHANS", 46, "overflow_orphans", "orphan records that found no room (splat_orphans)"),
    counter("C_ORPHAN_CORNERS", 47, "orphan_corners", "landed corners of the orphan records (splat_orphans)"),
    counter("C_SPLIT_FAMILY", 48, "splits_family", "splits asked because a further light-path family parts ways"),
    counter("C_VERTEX_PATHS", 49, "vertex_paths", "main light paths the vertex cache traced, one per lattice vertex needed (0 without it)"),
    counter("C_VERTEX_CACHE_MISSES", 50, "vertex_cache_misses", "main paths read from the vertex cache that it had not traced (a defect: 0)"),
    state("C_LATTICE_LISTED", 51, "vertices gather_lattice listed for the vertex cache to trace (this level)"),
    state("C_LATTICE_TRACE", 52, "vertices trace_lattice traces (this level)"),
    counter("C_SPLIT_IRRADIANCE", 53, "splits_irradiance", "splits asked because the children spread the light unevenly"),
    counter("C_BEAMS_CLIPPED", 54, "beams_clipped", "clipped beams of leaves whose corners part ways (clip_leaves)"),
    counter("C_BEAMS_CLIPPED_EMPTY", 55, "beams_clipped_empty", "clipped beams too thin for a beam space, written empty (clip_leaves)"),
    counter("C_BEAMS_REBASED", 56, "beams_clipped_rebased", "clipped beams that start on the plane across their mean direction (clip_leaves)"),
    counter("C_BEAMS_LANDING", 58, "beams_clipped_landing", "clipped beams drawn as their landing triangle (clip_leaves)"),
    state("C_BEAMS_CLIPPED_BUDGET", 57, "clipped beams of the main path and the Fresnel reflection, which the budget does not count (clip_leaves)"),
    SPLIT_HISTOGRAM,
];

/// What each counter of both beam methods counts (`static-grid` and `adaptive-beams`
/// report the same set, summed over the scene's lights but `levels_run`): the control
/// words read back after the frame (the generate pass of the last frame, the count
/// frame), then the two that `BeamMethod::counters` derives and the two of the compute
/// rasterizer (`raster = compute`). A test checks that every counter they can report is
/// here, and nothing else.
#[rustfmt::skip]
pub const COUNTER_DOCS: &[CounterDoc] = &[
    CounterDoc { name: "base_triangles", doc: "triangles of the unrefined projected grid in each light's view, 2 per cell and light (2 x grid^2 x lights); set by the parameters, not counted on the GPU" },
    CounterDoc { name: "beams", doc: "beams written in the last frame's generate pass and rasterized as hulls, over all refinement levels, light-path families and lights (after splitting and dropping; at most max_beams per light)" },
    CounterDoc { name: "beams_level_N", doc: "beams written from leaves at refinement level N (0: the unrefined grid; one counter per level run), all families; they add up to beams" },
    CounterDoc { name: "beams_path_main", doc: "beams written of the main light path (refracted through each dielectric, reflected off mirrors: the paper's path)" },
    CounterDoc { name: "beams_path_fresnel_reflection", doc: "beams written of the Fresnel reflection off a dielectric's first interface (reflections = true; 0 without dielectrics)" },
    CounterDoc { name: "beams_path_internal_N", doc: "beams written of the light reflected N times inside the first object, a closed refractor, before it leaves (bounces >= N; one counter per N up to bounces)" },
    CounterDoc { name: "beams_path_rehit", doc: "beams written (any family) at least one of whose corner paths met the generator it had just left again and went on (a ring's opposite wall, a concave mesh; only with bounces > 0)" },
    CounterDoc { name: "beams_path_tir", doc: "beams written (any family) at least one of whose corner paths took a total internal reflection and went on (only with bounces > 0)" },
    CounterDoc { name: "beams_clipped", doc: "with clip_leaves: beams written from leaves whose corners part ways for a family (a silhouette, different paths or receivers), each the part of the leaf around a group of corners on one path, bounded by bisected points on its edges (2 for a pair of corners, 1 for a corner alone; 1, the whole leaf, where its corners agree but their exit points admit no beam space); counted in beams, beams_level_N and beams_path_*; without clip_leaves that light is lost" },
    CounterDoc { name: "beams_clipped_landing", doc: "with clip_leaves: clipped beams whose rays admit no beam space even rebased (they spread over more than a half-space or cross before the plane), drawn as the landing triangle of their corners instead: the corners lifted off their landing points against the rays' mean direction and sent back down along it (counted in beams_clipped)" },
    CounterDoc { name: "beams_clipped_rebased", doc: "with clip_leaves: clipped beams whose corners' exit points admit no beam space (a direction along or across their base plane), started instead where their rays cross the plane across their mean direction through the corner furthest along it (counted in beams_clipped)" },
    CounterDoc { name: "beams_clipped_empty", doc: "with clip_leaves: clipped beams whose corners admit no beam space (on a line, or an edge direction in the base plane), written with no light and a hull that covers no pixel (counted in beams_clipped and hulls_prism)" },
    CounterDoc { name: "candidates", doc: "grid triangles the split oracle looked at over all levels: the 2 x grid^2 base triangles plus the children of every split that fit in the candidate list" },
    CounterDoc { name: "dropped_discontinuity", doc: "leaves (triangles not split) that emit no beam because their three corners' main light paths differ: some corners miss the generators (a silhouette), or they meet different objects or event sequences, or land on different receivers" },
    CounterDoc { name: "dropped_invalid", doc: "leaves that emit no beam because none of their three corners' main light paths is valid (the light misses every generator, is totally internally reflected, or finds no exit)" },
    CounterDoc { name: "dropped_no_receiver", doc: "beams not emitted because their consistent corner paths meet no receiver (counted per leaf and light-path family; only in scenes without a participating medium, where such a beam adds nothing)" },
    CounterDoc { name: "hull_triangles", doc: "triangles of the beam hulls drawn by the rasterize pass: 8 per beam (8 x beams, derived)" },
    CounterDoc { name: "hulls_prism", doc: "beams whose hull is Ernst et al.'s bounding prism (hull = prism, or a tight hull with no unique choice of triangle at an edge)" },
    CounterDoc { name: "hulls_tight", doc: "beams whose hull is the paper's tight six-triangle hull (hull = tight and a unique choice at every edge); hulls_tight + hulls_prism = beams" },
    CounterDoc { name: "levels_run", doc: "levels of the grid the generate pass decided on, the unrefined grid included (levels + 1)" },
    CounterDoc { name: "orphan_corners", doc: "with splat_orphans: corners of the orphan records that landed on a receiver, each drawn as a one-pixel point of a third of its triangle's flux" },
    CounterDoc { name: "orphans", doc: "with splat_orphans: orphan records written, one per leaf and light-path family that emits no beam (its corners part ways) while some corner landed; without splat_orphans that light is lost" },
    CounterDoc { name: "overflow_beams", doc: "beams that found no room in the beam buffer (max_beams) and were not drawn: light missing from the image; 0 in a good run" },
    CounterDoc { name: "overflow_candidates", doc: "children of splits that found no room in the next level's candidate list (max_beams) and were not refined further: light missing from the image; 0 in a good run" },
    CounterDoc { name: "overflow_orphans", doc: "with splat_orphans: orphan records that found no room (as many slots as max_beams) and were not drawn: light missing from the image; 0 in a good run" },
    CounterDoc { name: "raster_pairs_lit", doc: "with raster = compute: the (beam, pixel) pairs of raster_pairs_shaded that added light (the pixel's ray meets the beam or its visible point lies in it): the fragments of the hardware path that add light" },
    CounterDoc { name: "raster_pairs_shaded", doc: "with raster = compute: (beam, pixel) pairs the compute rasterizer shaded, every pixel of each beam's hull rectangle (the hardware path shades only the pixels its hull covers, its rasterize fragments)" },
    CounterDoc { name: "splits_camera", doc: "triangles split by the camera criterion: the beam's base spans more than split_camera_px pixels where its central ray passes closest to the eye (0 in static-grid, which never splits; a triangle split for several reasons counts in each splits_*)" },
    CounterDoc { name: "splits_discontinuity", doc: "triangles split by the discontinuity criterion: corners partly missing the generators, on different paths, with normals or depths that differ too much, or an edge midpoint whose light lands off the linear prediction (0 in static-grid)" },
    CounterDoc { name: "splits_deferred", doc: "splits the oracle asked for that the beam budget left undone: the triangle stayed a leaf because splits of higher priority used the budget (0 without beam_budget; counted also in splits_*)" },
    CounterDoc { name: "splits_family", doc: "with split_families: triangles split because a light-path family beyond the main path (the Fresnel reflection, the internal reflections of bounces) parts ways at their corners while the main path does not and no other criterion asked (0 in static-grid)" },
    CounterDoc { name: "splits_irradiance", doc: "with split_irradiance: triangles split because the leaf's even irradiance is off from its four children's (their landing areas) by more than split_hit_px pixels' worth of light (0 in static-grid)" },
    CounterDoc { name: "splits_energy", doc: "triangles split by the energy criterion: the beam's flux relative to an unrefined beam's times how much it focuses where it is seen exceeds split_energy_threshold (0 in static-grid)" },
    CounterDoc { name: "vertex_cache_misses", doc: "main light paths decide or emit read from the vertex cache that no level had traced, read as paths that are not valid (light lost); 0 in a good run" },
    CounterDoc { name: "vertex_paths", doc: "main light paths the vertex cache traced, summed over the lights: one per vertex that some level's corners or split-oracle midpoints needed, traced once (without the cache a vertex is traced again for each triangle that has it as a corner, as an oracle midpoint and when its leaf is emitted); 0 where the cache's lattice of (grid x 2^levels + 1)^2 vertices does not fit its 64 MiB" },
];

impl Word {
    fn words(&self) -> usize {
        match self.span {
            Span::One => 1,
            Span::Levels => MAX_LEVELS as usize + 1,
            Span::Families => FAMILIES,
            Span::Bins => SPLIT_BINS,
        }
    }
}

/// The counter name of light-path family `f` (path.wgsl `FAMILY_*`).
fn family_name(prefix: &str, f: usize) -> String {
    match f {
        0 => format!("{prefix}_main"),
        1 => format!("{prefix}_fresnel_reflection"),
        _ => format!("{prefix}_internal_{}", f - 1),
    }
}

/// The `C_*` constants of generate.wgsl.
pub(crate) fn wgsl() -> String {
    let mut out = String::from(
        "// Words of `control`, generated from CONTROL in crates/beams/src/control.rs.\n",
    );
    for w in CONTROL {
        let span = match w.span {
            Span::One => String::new(),
            Span::Levels => format!(" ({} words, levels 0..{MAX_LEVELS})", w.words()),
            Span::Families => format!(" ({} words, families 0..{})", w.words(), FAMILIES - 1),
            Span::Bins => format!(" ({} words)", w.words()),
        };
        out.push_str(&format!(
            "const {}: u32 = {}u; // {}{span}\n",
            w.wgsl, w.index, w.doc
        ));
    }
    out.push_str(&format!(
        "const C_VERTEX_LISTS: u32 = {CONTROL_WORDS}u; // vertex_irradiance: per lattice vertex and family, {VERTEX_LIST_WORDS} words (a count, then beam slots)\n\
         const VERTEX_LIST_WORDS: u32 = {VERTEX_LIST_WORDS}u;\n\
         const VERTEX_LIST_SLOTS: u32 = {VERTEX_LIST_SLOTS}u;\n"
    ));
    out
}

/// The counters in the control words `c`, per-level ones for levels 0..=`levels`,
/// per-family ones for the families traced with `bounces`.
pub(crate) fn counters(c: &[u32], levels: u32, bounces: u32) -> Counters {
    let mut out = Counters::new();
    for w in CONTROL {
        let Some(name) = w.counter else { continue };
        match w.span {
            Span::One => {
                out.insert(name.to_owned(), u64::from(c[w.index]));
            }
            Span::Levels => {
                for level in 0..=levels as usize {
                    out.insert(format!("{name}_{level}"), u64::from(c[w.index + level]));
                }
            }
            Span::Families => {
                for f in 0..(2 + bounces as usize).min(FAMILIES) {
                    out.insert(family_name(name, f), u64::from(c[w.index + f]));
                }
            }
            Span::Bins => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_are_distinct_and_fit_the_buffer() {
        let mut used = [None; CONTROL_WORDS];
        for w in CONTROL {
            assert!(
                w.index + w.words() <= CONTROL_WORDS,
                "{} runs past the buffer",
                w.wgsl
            );
            for (i, slot) in used.iter_mut().enumerate().skip(w.index).take(w.words()) {
                if let Some(other) = slot.replace(w.wgsl) {
                    panic!("{} and {other} share word {i}", w.wgsl);
                }
            }
        }
        let names: std::collections::BTreeSet<_> =
            CONTROL.iter().filter_map(|w| w.counter).collect();
        assert_eq!(
            names.len(),
            CONTROL.iter().filter(|w| w.counter.is_some()).count()
        );
    }

    /// Every counter the beam methods can report (every level and family at the
    /// limits, the two `BeamMethod::counters` derives and the compute rasterizer's) has a doc, and every doc is
    /// of a counter they report.
    #[test]
    fn every_counter_is_documented() {
        let c = [0u32; CONTROL_WORDS];
        let mut names: Vec<String> = counters(&c, MAX_LEVELS, MAX_BOUNCES).into_keys().collect();
        names.extend(
            [
                "hull_triangles",
                "base_triangles",
                "raster_pairs_shaded",
                "raster_pairs_lit",
            ]
            .map(String::from),
        );
        if let Err(e) = caustics_method::CounterDoc::check(COUNTER_DOCS, &names) {
            panic!("{e}");
        }
    }

    #[test]
    fn counters_read_their_words() {
        let c: Vec<u32> = (0..CONTROL_WORDS as u32).collect();
        let out = counters(&c, 2, 2);
        assert_eq!(out["beams"], BEAM_TOTAL.index as u64);
        assert_eq!(out["levels_run"], LEVEL.index as u64);
        assert_eq!((out["beams_level_0"], out["beams_level_2"]), (15, 17));
        assert!(!out.contains_key("beams_level_3"));
        assert!(wgsl().contains("const C_BEAMS_PER_LEVEL: u32 = 15u;"));
        // Families 0..=3 with two bounces: main, reflection, 1 and 2 internal reflections.
        assert_eq!(
            (
                out["beams_path_main"],
                out["beams_path_fresnel_reflection"],
                out["beams_path_internal_1"],
                out["beams_path_internal_2"]
            ),
            (32, 33, 34, 35)
        );
        assert!(!out.contains_key("beams_path_internal_3"));
        assert_eq!((out["beams_path_rehit"], out["beams_path_tir"]), (42, 43));
        let paper = counters(&c, 0, 0);
        assert!(paper.contains_key("beams_path_fresnel_reflection"));
        assert!(!paper.keys().any(|k| k.starts_with("beams_path_internal")));
        assert!(wgsl().contains("const C_BEAMS_PER_FAMILY: u32 = 32u;"));
    }
}
