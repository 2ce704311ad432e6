//! A 3×5 pixel font (digits, capitals, a few signs) for the labels of figures and legends,
//! so they need no font file. Each glyph is five rows of three cells, `#` for ink.

use image::{Rgba, RgbaImage};

/// Glyph rows, top to bottom.
const GLYPHS: &[(char, [&str; 5])] = &[
    ('0', ["###", "#.#", "#.#", "#.#", "###"]),
    ('1', [".#.", "##.", ".#.", ".#.", "###"]),
    ('2', ["###", "..#", "###", "#..", "###"]),
    ('3', ["###", "..#", "###", "..#", "###"]),
    ('4', ["#.#", "#.#", "###", "..#", "..#"]),
    ('5', ["###", "#..", "###", "..#", "###"]),
    ('6', ["###", "#..", "###", "#.#", "###"]),
    ('7', ["###", "..#", "..#", "..#", "..#"]),
    ('8', ["###", "#.#", "###", "#.#", "###"]),
    ('9', ["###", "#.#", "###", "..#", "###"]),
    ('.', ["...", "...", "...", "...", ".#."]),
    ('-', ["...", "...", "###", "...", "..."]),
    (':', ["...", ".#.", "...", ".#.", "..."]),
    ('/', ["..#", "..#", ".#.", "#..", "#.."]),
    ('(', [".#.", "#..", "#..", "#..", ".#."]),
    (')', [".#.", "..#", "..#", "..#", ".#."]),
    ('=', ["...", "###", "...", "###", "..."]),
    (' ', ["...", "...", "...", "...", "..."]),
    ('+', ["...", ".#.", "###", ".#.", "..."]),
    (',', ["...", "...", "...", ".#.", "#.."]),
    ('%', ["#.#", "..#", ".#.", "#..", "#.#"]),
    ('A', [".#.", "#.#", "###", "#.#", "#.#"]),
    ('B', ["##.", "#.#", "##.", "#.#", "##."]),
    ('C', ["###", "#..", "#..", "#..", "###"]),
    ('D', ["##.", "#.#", "#.#", "#.#", "##."]),
    ('E', ["###", "#..", "##.", "#..", "###"]),
    ('F', ["###", "#..", "##.", "#..", "#.."]),
    ('G', ["###", "#..", "#.#", "#.#", "###"]),
    ('H', ["#.#", "#.#", "###", "#.#", "#.#"]),
    ('I', ["###", ".#.", ".#.", ".#.", "###"]),
    ('J', ["..#", "..#", "..#", "#.#", "###"]),
    ('K', ["#.#", "#.#", "##.", "#.#", "#.#"]),
    ('L', ["#..", "#..", "#..", "#..", "###"]),
    ('M', ["#.#", "###", "###", "#.#", "#.#"]),
    ('N', ["##.", "#.#", "#.#", "#.#", "#.#"]),
    ('O', ["###", "#.#", "#.#", "#.#", "###"]),
    ('P', ["###", "#.#", "###", "#..", "#.."]),
    ('Q', ["###", "#.#", "#.#", "##.", "..#"]),
    ('R', ["##.", "#.#", "##.", "#.#", "#.#"]),
    ('S', ["###", "#..", "###", "..#", "###"]),
    ('T', ["###", ".#.", ".#.", ".#.", ".#."]),
    ('U', ["#.#", "#.#", "#.#", "#.#", "###"]),
    ('V', ["#.#", "#.#", "#.#", "#.#", ".#."]),
    ('W', ["#.#", "#.#", "###", "###", "#.#"]),
    ('X', ["#.#", "#.#", ".#.", "#.#", "#.#"]),
    ('Z', ["###", "..#", ".#.", "#..", "###"]),
    ('Y', ["#.#", "#.#", ".#.", ".#.", ".#."]),
];

/// Pixels per font cell.
pub const SCALE: u32 = 2;
/// Width of one character with its spacing, pixels.
pub const ADVANCE: u32 = 4 * SCALE;
/// Height of a line of text, pixels.
pub const LINE_HEIGHT: u32 = 5 * SCALE;

/// Width of `text` in pixels.
pub fn text_width(text: &str) -> u32 {
    (text.chars().count() as u32 * ADVANCE).saturating_sub(SCALE)
}

/// Draws `text` (upper-cased; unknown characters as blanks) with its top-left corner at
/// `(x, y)`, clipped to the image.
pub fn draw_text(img: &mut RgbaImage, x: u32, y: u32, text: &str, colour: Rgba<u8>) {
    for (k, ch) in text.chars().enumerate() {
        let ch = ch.to_ascii_uppercase();
        let Some((_, rows)) = GLYPHS.iter().find(|(c, _)| *c == ch) else {
            continue;
        };
        let x0 = x + k as u32 * ADVANCE;
        for (r, row) in rows.iter().enumerate() {
            for (c, b) in row.bytes().enumerate() {
                if b != b'#' {
                    continue;
                }
                for dy in 0..SCALE {
                    for dx in 0..SCALE {
                        let (px, py) = (x0 + c as u32 * SCALE + dx, y + r as u32 * SCALE + dy);
                        if px < img.width() && py < img.height() {
                            img.put_pixel(px, py, colour);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_well_formed_and_text_is_drawn_and_clipped() {
        for (c, rows) in GLYPHS {
            assert!(rows.iter().all(|r| r.len() == 3), "{c}");
        }
        let mut img = RgbaImage::new(20, 12);
        draw_text(&mut img, 0, 0, "1.5", Rgba([0, 0, 0, 255]));
        // '1' has ink at font cell (1, 0): pixels (2..4, 0..2).
        assert_eq!(img.get_pixel(2, 0)[3], 255);
        assert_eq!(img.get_pixel(0, 0)[3], 0);
        assert_eq!(text_width("1.5"), 3 * ADVANCE - SCALE);
        draw_text(&mut img, 15, 8, "888", Rgba([0, 0, 0, 255])); // clipped, no panic
    }
}
