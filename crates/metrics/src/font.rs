//! A tiny embedded 5×7 bitmap font for labels on colour bars.
//!
//! Covers digits, `. + - / : ( ) % = _ |`, space, `a`–`z`, `M` (for "mega"), `W` and `Y`
//! (for units `W/m2/sr` and luminance `Y`; there are no superscripts); other
//! upper-case letters are drawn with their lower-case glyph, and anything else as `?`.

use crate::Rgb8Image;

/// Glyph width in pixels.
pub(crate) const GLYPH_W: u32 = 5;
/// Glyph height in pixels.
pub const GLYPH_H: u32 = 7;
/// Horizontal advance per character (glyph plus one pixel of spacing).
pub(crate) const ADVANCE: u32 = GLYPH_W + 1;

type Glyph = [&'static str; 7];

#[rustfmt::skip]
const GLYPHS: &[(char, Glyph)] = &[
    ('0', [".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."]),
    ('1', ["..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."]),
    ('2', [".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"]),
    ('3', ["#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."]),
    ('4', ["...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."]),
    ('5', ["#####", "#....", "####.", "....#", "....#", "#...#", ".###."]),
    ('6', ["..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."]),
    ('7', ["#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."]),
    ('8', [".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."]),
    ('9', [".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."]),
    ('.', [".....", ".....", ".....", ".....", ".....", ".##..", ".##.."]),
    ('+', [".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."]),
    ('-', [".....", ".....", ".....", "#####", ".....", ".....", "....."]),
    ('/', [".....", "....#", "...#.", "..#..", ".#...", "#....", "....."]),
    (':', [".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."]),
    ('(', ["...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."]),
    (')', [".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."]),
    ('%', ["##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"]),
    ('=', [".....", ".....", "#####", ".....", "#####", ".....", "....."]),
    ('_', [".....", ".....", ".....", ".....", ".....", ".....", "#####"]),
    ('|', ["..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."]),
    ('?', [".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."]),
    (' ', [".....", ".....", ".....", ".....", ".....", ".....", "....."]),
    ('M', ["#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"]),
    ('W', ["#...#", "#...#", "#...#", "#.#.#", "#.#.#", "##.##", "#...#"]),
    ('Y', ["#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."]),
    ('a', [".....", ".....", ".###.", "....#", ".####", "#...#", ".####"]),
    ('b', ["#....", "#....", "####.", "#...#", "#...#", "#...#", "####."]),
    ('c', [".....", ".....", ".####", "#....", "#....", "#....", ".####"]),
    ('d', ["....#", "....#", ".####", "#...#", "#...#", "#...#", ".####"]),
    ('e', [".....", ".....", ".###.", "#...#", "#####", "#....", ".###."]),
    ('f', ["..##.", ".#...", "####.", ".#...", ".#...", ".#...", ".#..."]),
    ('g', [".....", ".####", "#...#", "#...#", ".####", "....#", ".###."]),
    ('h', ["#....", "#....", "####.", "#...#", "#...#", "#...#", "#...#"]),
    ('i', ["..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."]),
    ('j', ["...#.", ".....", "..##.", "...#.", "...#.", "#..#.", ".##.."]),
    ('k', ["#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."]),
    ('l', [".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."]),
    ('m', [".....", ".....", "##.#.", "#.#.#", "#.#.#", "#.#.#", "#.#.#"]),
    ('n', [".....", ".....", "####.", "#...#", "#...#", "#...#", "#...#"]),
    ('o', [".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."]),
    ('p', [".....", "####.", "#...#", "#...#", "####.", "#....", "#...."]),
    ('q', [".....", ".####", "#...#", "#...#", ".####", "....#", "....#"]),
    ('r', [".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."]),
    ('s', [".....", ".....", ".####", "#....", ".###.", "....#", "####."]),
    ('t', [".#...", ".#...", "####.", ".#...", ".#...", ".#..#", "..##."]),
    ('u', [".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#"]),
    ('v', [".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#.."]),
    ('w', [".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#."]),
    ('x', [".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"]),
    ('y', [".....", "#...#", "#...#", "#...#", ".####", "....#", ".###."]),
    ('z', [".....", ".....", "#####", "...#.", "..#..", ".#...", "#####"]),
];

fn glyph(c: char) -> &'static Glyph {
    let find = |c: char| GLYPHS.iter().find(|(g, _)| *g == c).map(|(_, rows)| rows);
    find(c)
        .or_else(|| find(c.to_ascii_lowercase()))
        .or_else(|| find('?'))
        .unwrap_or(&GLYPHS[0].1)
}

/// Whether glyph pixel `(gx, gy)` of `c` is set.
fn ink(c: char, gx: u32, gy: u32) -> bool {
    glyph(c)[gy as usize].as_bytes()[gx as usize] == b'#'
}

/// Width in pixels of `text` drawn horizontally (no trailing spacing).
pub fn text_width(text: &str) -> u32 {
    let n = text.chars().count() as u32;
    (n * ADVANCE).saturating_sub(1)
}

/// Draws `text` left to right with its top-left corner at `(x, y)`; clipped to the image.
pub fn draw_text(img: &mut Rgb8Image, x: u32, y: u32, text: &str, colour: [u8; 3]) {
    for (i, c) in text.chars().enumerate() {
        let x0 = x + i as u32 * ADVANCE;
        for gy in 0..GLYPH_H {
            for gx in 0..GLYPH_W {
                if ink(c, gx, gy) {
                    img.set(x0 + gx, y + gy, colour);
                }
            }
        }
    }
}

/// Draws `text` rotated 90° counter-clockwise (reading bottom to top, like a plot's y-axis
/// label) in the column `x .. x + GLYPH_H`, starting at the bottom row `y_bottom`.
/// Characters that would run above row 0 are dropped.
pub fn draw_text_vertical(img: &mut Rgb8Image, x: u32, y_bottom: u32, text: &str, colour: [u8; 3]) {
    for (i, c) in text.chars().enumerate() {
        let offset = i as u32 * ADVANCE + GLYPH_W - 1;
        let Some(top) = y_bottom.checked_sub(offset) else {
            return;
        };
        for gy in 0..GLYPH_H {
            for gx in 0..GLYPH_W {
                if ink(c, gx, gy) {
                    // Rotating CCW: glyph x runs up the image, glyph y runs right.
                    img.set(x + gy, top + (GLYPH_W - 1 - gx), colour);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_is_5x7_and_unique() {
        for (c, rows) in GLYPHS {
            for row in rows {
                assert_eq!(row.len(), GLYPH_W as usize, "glyph {c:?}");
                assert!(row.bytes().all(|b| b == b'#' || b == b'.'), "glyph {c:?}");
            }
            assert_eq!(GLYPHS.iter().filter(|(d, _)| d == c).count(), 1, "{c:?}");
        }
        for c in "0123456789.e+-kM/fragmentspx".chars() {
            assert!(GLYPHS.iter().any(|(g, _)| *g == c), "missing {c:?}");
        }
    }

    #[test]
    fn draws_ink_inside_its_box() {
        let mut img = Rgb8Image::new(20, 10);
        draw_text(&mut img, 1, 1, "1.", [255; 3]);
        let lit: Vec<_> = (0..10)
            .flat_map(|y| (0..20).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x, y) == [255; 3])
            .collect();
        assert!(!lit.is_empty());
        assert!(
            lit.iter()
                .all(|&(x, y)| (1..12).contains(&x) && (1..8).contains(&y))
        );
        assert_eq!(text_width("1."), 11);
    }
}
