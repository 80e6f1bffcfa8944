//! Scanout buffers from gbm for the copy presenter: a gbm device on the
//! KMS card (Mesa's gbm: the card's own driver, or its software KMS driver
//! on a display-only card), two XRGB8888 buffer objects the display engine
//! can scan out, each with its framebuffer. Frames rendered offscreen are
//! written into them through gbm's mapping.
//!
//! Rendering straight into them (their dma-bufs imported into Vulkan with
//! VK_EXT_external_memory_dma_buf and VK_EXT_image_drm_format_modifier) is
//! not built, and the journal says so: lavapipe 22.3 offers neither
//! extension, so no adapter here could test it.

use std::os::fd::{AsFd, OwnedFd};
use std::path::Path;

use drm::control::{Device as _, framebuffer};
use gbm::{BufferObject, BufferObjectFlags, Format};

use super::error::{PresentError, copy_rgba_to_xrgb};
use crate::platform::kms::Card;
use crate::render::headless::Image;

/// The buffers of one output.
pub(crate) struct GbmBuffers {
    device: gbm::Device<OwnedFd>,
    pub(crate) bos: Vec<(BufferObject<()>, framebuffer::Handle)>,
}

impl GbmBuffers {
    /// A gbm device on `card` (at `path`, for messages) and two scanout
    /// buffers of `w` x `h`, cleared to black, with their framebuffers.
    pub(crate) fn allocate(card: &Card, path: &Path, w: u32, h: u32) -> Result<Self, PresentError> {
        let io = |what, source| PresentError::Gbm {
            path: path.to_owned(),
            what,
            source,
        };
        let fd = card
            .as_fd()
            .try_clone_to_owned()
            .map_err(|e| io("sharing the card with gbm", e))?;
        let device = gbm::Device::new(fd).map_err(|e| io("opening a gbm device", e))?;
        let usage = BufferObjectFlags::SCANOUT | BufferObjectFlags::LINEAR;
        if !device.is_format_supported(Format::Xrgb8888, usage) {
            return Err(io(
                "gbm buffers",
                std::io::Error::other(format!(
                    "gbm ({}) cannot make linear XRGB8888 scanout buffers",
                    device.backend_name()
                )),
            ));
        }
        let mut bos = Vec::new();
        for _ in 0..2 {
            let mut bo = device
                .create_buffer_object::<()>(w, h, Format::Xrgb8888, usage)
                .map_err(|e| io("creating a gbm buffer", e))?;
            bo.map_mut(0, 0, w, h, |m| m.buffer_mut().fill(0))
                .map_err(|e| io("mapping a gbm buffer", e))?;
            let fb = card
                .add_framebuffer(&bo, 24, 32)
                .map_err(|e| io("adding a frame buffer", e))?;
            bos.push((bo, fb));
        }
        tracing::debug!(backend = device.backend_name(), "gbm device");
        Ok(Self { device, bos })
    }

    /// gbm's backend (`drm`, Mesa's).
    pub(crate) fn backend(&self) -> &str {
        self.device.backend_name()
    }

    /// Write `img` into buffer `i` (`w` x `h`).
    pub(crate) fn write(&mut self, i: usize, img: &Image, w: u32, h: u32) -> std::io::Result<()> {
        let (bo, _) = &mut self.bos[i];
        bo.map_mut(0, 0, w, h, |m| {
            let pitch = m.stride() as usize;
            copy_rgba_to_xrgb(img, m.buffer_mut(), pitch, w, h);
        })
    }
}
