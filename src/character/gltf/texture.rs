//! Base colour textures (PNG or JPEG, in a buffer view, a `data:` URI or a
//! file beside the glTF), sampled at each vertex's texture coordinates:
//! the figure is drawn in per-vertex colours, its texture's detail finer
//! than its vertices lost. A texture that cannot be read is said, and the
//! material's base colour factor alone is used.

use std::path::Path;

use super::read::{File, base64, inside};

/// The most texels a texture may have (decoded to RGBA, 4 bytes each),
/// checked from its header before it is decoded.
pub const MAX_TEXELS: u64 = 16 << 20;

/// The most texels all of a figure's textures may have together (128 MB
/// decoded): a texture past what is left is said and its material's base
/// colour used.
pub const MAX_FIGURE_TEXELS: u64 = 32 << 20;

/// A decoded texture: RGBA8, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Texture {
    width: usize,
    height: usize,
    rgba: Vec<u8>,
}

impl Texture {
    /// Bilinear sample at `uv` (repeating, as glTF's default sampler),
    /// linear RGBA (the texture is sRGB-encoded).
    #[must_use]
    pub fn sample(&self, uv: [f32; 2]) -> [f32; 4] {
        let (w, h) = (self.width as f32, self.height as f32);
        let x = uv[0].rem_euclid(1.0) * w - 0.5;
        let y = uv[1].rem_euclid(1.0) * h - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |xi: f32, yi: f32| -> [f32; 4] {
            let xi = (xi as i64).rem_euclid(self.width as i64) as usize;
            let yi = (yi as i64).rem_euclid(self.height as i64) as usize;
            let p = &self.rgba[(yi * self.width + xi) * 4..][..4];
            [
                srgb_to_linear(p[0]),
                srgb_to_linear(p[1]),
                srgb_to_linear(p[2]),
                f32::from(p[3]) / 255.0,
            ]
        };
        let (a, b, c, d) = (
            at(x0, y0),
            at(x0 + 1.0, y0),
            at(x0, y0 + 1.0),
            at(x0 + 1.0, y0 + 1.0),
        );
        let mut out = [0.0; 4];
        for k in 0..4 {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            out[k] = top + (bottom - top) * fy;
        }
        out
    }
}

fn srgb_to_linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// Its texels (width times height).
    #[must_use]
    pub fn texels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
}

/// Image `index` of `file`, decoded if it has at most `max_texels`; why
/// not, where it cannot be.
pub fn load(file: &File, index: usize, max_texels: u64) -> Result<Texture, String> {
    let image = file
        .doc
        .images()
        .nth(index)
        .ok_or_else(|| format!("no image {index}"))?;
    let bytes: Vec<u8> = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = file
                .buffers
                .get(view.buffer().index())
                .ok_or_else(|| "its buffer is missing".to_owned())?;
            let (start, len) = (view.offset(), view.length());
            buffer
                .get(start..start.saturating_add(len))
                .ok_or_else(|| {
                    format!(
                        "its buffer view ({len} bytes at {start}) runs past its buffer ({} bytes)",
                        buffer.len()
                    )
                })?
                .to_vec()
        }
        gltf::image::Source::Uri { uri, .. } => {
            if let Some(rest) = uri.strip_prefix("data:") {
                let (_, b64) = rest
                    .split_once(";base64,")
                    .ok_or_else(|| "a data URI that is not base64".to_owned())?;
                base64(b64).ok_or_else(|| "bad base64 in its data URI".to_owned())?
            } else {
                let rel = inside(uri).ok_or_else(|| {
                    format!(
                        "{} is not a file beside the glTF",
                        crate::reading::quote(uri)
                    )
                })?;
                let dir = file.path.parent().unwrap_or(Path::new("."));
                let path = dir.join(rel);
                crate::reading::read_inside(&path, dir, super::MAX_FILE_BYTES).map_err(
                    |e| match e {
                        crate::reading::ReadError::TooLarge { said, .. } => {
                            format!("{} is {said} bytes", path.display())
                        }
                        e => format!("{}: {e}", path.display()),
                    },
                )?
            }
        }
    };
    decode_within(&bytes, max_texels)
}

/// PNG or JPEG bytes (told apart by their signature) as RGBA8.
#[cfg(test)]
fn decode(bytes: &[u8]) -> Result<Texture, String> {
    decode_within(bytes, MAX_TEXELS)
}

/// [`decode`], refused from the header where the image has over
/// `max_texels`.
fn decode_within(bytes: &[u8], max_texels: u64) -> Result<Texture, String> {
    let too_big = |w: usize, h: usize| (w as u64).saturating_mul(h as u64) > max_texels;
    if bytes.starts_with(b"\x89PNG") {
        let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = dec.read_info().map_err(|e| format!("PNG: {e}"))?;
        let (w, h) = (reader.info().width as usize, reader.info().height as usize);
        if w == 0 || h == 0 || too_big(w, h) {
            return Err(format!(
                "a PNG of {w}x{h}: empty, or over the {max_texels} texels left of the {MAX_TEXELS} a texture and {MAX_FIGURE_TEXELS} a figure may have"
            ));
        }
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| "PNG: its size overflows".to_owned())?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| format!("PNG: {e}"))?;
        let channels = info.color_type.samples();
        let px = &buf[..info.buffer_size()];
        let rgba = px
            .chunks_exact(channels)
            .flat_map(|c| match c {
                [g] => [*g, *g, *g, 255],
                [g, a] => [*g, *g, *g, *a],
                [r, g, b] => [*r, *g, *b, 255],
                [r, g, b, a, ..] => [*r, *g, *b, *a],
                [] => [0, 0, 0, 255],
            })
            .collect();
        return Ok(Texture {
            width: w,
            height: h,
            rgba,
        });
    }
    if bytes.starts_with(&[0xff, 0xd8]) {
        let mut dec = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
        dec.read_info().map_err(|e| format!("JPEG: {e}"))?;
        let info = dec.info().ok_or_else(|| "JPEG: no header".to_owned())?;
        let (w, h) = (usize::from(info.width), usize::from(info.height));
        if w == 0 || h == 0 || too_big(w, h) {
            return Err(format!(
                "a JPEG of {w}x{h}: empty, or over the {max_texels} texels left of the {MAX_TEXELS} a texture and {MAX_FIGURE_TEXELS} a figure may have"
            ));
        }
        let px = dec.decode().map_err(|e| format!("JPEG: {e}"))?;
        use jpeg_decoder::PixelFormat as P;
        let rgba: Vec<u8> = match info.pixel_format {
            P::L8 => px.iter().flat_map(|g| [*g, *g, *g, 255]).collect(),
            P::L16 => px
                .chunks_exact(2)
                .flat_map(|g| [g[0], g[0], g[0], 255])
                .collect(),
            P::RGB24 => px
                .chunks_exact(3)
                .flat_map(|c| [c[0], c[1], c[2], 255])
                .collect(),
            P::CMYK32 => px
                .chunks_exact(4)
                .flat_map(|c| {
                    let k = u16::from(255 - c[3]);
                    let f = |v: u8| ((u16::from(255 - v) * k) / 255) as u8;
                    [f(c[0]), f(c[1]), f(c[2]), 255]
                })
                .collect(),
        };
        if rgba.len() != w * h * 4 {
            return Err(format!(
                "JPEG: {} texels decoded for {w}x{h}",
                rgba.len() / 4
            ));
        }
        return Ok(Texture {
            width: w,
            height: h,
            rgba,
        });
    }
    Err("neither PNG nor JPEG".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, rgba: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().unwrap();
            wr.write_image_data(rgba).unwrap();
        }
        out
    }

    #[test]
    fn a_png_is_sampled_bilinearly_repeating_in_linear_colour() {
        // Two texels: white and black.
        let t = decode(&png(2, 1, &[255, 255, 255, 255, 0, 0, 0, 255])).unwrap();
        assert!((t.sample([0.25, 0.5])[0] - 1.0).abs() < 1e-6);
        assert!(t.sample([0.75, 0.5])[0].abs() < 1e-6);
        // Half way between the two texel centres.
        assert!((t.sample([0.5, 0.5])[0] - 0.5).abs() < 1e-6);
        // Repeating: u = 1.25 is u = 0.25.
        assert!((t.sample([1.25, 0.5])[0] - 1.0).abs() < 1e-6);
        // sRGB 188 is about linear 0.5.
        let g = decode(&png(1, 1, &[188, 188, 188, 255])).unwrap();
        assert!((g.sample([0.5, 0.5])[0] - 0.5).abs() < 0.01);
    }

    #[test]
    fn bad_images_are_refused_with_the_reason() {
        assert_eq!(decode(b"GIF89a").unwrap_err(), "neither PNG nor JPEG");
        let mut p = png(1, 1, &[0, 0, 0, 255]);
        p.truncate(30);
        assert!(decode(&p).unwrap_err().starts_with("PNG"));
        assert!(
            decode(&[0xff, 0xd8, 0xff, 0xe0, 0, 2])
                .unwrap_err()
                .starts_with("JPEG")
        );
        // A header claiming 65535 x 65535 texels is refused before decoding.
        let mut huge = png(1, 1, &[0, 0, 0, 255]);
        huge[16..20].copy_from_slice(&65535u32.to_be_bytes());
        huge[20..24].copy_from_slice(&65535u32.to_be_bytes());
        assert!(decode(&huge).is_err());
    }
}
