//! Showing frames on a KMS output through two scanout buffers, page-flipped
//! on vblank. Either the renderer draws straight into gbm's buffers (zero
//! copy, where the Vulkan driver imports dma-bufs), or frames rendered
//! offscreen (any Vulkan adapter, lavapipe included) are copied into them
//! (gbm's where gbm opens the card, else dumb buffers: every KMS driver).
//! marionette becomes DRM master for the output it drives, and gives the
//! CRTC back as it found it when it stops.

use std::os::fd::{AsFd, BorrowedFd};
use std::path::{Path, PathBuf};
use std::time::Duration;

use drm::buffer::DrmFourcc;
use drm::control::dumbbuffer::DumbBuffer;
use drm::control::{Device as _, Mode, PageFlipFlags, connector, crtc, framebuffer};

pub use super::error::{PresentError, copy_rgba_to_xrgb};
pub use super::output::{Attempt, OutputChoice, PresenterKind};
use super::output::{Found, become_master, find_output};
use crate::platform::kms::Card;
use crate::render::headless::Image;

/// How many frame costs are kept for their median.
const COSTS_KEPT: usize = 4096;

/// The output being driven, with its two buffers.
pub struct CopyPresenter {
    card: Card,
    path: PathBuf,
    name: String,
    connector: connector::Handle,
    crtc: crtc::Handle,
    mode: Mode,
    buffers: Buffers,
    /// Which buffer is on screen, and whether a flip is queued.
    flips: super::flips::Flips,
    /// The CRTC as it was, to give back.
    saved: Option<crtc::Info>,
    /// Time spent writing frames into the buffers (s), and how many: the
    /// copy's cost, said when the presenter stops.
    copy_s: f64,
    copies: u64,
    /// The last [`COSTS_KEPT`] of those times (ms), for their median: a
    /// mean follows the few frames another program slowed.
    costs_ms: Vec<f32>,
    /// The renderer drawing into the buffers themselves (zero copy).
    imported: Option<Box<super::zero_copy::Imported>>,
}

/// Where the frames are copied to.
enum Buffers {
    Dumb(Vec<(DumbBuffer, framebuffer::Handle)>),
    Gbm(Box<super::gbm::GbmBuffers>),
}

impl Buffers {
    fn framebuffer(&self, i: usize) -> framebuffer::Handle {
        match self {
            Self::Dumb(b) => b[i].1,
            Self::Gbm(g) => g.bos[i].1,
        }
    }
}

/// Which buffers frames reach the output through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Via {
    /// Dumb buffers (every KMS driver has them).
    Dumb,
    /// gbm's scanout buffers (refused where gbm cannot open the card).
    Gbm,
    /// gbm's scanout buffers, rendered into on a GPU from `adapter` with
    /// up to `samples` per pixel (refused where the Vulkan driver cannot
    /// import them, or no layout suits both it and the plane).
    GbmZeroCopy {
        adapter: crate::render::gpu::AdapterChoice,
        samples: u32,
    },
}

impl CopyPresenter {
    /// Find the output on the cards in `dir` (normally `/dev/dri`), become
    /// DRM master and show a black frame on it.
    #[tracing::instrument(
        level = "debug",
        name = "drm_device",
        skip(choice),
        err(level = "debug")
    )]
    pub fn open(dir: &Path, choice: &OutputChoice, via: Via) -> Result<Self, PresentError> {
        let f = find_output(dir, choice)?;
        Self::start(f, via)
    }

    fn start(f: Found, via: Via) -> Result<Self, PresentError> {
        let Found {
            card,
            path,
            name,
            connector,
            crtc,
            mode,
        } = f;
        become_master(&card, &path)?;
        let io = |what, source| PresentError::Io {
            path: path.clone(),
            what,
            source,
        };
        let (w, h) = mode.size();
        let mut imported = None;
        let buffers = match via {
            Via::Gbm => Buffers::Gbm(Box::new(super::gbm::GbmBuffers::allocate(
                &card,
                &path,
                u32::from(w),
                u32::from(h),
                &[],
            )?)),
            Via::GbmZeroCopy { adapter, samples } => {
                let (buffers, renderer) =
                    super::zero_copy::open(&card, &path, crtc, (w, h), adapter, samples)?;
                imported = Some(Box::new(renderer));
                Buffers::Gbm(Box::new(buffers))
            }
            Via::Dumb => Buffers::Dumb(dumb_buffers(&card, &path, w, h)?),
        };
        let saved = card.get_crtc(crtc).ok();
        card.set_crtc(
            crtc,
            Some(buffers.framebuffer(0)),
            (0, 0),
            &[connector],
            Some(mode),
        )
        .map_err(|e| io("setting the mode", e))?;
        let presenter = Self {
            card,
            path,
            name,
            connector,
            crtc,
            mode,
            buffers,
            flips: super::flips::Flips::default(),
            saved,
            copy_s: 0.0,
            copies: 0,
            costs_ms: Vec::new(),
            imported,
        };
        presenter.say_driving();
        Ok(presenter)
    }

    /// The journal's line on the output driven, and how.
    fn say_driving(&self) {
        let (path, name, mode) = (&self.path, &self.name, self.mode);
        let (w, h) = mode.size();
        match &self.buffers {
            Buffers::Gbm(g) if self.imported.is_some() => tracing::info!(
                card = %path.display(),
                output = %name,
                width = w,
                height = h,
                refresh_hz = mode.vrefresh(),
                presenter = "gbm",
                gbm_backend = g.backend(),
                modifier = %super::modifiers::name(g.modifier()),
                zero_copy = true,
                "driving the display (frames rendered straight into gbm scanout buffers, page-flipped on vblank)"
            ),
            Buffers::Gbm(g) => tracing::info!(
                card = %path.display(),
                output = %name,
                width = w,
                height = h,
                refresh_hz = mode.vrefresh(),
                presenter = "gbm",
                gbm_backend = g.backend(),
                "driving the display (frames rendered offscreen, written into gbm scanout buffers, page-flipped on vblank)"
            ),
            Buffers::Dumb(_) => tracing::info!(
                card = %path.display(),
                output = %name,
                width = w,
                height = h,
                refresh_hz = mode.vrefresh(),
                presenter = "copy",
                "driving the display (frames rendered offscreen, copied into dumb buffers, page-flipped on vblank)"
            ),
        }
    }
}

/// Two dumb buffers of `w` x `h`, cleared, with their framebuffers.
fn dumb_buffers(
    card: &Card,
    path: &Path,
    w: u16,
    h: u16,
) -> Result<Vec<(DumbBuffer, framebuffer::Handle)>, PresentError> {
    let io = |what, source| PresentError::Io {
        path: path.to_owned(),
        what,
        source,
    };
    let mut buffers = Vec::new();
    {
        for _ in 0..2 {
            let mut db = card
                .create_dumb_buffer((u32::from(w), u32::from(h)), DrmFourcc::Xrgb8888, 32)
                .map_err(|e| io("creating a frame buffer", e))?;
            {
                let mut map = card
                    .map_dumb_buffer(&mut db)
                    .map_err(|e| io("mapping a frame buffer", e))?;
                map.as_mut().fill(0);
            }
            let fb = card
                .add_framebuffer(&db, 24, 32)
                .map_err(|e| io("adding a frame buffer", e))?;
            buffers.push((db, fb));
        }
    }
    Ok(buffers)
}

impl CopyPresenter {
    /// The output's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        let (w, h) = self.mode.size();
        (u32::from(w), u32::from(h))
    }

    /// The connector's name (`Virtual-1`, `HDMI-A-1`).
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The refresh rate (Hz).
    #[must_use]
    pub fn refresh_hz(&self) -> u32 {
        self.mode.vrefresh().max(1)
    }

    /// Page flips completed.
    #[must_use]
    pub fn flips(&self) -> u64 {
        self.flips.completed()
    }

    /// Whether a flip is queued (the next frame waits for it).
    #[must_use]
    pub fn flip_pending(&self) -> bool {
        self.flips.pending()
    }

    /// The card's descriptor, readable when a flip completed.
    #[must_use]
    pub fn fd(&self) -> BorrowedFd<'_> {
        self.card.as_fd()
    }

    /// Read the card's events (call when its descriptor is readable):
    /// whether a flip completed.
    pub fn dispatch(&mut self) -> Result<bool, PresentError> {
        let events = match self.card.receive_events() {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return Ok(false),
            Err(source) => {
                return Err(PresentError::Io {
                    path: self.path.clone(),
                    what: "reading display events",
                    source,
                });
            }
        };
        let mut flipped = false;
        for e in events {
            if let drm::control::Event::PageFlip(_) = e {
                flipped = true;
            }
        }
        if flipped {
            self.flips.flipped();
        }
        Ok(flipped)
    }

    /// Wait up to `timeout` for the queued flip: whether it completed.
    pub fn wait_flip(&mut self, timeout: Duration) -> Result<bool, PresentError> {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        if !self.flips.pending() {
            return Ok(true);
        }
        let ms = u16::try_from(timeout.as_millis()).unwrap_or(u16::MAX);
        let ready = {
            let mut fds = [PollFd::new(self.card.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, PollTimeout::from(ms)) {
                Ok(n) => n > 0,
                Err(nix::errno::Errno::EINTR) => false,
                Err(e) => {
                    return Err(PresentError::Io {
                        path: self.path.clone(),
                        what: "waiting for a page flip",
                        source: e.into(),
                    });
                }
            }
        };
        if ready {
            self.dispatch()?;
        }
        Ok(!self.flips.pending())
    }

    /// Whether the renderer draws into the scanout buffers themselves
    /// ([`CopyPresenter::draw`]); otherwise frames come as images
    /// ([`CopyPresenter::present`]).
    #[must_use]
    pub fn renders(&self) -> bool {
        self.imported.is_some()
    }

    /// Samples per pixel of the renderer drawing into the buffers.
    #[must_use]
    pub fn samples(&self) -> Option<u32> {
        self.imported.as_ref().map(|i| i.samples())
    }

    /// The buffer not on screen, free to draw into: a flip still queued
    /// is waited for first (the back buffer is on screen until it
    /// completes).
    fn back(&mut self) -> Result<usize, PresentError> {
        if self.flips.pending() && !self.wait_flip(Duration::from_millis(250))? {
            // The flip never came (a stalled driver): start over with a
            // mode set rather than queue behind it.
            tracing::warn!(output = %self.name, "page flip did not complete in 250 ms; setting the mode again");
            self.flips.abandoned();
            self.restore()?;
        }
        // Nothing is queued any more.
        Ok(self.flips.free().unwrap_or(1 - self.flips.front()))
    }

    /// Draw `list` straight into the back buffer and flip to it at the
    /// next vblank (zero copy; [`CopyPresenter::renders`]).
    pub fn draw(&mut self, list: &crate::render::mesh::DrawList) -> Result<(), PresentError> {
        let back = self.back()?;
        let Some(imported) = self.imported.as_mut() else {
            return Err(PresentError::NoRenderer);
        };
        #[allow(
            clippy::disallowed_methods,
            reason = "the frame's cost is measured for the journal, not used to decide anything"
        )]
        let started = std::time::Instant::now();
        imported.draw(back, list)?;
        self.cost(started.elapsed().as_secs_f64());
        self.flip(back)
    }

    /// The imported buffers again on a new GPU device after the old one
    /// was lost.
    pub fn rebuild_gpu(
        &mut self,
        adapter: crate::render::gpu::AdapterChoice,
    ) -> Result<(), PresentError> {
        let (Some(imported), Buffers::Gbm(buffers)) = (self.imported.as_mut(), &self.buffers)
        else {
            return Ok(());
        };
        let gpu = crate::render::gpu::Gpu::new(adapter)?;
        imported
            .rebuild(gpu, &self.card, buffers)
            .map_err(|why| PresentError::ZeroCopy {
                path: self.path.clone(),
                why,
            })
    }

    /// Copy `img` (RGBA, the output's size) into the back buffer and flip
    /// to it at the next vblank. A flip still queued is waited for first.
    pub fn present(&mut self, img: &Image) -> Result<(), PresentError> {
        let back = self.back()?;
        let (w, h) = self.size();
        let mapping = |source| PresentError::Io {
            path: self.path.clone(),
            what: "mapping a frame buffer",
            source,
        };
        #[allow(
            clippy::disallowed_methods,
            reason = "the copy's cost is measured for the journal, not used to decide anything"
        )]
        let started = std::time::Instant::now();
        match &mut self.buffers {
            Buffers::Dumb(b) => {
                let (db, _) = &mut b[back];
                let pitch = drm::buffer::Buffer::pitch(db) as usize;
                let mut map = self.card.map_dumb_buffer(db).map_err(mapping)?;
                copy_rgba_to_xrgb(img, map.as_mut(), pitch, w, h);
            }
            Buffers::Gbm(g) => g.write(back, img, w, h).map_err(mapping)?,
        }
        self.cost(started.elapsed().as_secs_f64());
        self.flip(back)
    }

    /// One frame's drawing or writing took `s` seconds.
    fn cost(&mut self, s: f64) {
        self.copy_s += s;
        if self.costs_ms.len() < COSTS_KEPT {
            self.costs_ms.push((s * 1e3) as f32);
        } else {
            self.costs_ms[(self.copies as usize) % COSTS_KEPT] = (s * 1e3) as f32;
        }
        self.copies += 1;
    }

    /// The median of the kept frame costs (ms).
    fn cost_median_ms(&self) -> f64 {
        let mut c = self.costs_ms.clone();
        c.sort_by(f32::total_cmp);
        c.get(c.len() / 2).map_or(0.0, |m| f64::from(*m))
    }

    /// Flip to buffer `back` at the next vblank.
    fn flip(&mut self, back: usize) -> Result<(), PresentError> {
        match self.card.page_flip(
            self.crtc,
            self.buffers.framebuffer(back),
            PageFlipFlags::EVENT,
            None,
        ) {
            Ok(()) => {
                self.flips.queued(back);
                Ok(())
            }
            Err(e) if matches!(e.raw_os_error(), Some(libc::EACCES | libc::EPERM)) => {
                Err(PresentError::LostMaster(self.path.clone()))
            }
            Err(source) => Err(PresentError::Io {
                path: self.path.clone(),
                what: "page flip",
                source,
            }),
        }
    }

    /// Take the display back after another program had it (VT switch):
    /// whether marionette is master again (the mode is set again).
    pub fn reacquire(&mut self) -> bool {
        if drm::Device::acquire_master_lock(&self.card)
            .is_err_and(|e| e.raw_os_error() != Some(libc::EINVAL))
        {
            return false;
        }
        self.flips.abandoned();
        self.restore().is_ok()
    }

    fn restore(&mut self) -> Result<(), PresentError> {
        self.card
            .set_crtc(
                self.crtc,
                Some(self.buffers.framebuffer(self.flips.front())),
                (0, 0),
                &[self.connector],
                Some(self.mode),
            )
            .map_err(|e| {
                if matches!(e.raw_os_error(), Some(libc::EACCES | libc::EPERM)) {
                    PresentError::LostMaster(self.path.clone())
                } else {
                    PresentError::Io {
                        path: self.path.clone(),
                        what: "setting the mode",
                        source: e,
                    }
                }
            })
    }
}

impl Drop for CopyPresenter {
    /// Give the CRTC back as it was and stop being master.
    fn drop(&mut self) {
        if self.copies > 0 && self.imported.is_some() {
            tracing::info!(
                buffers = "gbm",
                frames = self.copies,
                draw_ms_mean = self.copy_s / self.copies as f64 * 1e3,
                draw_ms_median = self.cost_median_ms(),
                "frames rendered straight into scanout buffers (zero copy)"
            );
        } else if self.copies > 0 {
            tracing::info!(
                buffers = match self.buffers {
                    Buffers::Gbm(_) => "gbm",
                    Buffers::Dumb(_) => "dumb",
                },
                frames = self.copies,
                copy_ms_mean = self.copy_s / self.copies as f64 * 1e3,
                copy_ms_median = self.cost_median_ms(),
                "frames written into scanout buffers"
            );
        }
        if self.flips.pending() {
            let _ = self.wait_flip(Duration::from_millis(100));
        }
        if let Some(s) = &self.saved {
            let _ = self.card.set_crtc(
                self.crtc,
                s.framebuffer(),
                s.position(),
                &[self.connector],
                s.mode(),
            );
        }
        match &mut self.buffers {
            Buffers::Dumb(b) => {
                for (db, fb) in b.drain(..) {
                    let _ = self.card.destroy_framebuffer(fb);
                    let _ = self.card.destroy_dumb_buffer(db);
                }
            }
            // The buffer objects go with the gbm device when dropped.
            Buffers::Gbm(g) => {
                for (_, fb) in &g.bos {
                    let _ = self.card.destroy_framebuffer(*fb);
                }
            }
        }
        let _ = drm::Device::release_master_lock(&self.card);
    }
}
