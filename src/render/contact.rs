//! Contact sheets of rendered frames: thumbnails side by side, each
//! labelled underneath (time, mode, action), composed on the CPU.

use super::headless::Image;

/// Box-filter `img` down by an integer `factor`.
#[must_use]
pub fn downscale(img: &Image, factor: u32) -> Image {
    let f = factor.max(1);
    let (w, h) = (img.width / f, img.height / f);
    let mut out = Image::filled(w, h, [0, 0, 0, 255]);
    let n = f * f;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 4];
            for dy in 0..f {
                for dx in 0..f {
                    let p = img.pixel(x * f + dx, y * f + dy);
                    for (a, v) in acc.iter_mut().zip(p) {
                        *a += u32::from(v);
                    }
                }
            }
            let i = ((y * w + x) * 4) as usize;
            for (o, a) in out.rgba[i..i + 4].iter_mut().zip(acc) {
                *o = (a / n) as u8;
            }
        }
    }
    out
}

/// Draw `text` in the 8x8 bitmap font at (`x`, `y`), one image pixel per
/// font pixel.
pub fn draw_text(img: &mut Image, x: u32, y: u32, text: &str, rgba: [u8; 4]) {
    for (i, ch) in text.chars().enumerate() {
        let code = if (ch as u32) < 128 {
            ch as usize
        } else {
            '?' as usize
        };
        let glyph = font8x8::legacy::BASIC_LEGACY[code];
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8u32 {
                if bits & (1 << col) == 0 {
                    continue;
                }
                let (px, py) = (x + i as u32 * 8 + col, y + row as u32);
                if px < img.width && py < img.height {
                    let k = ((py * img.width + px) * 4) as usize;
                    img.rgba[k..k + 4].copy_from_slice(&rgba);
                }
            }
        }
    }
}

/// Thumbnails (each `factor` times smaller) in rows of `columns`, with a
/// label under each.
#[must_use]
pub fn sheet(frames: &[(&Image, String)], columns: u32, factor: u32) -> Image {
    const LABEL: u32 = 16;
    const GAP: u32 = 6;
    let Some((first, _)) = frames.first() else {
        return Image::filled(1, 1, [20, 20, 24, 255]);
    };
    let (tw, th) = (first.width / factor.max(1), first.height / factor.max(1));
    let cols = columns.max(1).min(frames.len() as u32);
    let rows = (frames.len() as u32).div_ceil(cols);
    let (cw, ch) = (tw + GAP, th + LABEL + GAP);
    let mut out = Image::filled(cols * cw + GAP, rows * ch + GAP, [20, 20, 24, 255]);
    for (i, (img, label)) in frames.iter().enumerate() {
        let (c, r) = (i as u32 % cols, i as u32 / cols);
        let (x, y) = (GAP + c * cw, GAP + r * ch);
        out.blit(&downscale(img, factor), x, y);
        let max_chars = (tw / 8) as usize;
        let text: String = label.chars().take(max_chars).collect();
        draw_text(&mut out, x + 2, y + th + 4, &text, [235, 235, 235, 255]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_places_thumbnails_and_labels() {
        let a = Image::filled(40, 20, [200, 0, 0, 255]);
        let b = Image::filled(40, 20, [0, 0, 200, 255]);
        let s = sheet(&[(&a, "a".into()), (&b, "b".into())], 2, 2);
        assert_eq!((s.width, s.height), (6 + 2 * 26, 6 + 10 + 16 + 6));
        assert_eq!(s.pixel(7, 7), [200, 0, 0, 255]);
        assert_eq!(s.pixel(6 + 26 + 1, 7), [0, 0, 200, 255]);
        // The label's glyph pixels are light.
        let lit = (0..s.width)
            .flat_map(|x| (16..32).map(move |y| (x, y)))
            .filter(|&(x, y)| s.pixel(x, y)[0] > 200 && s.pixel(x, y)[2] > 200)
            .count();
        assert!(lit > 10);
    }
}
