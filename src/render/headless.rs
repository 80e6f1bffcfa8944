//! Headless output: the renderer draws into an offscreen texture, which is
//! copied into a buffer and read back as an RGBA image (for the demo,
//! replays, golden-image tests, and the KMS copy path).

use std::path::Path;

use super::gpu::{Gpu, GpuError};
use super::renderer::Renderer;
use crate::render::mesh::DrawList;

/// An 8-bit RGBA image, sRGB encoded, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Image {
    /// A blank image of one colour.
    #[must_use]
    pub fn filled(width: u32, height: u32, rgba: [u8; 4]) -> Self {
        Self {
            width,
            height,
            rgba: rgba.repeat(width as usize * height as usize),
        }
    }

    /// The pixel at (`x`, `y`).
    #[must_use]
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Copy `other` into this image with its top left at (`x`, `y`),
    /// clipped to this image.
    pub fn blit(&mut self, other: &Image, x: u32, y: u32) {
        for row in 0..other.height {
            let ty = y + row;
            if ty >= self.height || x >= self.width {
                continue;
            }
            let w = other.width.min(self.width - x) as usize;
            let src = row as usize * other.width as usize * 4;
            let dst = (ty as usize * self.width as usize + x as usize) * 4;
            self.rgba[dst..dst + w * 4].copy_from_slice(&other.rgba[src..src + w * 4]);
        }
    }

    /// Encode as PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_compression(png::Compression::Fast);
            let mut w = enc.write_header()?;
            w.write_image_data(&self.rgba)?;
        }
        Ok(out)
    }

    /// Write as a PNG file, whole or not at all, over a regular file only
    /// ([`crate::output::replace_file`]).
    pub fn write_png(&self, path: &Path) -> std::io::Result<()> {
        let bytes = self.to_png().map_err(std::io::Error::other)?;
        crate::output::replace_file(path, &bytes)
    }

    /// Read a PNG file (8-bit RGB or RGBA).
    pub fn read_png(path: &Path) -> std::io::Result<Self> {
        let file = std::io::BufReader::new(crate::reading::open(path)?);
        let mut dec = png::Decoder::new(file);
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = dec.read_info().map_err(std::io::Error::other)?;
        let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader.next_frame(&mut buf).map_err(std::io::Error::other)?;
        buf.truncate(info.buffer_size());
        let rgba = match info.color_type {
            png::ColorType::Rgba => buf,
            png::ColorType::Rgb => buf
                .chunks(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g, 255]).collect(),
            png::ColorType::GrayscaleAlpha => buf
                .chunks(2)
                .flat_map(|p| [p[0], p[0], p[0], p[1]])
                .collect(),
            png::ColorType::Indexed => {
                return Err(std::io::Error::other("indexed PNG not expanded"));
            }
        };
        Ok(Self {
            width: info.width,
            height: info.height,
            rgba,
        })
    }
}

/// The colour format of offscreen frames.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// An offscreen target of a fixed size, with its readback buffer.
pub struct Headless {
    pub gpu: Gpu,
    pub renderer: Renderer,
    size: (u32, u32),
    texture: wgpu::Texture,
    readback: wgpu::Buffer,
    padded_row: u32,
}

impl Headless {
    /// Frames of `width` x `height` (the output's size, before rotation)
    /// with up to `samples` samples per pixel (0: 4 on a GPU, 1 on a CPU
    /// renderer).
    pub fn new(gpu: Gpu, width: u32, height: u32, samples: u32) -> Result<Self, GpuError> {
        // Checked before anything is allocated: wgpu panics on a texture or
        // buffer over the device's limits.
        let limits = gpu.device.limits();
        let padded =
            u64::from((width.max(1) * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
        let bytes = padded * u64::from(height);
        let max_bytes = limits.max_buffer_size.min(u64::from(u32::MAX));
        if width > limits.max_texture_dimension_2d
            || height > limits.max_texture_dimension_2d
            || bytes > max_bytes
        {
            return Err(GpuError::TooLarge {
                width,
                height,
                adapter: gpu.info.name.clone(),
                max_side: limits.max_texture_dimension_2d,
                max_bytes,
            });
        }
        let samples = match samples {
            0 if gpu.is_cpu() => 1,
            0 => 4,
            n => n,
        };
        let renderer = Renderer::new(&gpu, FORMAT, samples);
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let padded_row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_row) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(Self {
            gpu,
            renderer,
            size: (width, height),
            texture,
            readback,
            padded_row,
        })
    }

    /// Output size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Draw `list` and read the frame back.
    pub fn render(&mut self, list: &DrawList) -> Result<Image, GpuError> {
        let (w, h) = self.size;
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        self.renderer
            .draw(&self.gpu, &mut encoder, &self.texture, list);
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.gpu
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(std::time::Duration::from_secs(10)),
            })
            .map_err(|e| GpuError::Lost(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Lost(e.to_string()))?
            .map_err(|e| GpuError::Lost(e.to_string()))?;
        let mut rgba = Vec::with_capacity((w * h * 4) as usize);
        {
            let data = slice
                .get_mapped_range()
                .map_err(|e| GpuError::Lost(e.to_string()))?;
            for row in 0..h as usize {
                let start = row * self.padded_row as usize;
                rgba.extend_from_slice(&data[start..start + w as usize * 4]);
            }
        }
        self.readback.unmap();
        Ok(Image {
            width: w,
            height: h,
            rgba,
        })
    }
}
