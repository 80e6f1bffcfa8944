//! Scanout buffers from gbm: a gbm device on the KMS card (Mesa's gbm: the
//! card's own driver, or its software KMS driver on a display-only card),
//! two XRGB8888 buffer objects the display engine can scan out, each with
//! its framebuffer. Either frames rendered offscreen are written into them
//! through gbm's mapping (linear buffers), or the renderer draws straight
//! into them ([`super::zero_copy`]: buffers in a layout both the plane and
//! the Vulkan driver take, exported as dma-bufs).

use std::os::fd::{AsFd, OwnedFd};
use std::path::Path;

use drm::control::{Device as _, FbCmd2Flags, framebuffer};
use gbm::{BufferObject, BufferObjectFlags, Format, Modifier};

use super::error::{PresentError, copy_rgba_to_xrgb};
use super::modifiers::{INVALID, LINEAR};
use crate::platform::kms::Card;
use crate::render::headless::Image;

/// One scanout buffer's memory, as the display engine lays it out.
pub struct DmaBuf {
    pub fd: OwnedFd,
    pub modifier: u64,
    pub stride: u32,
    pub offset: u32,
}

/// The buffers of one output.
pub(crate) struct GbmBuffers {
    device: gbm::Device<OwnedFd>,
    pub(crate) bos: Vec<(BufferObject<()>, framebuffer::Handle)>,
}

impl GbmBuffers {
    /// A gbm device on `card` (at `path`, for messages) and two scanout
    /// buffers of `w` x `h`, cleared to black, with their framebuffers:
    /// linear ones written through gbm's mapping (`modifiers` empty), or
    /// ones the GPU renders into, in one of `modifiers` (gbm chooses; only
    /// [`LINEAR`]: linear buffers made for rendering).
    pub(crate) fn allocate(
        card: &Card,
        path: &Path,
        w: u32,
        h: u32,
        modifiers: &[u64],
    ) -> Result<Self, PresentError> {
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
        let linear = modifiers.is_empty() || modifiers == [LINEAR];
        let usage = if modifiers.is_empty() {
            BufferObjectFlags::SCANOUT | BufferObjectFlags::LINEAR
        } else if linear {
            BufferObjectFlags::SCANOUT | BufferObjectFlags::LINEAR | BufferObjectFlags::RENDERING
        } else {
            BufferObjectFlags::SCANOUT | BufferObjectFlags::RENDERING
        };
        if linear && !device.is_format_supported(Format::Xrgb8888, usage) {
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
            // Linear buffers need no modifiers from gbm (Mesa's software
            // KMS driver takes none).
            let mut bo = if linear {
                device.create_buffer_object::<()>(w, h, Format::Xrgb8888, usage)
            } else {
                device.create_buffer_object_with_modifiers2::<()>(
                    w,
                    h,
                    Format::Xrgb8888,
                    modifiers.iter().map(|m| Modifier::from(*m)),
                    usage,
                )
            }
            .map_err(|e| io("creating a gbm buffer", e))?;
            if bo.plane_count() != 1 {
                return Err(io(
                    "gbm buffers",
                    std::io::Error::other(format!(
                        "gbm made a buffer of {} planes; one was asked for",
                        bo.plane_count()
                    )),
                ));
            }
            if linear {
                bo.map_mut(0, 0, w, h, |m| m.buffer_mut().fill(0))
                    .map_err(|e| io("mapping a gbm buffer", e))?;
            }
            let fb = if linear {
                card.add_framebuffer(&bo, 24, 32)
            } else {
                card.add_planar_framebuffer(&bo, FbCmd2Flags::MODIFIERS)
            }
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

    /// Buffer `i`'s memory as a dma-buf the renderer may write (exported
    /// from `card` read-write: gbm's own export is read-only on Mesa's
    /// software KMS driver, and a CPU renderer maps it for writing), with
    /// its layout.
    pub(crate) fn dmabuf(&self, card: &Card, i: usize) -> std::io::Result<DmaBuf> {
        let (bo, _) = &self.bos[i];
        let handle = drm::buffer::Buffer::handle(bo);
        let fd = match card.buffer_to_prime_fd(handle, drm::CLOEXEC | drm::RDWR) {
            Ok(fd) => fd,
            // Kernels that cannot export read-write: gbm's export.
            Err(_) => bo.fd_for_plane(0).map_err(std::io::Error::other)?,
        };
        // A driver that reports no modifier made the linear buffer asked
        // for.
        Ok(DmaBuf {
            fd,
            modifier: layout(bo),
            stride: bo.stride_for_plane(0),
            offset: bo.offset(0),
        })
    }

    /// The layout of the buffers (all share one).
    pub(crate) fn modifier(&self) -> u64 {
        layout(&self.bos[0].0)
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

/// A buffer's modifier; a driver that reports none made the linear buffer
/// asked for.
fn layout(bo: &BufferObject<()>) -> u64 {
    match u64::from(bo.modifier()) {
        INVALID => LINEAR,
        m => m,
    }
}
