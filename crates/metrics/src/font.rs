//! Text for plots, colour bars and figures: DejaVu Sans (embedded from the `dejavu`
//! crate, no system fonts), rasterized with `ab_glyph` into an [`Rgb8Image`] with
//! anti-aliased coverage blending.
//!
//! Text is laid out on a fixed grid so that callers can place it with integer
//! arithmetic: [`draw_text`]'s `y` is the top of the capitals and digits, which stand
//! [`GLYPH_H`] pixels tall on the baseline; descenders reach [`DESCENT`] pixels below it
//! and accents or brackets may rise a pixel or two above `y`. [`text_width`] is the
//! advance of the whole string with kerning, in whole pixels.

use std::sync::LazyLock;

use ab_glyph::{Font, FontRef, GlyphId, PxScale, ScaleFont, point};

use crate::Rgb8Image;

/// Font size: the pixel height of the font's ascent − descent (`ab_glyph`'s scale).
/// DejaVu Sans' capitals are 1,493 of its 2,384 units, 7.5 px at 12.
const SCALE_PX: f32 = 12.0;
/// Height in pixels of capitals and digits above the baseline (the layout unit).
pub const GLYPH_H: u32 = 8;
/// How far descenders (g, p, y, comma) reach below the baseline, in pixels.
pub const DESCENT: u32 = 3;

static FONT: LazyLock<FontRef<'static>> = LazyLock::new(|| {
    // The bytes are compiled in and never change: a failure is a broken build.
    FontRef::try_from_slice(dejavu::sans::regular()).expect("DejaVu Sans parses")
});

/// The glyphs of `text` with their pen positions (x of the origin, in pixels).
fn layout(text: &str) -> (Vec<(GlyphId, f32)>, f32) {
    let font = FONT.as_scaled(PxScale::from(SCALE_PX));
    let mut pen = 0.0;
    let mut prev: Option<GlyphId> = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = font.glyph_id(c);
        if let Some(p) = prev {
            pen += font.kern(p, id);
        }
        glyphs.push((id, pen));
        pen += font.h_advance(id);
        prev = Some(id);
    }
    (glyphs, pen)
}

/// Width in pixels of `text` drawn horizontally.
pub fn text_width(text: &str) -> u32 {
    layout(text).1.ceil() as u32
}

/// Calls `ink(dx, dy, coverage)` for every covered pixel of `text`, `(dx, dy)` relative
/// to the top-left of its box (`dy` = 0 at the capitals' top; may be negative above it).
fn rasterize(text: &str, mut ink: impl FnMut(i32, i32, f32)) {
    let font = FONT.as_scaled(PxScale::from(SCALE_PX));
    let baseline = GLYPH_H as f32;
    for (id, x) in layout(text).0 {
        let glyph = id.with_scale_and_position(font.scale(), point(x, baseline));
        if let Some(outline) = FONT.outline_glyph(glyph) {
            let b = outline.px_bounds();
            let (x0, y0) = (b.min.x as i32, b.min.y as i32);
            outline.draw(|gx, gy, c| ink(x0 + gx as i32, y0 + gy as i32, c));
        }
    }
}

fn blend(img: &mut Rgb8Image, x: i64, y: i64, colour: [u8; 3], coverage: f32) {
    if x < 0 || y < 0 || x >= i64::from(img.width) || y >= i64::from(img.height) {
        return;
    }
    let (x, y) = (x as u32, y as u32);
    let a = coverage.clamp(0.0, 1.0);
    let under = img.get(x, y);
    let mix = |u: u8, c: u8| (f32::from(u) * (1.0 - a) + f32::from(c) * a).round() as u8;
    img.set(
        x,
        y,
        [
            mix(under[0], colour[0]),
            mix(under[1], colour[1]),
            mix(under[2], colour[2]),
        ],
    );
}

/// Draws `text` left to right, the top of its capitals at `(x, y)`; clipped to the image.
pub fn draw_text(img: &mut Rgb8Image, x: u32, y: u32, text: &str, colour: [u8; 3]) {
    rasterize(text, |dx, dy, c| {
        blend(
            img,
            i64::from(x) + i64::from(dx),
            i64::from(y) + i64::from(dy),
            colour,
            c,
        );
    });
}

/// Draws `text` rotated 90° counter-clockwise (reading bottom to top, like a plot's y-axis
/// label): the capitals' top on column `x`, their baseline on column `x + GLYPH_H`
/// (descenders to the right of it), starting at row `y_bottom`. Clipped to the image.
pub fn draw_text_vertical(img: &mut Rgb8Image, x: u32, y_bottom: u32, text: &str, colour: [u8; 3]) {
    rasterize(text, |dx, dy, c| {
        // Rotating CCW: the text's x runs up the image, its y runs right.
        blend(
            img,
            i64::from(x) + i64::from(dy),
            i64::from(y_bottom) - i64::from(dx),
            colour,
            c,
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lit(img: &Rgb8Image) -> Vec<(u32, u32)> {
        (0..img.height)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x, y) != [0; 3])
            .collect()
    }

    #[test]
    fn capitals_stand_on_the_baseline_and_descenders_go_below() {
        let mut img = Rgb8Image::new(40, 20);
        draw_text(&mut img, 2, 4, "HE", [255; 3]);
        let caps = lit(&img);
        assert!(!caps.is_empty());
        let (top, bottom) = (
            caps.iter().map(|p| p.1).min().unwrap_or(0),
            caps.iter().map(|p| p.1).max().unwrap_or(0),
        );
        // 7.5 px capitals from row 4 to the baseline at row 4 + GLYPH_H.
        assert!((4..=5).contains(&top), "top {top}");
        assert_eq!(bottom, 4 + GLYPH_H - 1, "capitals end on the baseline");
        assert!(
            caps.iter()
                .all(|p| p.0 >= 2 && p.0 < 2 + text_width("HE") + 1)
        );

        let mut img = Rgb8Image::new(40, 20);
        draw_text(&mut img, 2, 4, "gy", [255; 3]);
        let low = lit(&img).iter().map(|p| p.1).max().unwrap_or(0);
        assert!(
            (4 + GLYPH_H..4 + GLYPH_H + DESCENT).contains(&low),
            "descender to row {low}"
        );
    }

    #[test]
    fn upper_and_lower_case_differ_and_widths_grow_with_the_text() {
        let draw = |t: &str| {
            let mut img = Rgb8Image::new(60, 16);
            draw_text(&mut img, 1, 3, t, [255; 3]);
            img
        };
        assert_ne!(lit(&draw("P")), lit(&draw("p")));
        assert!(text_width("relMSE") > text_width("rel"));
        assert!(text_width("W") > text_width("i"));
        // About 6 px a character at this size, as the layouts assume.
        let w = text_width("method GPU ms") as f32 / 13.0;
        assert!((5.0..7.5).contains(&w), "{w} px per character");
    }

    #[test]
    fn vertical_text_is_the_horizontal_text_rotated() {
        let mut h = Rgb8Image::new(60, 20);
        draw_text(&mut h, 0, 2, "Ay", [255; 3]);
        let mut v = Rgb8Image::new(20, 60);
        draw_text_vertical(&mut v, 2, 59, "Ay", [255; 3]);
        let mut rotated: Vec<(u32, u32)> = lit(&h).iter().map(|&(x, y)| (y, 59 - x)).collect();
        rotated.sort_unstable();
        let mut got = lit(&v);
        got.sort_unstable();
        assert_eq!(rotated, got);
    }

    #[test]
    fn text_off_the_image_is_clipped_not_a_panic() {
        let mut img = Rgb8Image::new(8, 8);
        draw_text(&mut img, 2, 1, "HELLO WORLD", [255; 3]);
        draw_text_vertical(&mut img, 0, 3, "HELLO WORLD", [255; 3]);
        draw_text(&mut img, 7, 7, "HELLO", [255; 3]);
        assert!(!lit(&img).is_empty());
    }
}
