//! Full-screen messages on the display: the calibration's targets and
//! words, and the error screen of a kiosk that cannot start.

use crate::render::contact::draw_text;
use crate::render::headless::Image;
use crate::screen::{Rotation, ScreenPoint};

/// A picture-sized screen with a target, a message and a hint.
pub fn screen(
    size: (u32, u32),
    target: Option<ScreenPoint>,
    lines: &[&str],
    colour: [u8; 4],
) -> Image {
    let (w, h) = size;
    let mut img = Image::filled(w, h, BACKGROUND);
    if let Some(t) = target {
        let (cx, cy) = (t.x.round() as i64, t.y.round() as i64);
        let mut put = |x: i64, y: i64, c: [u8; 4]| {
            if (0..i64::from(w)).contains(&x) && (0..i64::from(h)).contains(&y) {
                let i = (y as usize * w as usize + x as usize) * 4;
                img.rgba[i..i + 4].copy_from_slice(&c);
            }
        };
        let white = [240, 240, 240, 255];
        for d in -30..=30i64 {
            for k in -1..=1 {
                put(cx + d, cy + k, white);
                put(cx + k, cy + d, white);
            }
        }
        for a in 0..720 {
            let th = f64::from(a) * std::f64::consts::TAU / 720.0;
            for r in [18.0, 19.0, 20.0] {
                put(
                    cx + (r * th.cos()).round() as i64,
                    cy + (r * th.sin()).round() as i64,
                    [255, 150, 40, 255],
                );
            }
        }
    }
    for (k, line) in lines.iter().enumerate() {
        text_line(&mut img, h / 2 + 60 + k as u32 * 30, line, colour, None);
    }
    img
}

/// The background of message screens.
const BACKGROUND: [u8; 4] = [24, 28, 38, 255];

/// How many screen pixels per font pixel a line gets: up to three, as
/// large as fits in nine tenths of the width `w`.
fn fit_scale(w: u32, line: &str) -> u32 {
    let lw = line.chars().count() as u32 * 8;
    (w * 9 / 10 / lw.max(1)).clamp(1, 3)
}

/// One line of text centred across the image, its top at `y0`, at
/// `scale` (`None`: as large as fits).
fn text_line(img: &mut Image, y0: u32, line: &str, colour: [u8; 4], scale: Option<u32>) {
    let (w, h) = (img.width, img.height);
    let lw = line.chars().count() as u32 * 8;
    let scale = scale.unwrap_or_else(|| fit_scale(w, line));
    let mut small = Image::filled(lw.max(1), 8, BACKGROUND);
    draw_text(&mut small, 0, 0, line, colour);
    let x0 = (w.saturating_sub(lw * scale)) / 2;
    for y in 0..8 * scale {
        for x in 0..lw * scale {
            let (px, py) = (x0 + x, y0 + y);
            if px < w && py < h {
                let s = small.pixel(x / scale, y / scale);
                let i = (py as usize * w as usize + px as usize) * 4;
                img.rgba[i..i + 4].copy_from_slice(&s);
            }
        }
    }
}

/// A picture-sized notice: lines of text, each in its colour, centred on
/// the screen as a block, all at the size the longest fits.
#[must_use]
pub fn notice(size: (u32, u32), lines: &[(String, [u8; 4])]) -> Image {
    let (w, h) = size;
    let mut img = Image::filled(w, h, BACKGROUND);
    let scale = lines
        .iter()
        .map(|(l, _)| fit_scale(w, l))
        .min()
        .unwrap_or(1);
    let step = 8 * scale + 6;
    let top = h.saturating_sub(lines.len() as u32 * step) / 2;
    for (k, (line, colour)) in lines.iter().enumerate() {
        text_line(&mut img, top + k as u32 * step, line, *colour, Some(scale));
    }
    img
}

/// The picture turned onto the output (the panel's mounting).
pub fn to_output(img: &Image, rotation: Rotation) -> Image {
    let (w, h) = (img.width, img.height);
    let deg = rotation.degrees();
    let (ow, oh) = if deg % 180 == 0 { (w, h) } else { (h, w) };
    if deg == 0 {
        return img.clone();
    }
    let mut out = Image::filled(ow, oh, [0, 0, 0, 255]);
    for y in 0..h {
        for x in 0..w {
            let (ox, oy) = match deg {
                90 => (h - 1 - y, x),
                180 => (w - 1 - x, h - 1 - y),
                _ => (y, w - 1 - x),
            };
            let s = img.pixel(x, y);
            let i = (oy as usize * ow as usize + ox as usize) * 4;
            out.rgba[i..i + 4].copy_from_slice(&s);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pictures_turn_onto_the_output() {
        let mut img = Image::filled(3, 2, [0, 0, 0, 255]);
        img.rgba[0..4].copy_from_slice(&[255, 0, 0, 255]); // top-left
        let r = to_output(&img, Rotation::from_degrees(90).unwrap());
        assert_eq!((r.width, r.height), (2, 3));
        assert_eq!(r.pixel(1, 0), [255, 0, 0, 255], "top-left goes top-right");
    }
}
