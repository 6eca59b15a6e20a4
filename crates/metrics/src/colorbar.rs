//! The colour-bar panel shared by heatmaps and error maps: a vertical bar, ticks with
//! labels at stated scale positions, optional end caps for out-of-range values, and a
//! vertical title.

use crate::Rgb8Image;
use crate::font::{self, DESCENT, GLYPH_H};
use crate::heatmap::{COLOR_BAR_WIDTH, MIN_MAP_HEIGHT, PANEL_BACKGROUND};

pub(crate) const LABEL_COLOUR: [u8; 3] = [235, 235, 235];

// Panel layout, in columns relative to the panel's left edge.
pub(crate) const BAR_X: u32 = 6;
pub(crate) const BAR_W: u32 = 12;
/// A tick is a short mark touching the bar's right edge; its label starts a clear gap
/// after it, so that mark and label do not read as a minus sign.
const TICK_W: u32 = 2;
const LABEL_X: u32 = BAR_X + BAR_W + TICK_W + 3;
/// The vertical title's capitals start here; its descenders end a pixel inside the panel.
const TITLE_X: u32 = COLOR_BAR_WIDTH - GLYPH_H - DESCENT - 1;
const MARGIN_Y: u32 = 4;
/// Rows of an end cap (plus one row of background between cap and bar).
pub(crate) const CAP_H: u32 = 4;

/// What the panel shows.
pub(crate) struct ColourBar<'a> {
    /// Colour of scale position `t ∈ [0, 1]` (0 at the bottom of the bar).
    pub(crate) colour: &'a dyn Fn(f64) -> [u8; 3],
    /// `(t, label)` in order of priority: a tick whose label would overlap one drawn
    /// before it is left out, so list the ends first.
    pub(crate) ticks: Vec<(f64, String)>,
    /// Written vertically along the right edge of the panel.
    pub(crate) title: &'a str,
    /// Colours of the caps drawn above (values beyond the top) and below (beyond the
    /// bottom) the bar, for maps that clip.
    pub(crate) caps: Option<([u8; 3], [u8; 3])>,
}

/// Copies `area` into a wider image and draws `bar` in a [`COLOR_BAR_WIDTH`] panel on its
/// right; the output is at least [`MIN_MAP_HEIGHT`] rows high, and high enough for the
/// whole title (below a small map the panel's background continues).
pub(crate) fn with_colour_bar(area: &Rgb8Image, bar: &ColourBar<'_>) -> Rgb8Image {
    let title_len = font::text_width(bar.title);
    let out_h = area
        .height
        .max(MIN_MAP_HEIGHT)
        .max(title_len + 2 * MARGIN_Y + 2);
    let mut out = Rgb8Image::filled(area.width + COLOR_BAR_WIDTH, out_h, PANEL_BACKGROUND);
    for y in 0..area.height {
        for x in 0..area.width {
            out.set(x, y, area.get(x, y));
        }
    }
    let px = area.width;
    let (mut top, mut bottom) = (MARGIN_Y, out_h - 1 - MARGIN_Y);
    if let Some((above, below)) = bar.caps {
        for i in 0..CAP_H {
            for x in 0..BAR_W {
                out.set(px + BAR_X + x, top + i, above);
                out.set(px + BAR_X + x, bottom - i, below);
            }
        }
        top += CAP_H + 1;
        bottom -= CAP_H + 1;
    }
    let span = f64::from(bottom - top);
    for y in top..=bottom {
        let t = f64::from(bottom - y) / span;
        for x in 0..BAR_W {
            out.set(px + BAR_X + x, y, (bar.colour)(t));
        }
    }
    // Labels centred vertically on their bar position, clamped into the image; a label
    // overlapping one already drawn is dropped.
    let half = GLYPH_H / 2;
    let mut drawn: Vec<u32> = Vec::new();
    for (t, label) in &bar.ticks {
        let y_tick = f64::from(bottom) - t.clamp(0.0, 1.0) * span;
        let y_tick = y_tick.round() as u32;
        let y = y_tick.saturating_sub(half).min(out_h - GLYPH_H);
        if drawn.iter().any(|&d| d.abs_diff(y) <= GLYPH_H) {
            continue;
        }
        drawn.push(y);
        for x in BAR_X + BAR_W..BAR_X + BAR_W + TICK_W {
            out.set(px + x, y_tick, LABEL_COLOUR);
        }
        font::draw_text(&mut out, px + LABEL_X, y, label, LABEL_COLOUR);
    }
    let room = out_h - 2 * MARGIN_Y;
    let y_bottom = out_h - MARGIN_Y - 1 - room.saturating_sub(title_len) / 2;
    font::draw_text_vertical(&mut out, px + TITLE_X, y_bottom, bar.title, LABEL_COLOUR);
    out
}
