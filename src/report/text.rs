//! Labels on plots: a 3×5-pixel bitmap font (digits, letters drawn in capitals, a few signs),
//! scaled by whole pixels. Enough for axis names, units, tick values and legends without a
//! font dependency; characters it does not know are drawn as a hollow box.

/// Rows top to bottom, `#` = ink.
const GLYPHS: &[(char, [&str; 5])] = &[
    ('0', ["###", "#.#", "#.#", "#.#", "###"]),
    ('1', [".#.", "##.", ".#.", ".#.", "###"]),
    ('2', ["###", "..#", "###", "#..", "###"]),
    ('3', ["###", "..#", ".##", "..#", "###"]),
    ('4', ["#.#", "#.#", "###", "..#", "..#"]),
    ('5', ["###", "#..", "###", "..#", "###"]),
    ('6', ["###", "#..", "###", "#.#", "###"]),
    ('7', ["###", "..#", ".#.", ".#.", ".#."]),
    ('8', ["###", "#.#", "###", "#.#", "###"]),
    ('9', ["###", "#.#", "###", "..#", "###"]),
    ('A', [".#.", "#.#", "###", "#.#", "#.#"]),
    ('B', ["##.", "#.#", "##.", "#.#", "##."]),
    ('C', [".##", "#..", "#..", "#..", ".##"]),
    ('D', ["##.", "#.#", "#.#", "#.#", "##."]),
    ('E', ["###", "#..", "##.", "#..", "###"]),
    ('F', ["###", "#..", "##.", "#..", "#.."]),
    ('G', [".##", "#..", "#.#", "#.#", ".##"]),
    ('H', ["#.#", "#.#", "###", "#.#", "#.#"]),
    ('I', ["###", ".#.", ".#.", ".#.", "###"]),
    ('J', ["..#", "..#", "..#", "#.#", ".#."]),
    ('K', ["#.#", "#.#", "##.", "#.#", "#.#"]),
    ('L', ["#..", "#..", "#..", "#..", "###"]),
    ('M', ["#.#", "###", "###", "#.#", "#.#"]),
    ('N', ["##.", "#.#", "#.#", "#.#", "#.#"]),
    ('O', [".#.", "#.#", "#.#", "#.#", ".#."]),
    ('P', ["##.", "#.#", "##.", "#..", "#.."]),
    ('Q', [".#.", "#.#", "#.#", "##.", ".##"]),
    ('R', ["##.", "#.#", "##.", "#.#", "#.#"]),
    ('S', [".##", "#..", ".#.", "..#", "##."]),
    ('T', ["###", ".#.", ".#.", ".#.", ".#."]),
    ('U', ["#.#", "#.#", "#.#", "#.#", "###"]),
    ('V', ["#.#", "#.#", "#.#", "#.#", ".#."]),
    ('W', ["#.#", "#.#", "###", "###", "#.#"]),
    ('X', ["#.#", "#.#", ".#.", "#.#", "#.#"]),
    ('Y', ["#.#", "#.#", ".#.", ".#.", ".#."]),
    ('Z', ["###", "..#", ".#.", "#..", "###"]),
    (' ', ["...", "...", "...", "...", "..."]),
    ('.', ["...", "...", "...", "...", ".#."]),
    (',', ["...", "...", "...", ".#.", "#.."]),
    (':', ["...", ".#.", "...", ".#.", "..."]),
    ('-', ["...", "...", "###", "...", "..."]),
    ('+', ["...", ".#.", "###", ".#.", "..."]),
    ('/', ["..#", "..#", ".#.", "#..", "#.."]),
    ('(', [".#.", "#..", "#..", "#..", ".#."]),
    (')', [".#.", "..#", "..#", "..#", ".#."]),
    ('%', ["#.#", "..#", ".#.", "#..", "#.#"]),
    ('=', ["...", "###", "...", "###", "..."]),
];

/// The box drawn for characters the font does not have.
const UNKNOWN: [&str; 5] = ["###", "###", "###", "###", "###"];

fn glyph(c: char) -> [&'static str; 5] {
    let c = c.to_ascii_uppercase();
    GLYPHS
        .iter()
        .find(|(g, _)| *g == c)
        .map_or(UNKNOWN, |(_, rows)| *rows)
}

/// Width in pixels of `text` at `scale` (4 columns per character: 3 of ink, 1 of space).
pub(crate) fn text_width(text: &str, scale: u32) -> u32 {
    (text.chars().count() as u32 * 4).saturating_sub(1) * scale
}

/// Height in pixels of a line of text at `scale`.
pub(crate) fn text_height(scale: u32) -> u32 {
    5 * scale
}

/// Draws `text` with its top-left corner at `(x, y)`, each font pixel a `scale`×`scale` block;
/// what falls outside the image is clipped.
pub(crate) fn draw_text(
    img: &mut image::RgbaImage,
    (x, y): (i64, i64),
    text: &str,
    scale: u32,
    color: image::Rgba<u8>,
) {
    let s = i64::from(scale.max(1));
    for (k, c) in text.chars().enumerate() {
        let left = x + k as i64 * 4 * s;
        for (row, bits) in glyph(c).iter().enumerate() {
            for (col, b) in bits.bytes().enumerate() {
                if b != b'#' {
                    continue;
                }
                for dy in 0..s {
                    for dx in 0..s {
                        let (px, py) = (left + col as i64 * s + dx, y + row as i64 * s + dy);
                        if px >= 0
                            && py >= 0
                            && (px as u64) < u64::from(img.width())
                            && (py as u64) < u64::from(img.height())
                        {
                            img.put_pixel(px as u32, py as u32, color);
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

    /// Every glyph has 5 rows of 3 columns, and no two glyphs look the same (so a label
    /// reads as what it says).
    #[test]
    fn glyphs_are_well_formed_and_distinct() {
        for (c, rows) in GLYPHS {
            assert!(rows.iter().all(|r| r.len() == 3), "{c}");
        }
        for (i, (a, ra)) in GLYPHS.iter().enumerate() {
            for (b, rb) in &GLYPHS[i + 1..] {
                assert_ne!(ra, rb, "{a} and {b} look alike");
            }
        }
    }

    /// Drawn text covers exactly its glyphs' ink, scaled; lower case draws as upper case.
    #[test]
    fn text_draws_its_ink_at_scale() {
        let mut img = image::RgbaImage::from_pixel(40, 20, image::Rgba([255, 255, 255, 255]));
        let ink = image::Rgba([0, 0, 0, 255]);
        draw_text(&mut img, (1, 2), "1x", 2, ink);
        let inked = img.pixels().filter(|p| **p == ink).count();
        // '1' has 8 ink pixels, 'X' 9; each is a 2×2 block.
        assert_eq!(inked, (8 + 9) * 4);
        assert_eq!(text_width("1x", 2), 14);
        assert_eq!(img.get_pixel(3, 2), &ink, "top of the 1");
        assert_eq!(img.get_pixel(1, 2), &image::Rgba([255, 255, 255, 255]));
    }
}
