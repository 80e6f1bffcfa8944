//! The direct presenter: Vulkan drives the KMS output itself
//! (VK_EXT_acquire_drm_display through wgpu's DRM surface), so frames are
//! rendered straight into the display's swapchain and shown on vblank
//! (FIFO), without a copy through the CPU. Real GPU drivers have it; Mesa
//! lavapipe does not, and there the copy presenter is used.

use std::panic::AssertUnwindSafe;
use std::path::PathBuf;

use drm::control::Mode;

use super::error::PresentError;
use super::output::{Found, OutputChoice, become_master, find_output};
use crate::platform::kms::Card;
use crate::render::gpu::Gpu;
use crate::render::headless::Image;
use crate::render::mesh::DrawList;
use crate::render::renderer::Renderer;

/// The Vulkan display plane the picture goes on (the primary plane).
const PLANE: u32 = 0;

/// A KMS output driven by Vulkan.
pub struct DirectPresenter {
    // Dropped in this order: the swapchain before the device, the device
    // before the card whose descriptor the surface uses.
    surface: wgpu::Surface<'static>,
    pub renderer: Renderer,
    pub gpu: Gpu,
    instance: wgpu::Instance,
    config: wgpu::SurfaceConfiguration,
    card: Card,
    path: PathBuf,
    name: String,
    connector: u32,
    mode: Mode,
    presents: u64,
}

/// The refresh rate of `mode` in millihertz, as Vulkan's display modes
/// give it.
#[must_use]
pub fn refresh_mhz(mode: &Mode) -> u32 {
    let flags = mode.flags();
    let mhz = refresh_mhz_of(
        mode.clock(),
        mode.hsync().2,
        mode.vsync().2,
        flags.contains(drm::control::ModeFlags::INTERLACE),
        flags.contains(drm::control::ModeFlags::DBLSCAN),
    );
    if mhz == 0 {
        mode.vrefresh() * 1000
    } else {
        mhz
    }
}

/// The pixel clock (kHz) over the total pixels of a frame, in millihertz,
/// interlace and double scan counted; 0 for a mode without totals.
#[must_use]
pub fn refresh_mhz_of(
    clock_khz: u32,
    htotal: u16,
    vtotal: u16,
    interlace: bool,
    dblscan: bool,
) -> u32 {
    if htotal == 0 || vtotal == 0 {
        return 0;
    }
    let mut hz = f64::from(clock_khz) * 1000.0 / (f64::from(htotal) * f64::from(vtotal));
    if interlace {
        hz *= 2.0;
    }
    if dblscan {
        hz /= 2.0;
    }
    (hz * 1000.0).round() as u32
}

/// Make the DRM surface for the output, turning a panic inside the driver
/// layer (it panics when a display cannot be acquired) into an error.
fn drm_surface(
    instance: &wgpu::Instance,
    card: &Card,
    connector: u32,
    mode: &Mode,
) -> Result<wgpu::Surface<'static>, String> {
    use std::os::fd::{AsFd, AsRawFd};
    let (w, h) = mode.size();
    let target = wgpu::SurfaceTargetUnsafe::Drm {
        fd: card.as_fd().as_raw_fd(),
        plane: PLANE,
        connector_id: connector,
        width: u32::from(w),
        height: u32::from(h),
        refresh_rate: refresh_mhz(mode),
    };
    // SAFETY: the descriptor, connector and mode are the card's own, and
    // the card outlives the surface (field order of DirectPresenter).
    let made = std::panic::catch_unwind(AssertUnwindSafe(|| unsafe {
        instance.create_surface_unsafe(target)
    }));
    match made {
        Ok(Ok(surface)) => Ok(surface),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
            .unwrap_or_else(|| "the Vulkan driver failed to take the display".to_owned())),
    }
}

impl DirectPresenter {
    /// Find the output, become DRM master and let Vulkan drive it. Fails
    /// (with the reason) where the driver cannot: the caller then copies.
    pub fn open(
        dir: &std::path::Path,
        choice: &OutputChoice,
        samples: u32,
    ) -> Result<Self, PresentError> {
        let f = find_output(dir, choice)?;
        Self::start(f, samples)
    }

    fn start(f: Found, samples: u32) -> Result<Self, PresentError> {
        let Found {
            card,
            path,
            name,
            connector,
            mode,
            ..
        } = f;
        become_master(&card, &path)?;
        let direct = |why: String| PresentError::Direct {
            path: path.clone(),
            why,
        };
        let connector_id: u32 = connector.into();
        let instance = Gpu::instance();
        let surface = drm_surface(&instance, &card, connector_id, &mode).map_err(direct)?;
        let gpu = Gpu::for_surface(&instance, &surface).map_err(|e| direct(e.to_string()))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(wgpu::TextureFormat::is_srgb)
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| direct("the display offers no colour format".to_owned()))?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
            usage |= wgpu::TextureUsages::COPY_DST;
        }
        let (w, h) = mode.size();
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: u32::from(w),
            height: u32::from(h),
            desired_maximum_frame_latency: 2,
            present_mode: wgpu::PresentMode::Fifo,
            alpha_mode: wgpu::CompositeAlphaMode::Auto,
            view_formats: vec![],
        };
        surface.configure(&gpu.device, &config);
        let samples = match samples {
            0 if gpu.is_cpu() => 1,
            0 => 4,
            n => n,
        };
        let renderer = Renderer::new(&gpu, format, samples);
        tracing::info!(
            card = %path.display(),
            output = %name,
            width = w,
            height = h,
            refresh_mhz = refresh_mhz(&mode),
            format = ?format,
            presenter = "direct",
            "driving the display (Vulkan renders into the display's swapchain, shown on vblank)"
        );
        Ok(Self {
            surface,
            renderer,
            gpu,
            instance,
            config,
            card,
            path,
            name,
            connector: connector_id,
            mode,
            presents: 0,
        })
    }

    /// The output's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// The connector's name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The refresh rate (Hz).
    #[must_use]
    pub fn refresh_hz(&self) -> u32 {
        self.mode.vrefresh().max(1)
    }

    /// Frames queued for the display.
    #[must_use]
    pub fn flips(&self) -> u64 {
        self.presents
    }

    /// The next swapchain image: `None` when this frame is to be skipped
    /// (the swapchain was out of date and is rebuilt, or timed out).
    fn acquire(&mut self) -> Result<Option<wgpu::SurfaceTexture>, PresentError> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => Ok(Some(t)),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                drop(t);
                self.surface.configure(&self.gpu.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&self.gpu.device, &self.config);
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Lost => Err(PresentError::LostMaster(self.path.clone())),
            wgpu::CurrentSurfaceTexture::Validation => Err(PresentError::Direct {
                path: self.path.clone(),
                why: "the swapchain image could not be acquired (validation error)".to_owned(),
            }),
        }
    }

    /// Draw `list` into the next swapchain image and queue it for the
    /// next vblank (FIFO: this waits while the queue is full, which paces
    /// the loop to the display). Whether a frame was queued.
    pub fn draw(&mut self, list: &DrawList) -> Result<bool, PresentError> {
        let Some(frame) = self.acquire()? else {
            return Ok(false);
        };
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        self.renderer
            .draw(&self.gpu, &mut encoder, &frame.texture, list);
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.queue.present(frame);
        self.presents += 1;
        Ok(true)
    }

    /// Show a picture drawn on the CPU (RGBA, the output's size).
    pub fn show_image(&mut self, img: &Image) -> Result<(), PresentError> {
        if !self.config.usage.contains(wgpu::TextureUsages::COPY_DST) {
            return Err(PresentError::Direct {
                path: self.path.clone(),
                why: "the display's swapchain cannot take copied pictures; set [display] presenter = \"copy\"".to_owned(),
            });
        }
        let frame = loop {
            if let Some(f) = self.acquire()? {
                break f;
            }
        };
        let (w, h) = self.size();
        let bgra = matches!(
            self.config.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let mut data = vec![0u8; (w * h * 4) as usize];
        for y in 0..h.min(img.height) as usize {
            for x in 0..w.min(img.width) as usize {
                let s = &img.rgba[(y * img.width as usize + x) * 4..][..4];
                let d = &mut data[(y * w as usize + x) * 4..][..4];
                if bgra {
                    d.copy_from_slice(&[s[2], s[1], s[0], 255]);
                } else {
                    d.copy_from_slice(&[s[0], s[1], s[2], 255]);
                }
            }
        }
        self.gpu.queue.write_texture(
            frame.texture.as_image_copy(),
            &data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(h),
            },
            frame.texture.size(),
        );
        self.gpu.queue.submit([]);
        self.gpu.queue.present(frame);
        self.presents += 1;
        Ok(())
    }

    /// A new device after the old one was lost, on the same surface.
    pub fn rebuild_gpu(&mut self) -> Result<(), PresentError> {
        self.gpu = Gpu::for_surface(&self.instance, &self.surface)?;
        self.surface.configure(&self.gpu.device, &self.config);
        self.renderer = Renderer::new(&self.gpu, self.config.format, self.renderer.samples());
        Ok(())
    }

    /// Take the display back after another program had it: master again,
    /// a new surface and swapchain. Whether it worked.
    pub fn reacquire(&mut self) -> bool {
        if become_master(&self.card, &self.path).is_err() {
            return false;
        }
        match drm_surface(&self.instance, &self.card, self.connector, &self.mode) {
            Ok(surface) => {
                surface.configure(&self.gpu.device, &self.config);
                self.surface = surface;
                true
            }
            Err(why) => {
                tracing::warn!(%why, "the display cannot be taken back yet");
                false
            }
        }
    }
}

impl Drop for DirectPresenter {
    fn drop(&mut self) {
        let _ = self.gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(std::time::Duration::from_millis(500)),
        });
        let _ = drm::Device::release_master_lock(&self.card);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refresh_is_counted_as_vulkan_counts_it() {
        // 1920x1080@60 (CEA 16): 148.5 MHz over 2200 x 1125.
        assert_eq!(refresh_mhz_of(148_500, 2200, 1125, false, false), 60_000);
        // 1280x800@75 as virtio-gpu offers it: not a round number.
        assert_eq!(refresh_mhz_of(106_500, 1696, 838, false, false), 74_934);
        // 1920x1080i: two fields a frame.
        assert_eq!(refresh_mhz_of(74_250, 2200, 1125, true, false), 60_000);
        assert_eq!(refresh_mhz_of(25_175, 0, 525, false, false), 0);
    }
}
