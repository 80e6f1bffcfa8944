//! Showing frames on a KMS output. The copy presenter renders offscreen
//! (any Vulkan adapter, lavapipe included), copies each frame into one of
//! two dumb buffers and page-flips to it on vblank: it works on every KMS
//! driver. marionette becomes DRM master for the output it drives, and
//! gives the CRTC back as it found it when it stops.

use std::os::fd::{AsFd, BorrowedFd};
use std::path::{Path, PathBuf};
use std::time::Duration;

use drm::buffer::DrmFourcc;
use drm::control::dumbbuffer::DumbBuffer;
use drm::control::{Device as _, Mode, PageFlipFlags, connector, crtc, framebuffer};
use thiserror::Error;

use crate::platform::kms::Card;
use crate::render::headless::Image;

/// Why frames cannot be shown.
#[derive(Debug, Error)]
pub enum PresentError {
    #[error(transparent)]
    Kms(#[from] crate::platform::kms::KmsError),
    #[error("{0}")]
    NoOutput(String),
    #[error(
        "{path}: cannot become DRM master: {source} (another program drives the display: stop the display manager, or switch marionette to a free VT)"
    )]
    Master {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {what}: {source}")]
    Io {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// No GPU to render with.
    #[error(transparent)]
    Gpu(#[from] crate::render::gpu::GpuError),
    /// The direct presenter cannot drive this output.
    #[error("{path}: Vulkan cannot drive the display directly: {why}")]
    Direct { path: PathBuf, why: String },
    /// Another program took the display (a VT switch): wait and take it
    /// back.
    #[error("{0}: the display was taken by another program (VT switch)")]
    LostMaster(PathBuf),
}

/// Which output and mode to drive: by connector name (`HDMI-A-1`) and
/// `WIDTHxHEIGHT[@HZ]`, else the first connected output and its preferred
/// mode.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OutputChoice {
    pub connector: Option<String>,
    pub mode: Option<(u16, u16, Option<u32>)>,
}

impl OutputChoice {
    /// The output and mode `[display]` asks for.
    #[must_use]
    pub fn from_config(d: &crate::display::config::DisplayConfig) -> Self {
        Self {
            connector: (!d.output.is_empty()).then(|| d.output.clone()),
            mode: Self::parse_mode(&d.mode),
        }
    }

    /// Parse a mode as written in the configuration: `1280x800` or
    /// `1920x1080@60`.
    #[must_use]
    pub fn parse_mode(s: &str) -> Option<(u16, u16, Option<u32>)> {
        let (size, hz) = match s.split_once('@') {
            Some((size, hz)) => (size, Some(hz.trim().parse().ok()?)),
            None => (s, None),
        };
        let (w, h) = size.split_once('x')?;
        Some((w.trim().parse().ok()?, h.trim().parse().ok()?, hz))
    }
}

/// The output being driven, with its two buffers.
pub struct CopyPresenter {
    card: Card,
    path: PathBuf,
    name: String,
    connector: connector::Handle,
    crtc: crtc::Handle,
    mode: Mode,
    buffers: Vec<(DumbBuffer, framebuffer::Handle)>,
    /// The buffer on screen (or queued to be).
    front: usize,
    /// A page flip is queued and its event not yet read.
    pending: bool,
    /// The CRTC as it was, to give back.
    saved: Option<crtc::Info>,
    flips: u64,
}

pub(crate) fn connector_name(info: &connector::Info) -> String {
    format!("{}-{}", info.interface().as_str(), info.interface_id())
}

/// How frames reach the output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PresenterKind {
    /// Direct where the Vulkan driver can drive the display, else copy.
    #[default]
    Auto,
    /// Vulkan drives the display (VK_EXT_acquire_drm_display).
    Direct,
    /// Frames rendered offscreen and copied into dumb buffers.
    Copy,
}

impl PresenterKind {
    /// `auto`, `direct` or `copy`, as written in `[display] presenter`.
    #[must_use]
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(Self::Auto),
            "direct" => Some(Self::Direct),
            "copy" => Some(Self::Copy),
            _ => None,
        }
    }
}

/// A connected output found on a card, with the mode to drive it in.
pub(crate) struct Found {
    pub card: Card,
    pub path: PathBuf,
    pub name: String,
    pub connector: connector::Handle,
    pub crtc: crtc::Handle,
    pub mode: Mode,
}

/// Find the output `choice` names (or the first connected one) on the
/// cards in `dir` (normally `/dev/dri`).
pub(crate) fn find_output(dir: &Path, choice: &OutputChoice) -> Result<Found, PresentError> {
    let mut seen = Vec::new();
    for path in crate::platform::kms::card_paths(dir)? {
        let card = Card::open(&path)?;
        let io = |what, source| PresentError::Io {
            path: path.clone(),
            what,
            source,
        };
        let Ok(res) = card.resource_handles() else {
            continue; // a render-only node
        };
        for &h in res.connectors() {
            let info = card
                .get_connector(h, true)
                .map_err(|e| io("reading a connector", e))?;
            let name = connector_name(&info);
            let connected = info.state() == connector::State::Connected;
            seen.push(format!(
                "{name} ({})",
                if connected {
                    "connected"
                } else {
                    "disconnected"
                }
            ));
            if choice.connector.as_ref().is_some_and(|c| *c != name) || !connected {
                continue;
            }
            let mode = pick_mode(info.modes(), choice.mode).ok_or_else(|| {
                PresentError::NoOutput(format!(
                    "{name} has no mode {}; its modes: {}",
                    choice.mode.map_or_else(String::new, |(w, h, hz)| format!(
                        "{w}x{h}{}",
                        hz.map_or(String::new(), |hz| format!("@{hz}"))
                    )),
                    info.modes()
                        .iter()
                        .map(|m| format!("{}x{}@{}", m.size().0, m.size().1, m.vrefresh()))
                        .collect::<Vec<_>>()
                        .join(" ")
                ))
            })?;
            let crtc = crtc_for(&card, &res, &info)
                .ok_or_else(|| PresentError::NoOutput(format!("{name}: no CRTC can drive it")))?;
            return Ok(Found {
                card,
                path: path.clone(),
                name,
                connector: h,
                crtc,
                mode,
            });
        }
    }
    let seen = if seen.is_empty() {
        "none".to_owned()
    } else {
        seen.join(", ")
    };
    Err(PresentError::NoOutput(match &choice.connector {
        Some(c) => format!(
            "no connected output named {c} in {} (outputs: {seen}); see `marionette list-outputs`",
            dir.display(),
        ),
        None => format!(
            "no connected display in {} (outputs: {seen}): plug a display in, or check the cable",
            dir.display(),
        ),
    }))
}

/// Become DRM master of `card` (the first client of a card is master
/// already; an explicit request fails only if another program holds it).
#[tracing::instrument(level = "debug", skip(card), err(level = "debug"))]
pub(crate) fn become_master(card: &Card, path: &Path) -> Result<(), PresentError> {
    if let Err(source) = drm::Device::acquire_master_lock(card) {
        if source.raw_os_error() != Some(libc::EINVAL) {
            return Err(PresentError::Master {
                path: path.to_owned(),
                source,
            });
        }
    }
    Ok(())
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
    pub fn open(dir: &Path, choice: &OutputChoice) -> Result<Self, PresentError> {
        let f = find_output(dir, choice)?;
        Self::start(f.card, f.path, f.name, f.connector, f.crtc, f.mode)
    }

    fn start(
        card: Card,
        path: PathBuf,
        name: String,
        connector: connector::Handle,
        crtc: crtc::Handle,
        mode: Mode,
    ) -> Result<Self, PresentError> {
        become_master(&card, &path)?;
        let io = |what, source| PresentError::Io {
            path: path.clone(),
            what,
            source,
        };
        let (w, h) = mode.size();
        let mut buffers = Vec::new();
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
        let saved = card.get_crtc(crtc).ok();
        card.set_crtc(crtc, Some(buffers[0].1), (0, 0), &[connector], Some(mode))
            .map_err(|e| io("setting the mode", e))?;
        tracing::info!(
            card = %path.display(),
            output = %name,
            width = w,
            height = h,
            refresh_hz = mode.vrefresh(),
            presenter = "copy",
            "driving the display (frames rendered offscreen, copied into dumb buffers, page-flipped on vblank)"
        );
        Ok(Self {
            card,
            path,
            name,
            connector,
            crtc,
            mode,
            buffers,
            front: 0,
            pending: false,
            saved,
            flips: 0,
        })
    }

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
        self.flips
    }

    /// Whether a flip is queued (the next frame waits for it).
    #[must_use]
    pub fn flip_pending(&self) -> bool {
        self.pending
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
            self.pending = false;
            self.flips += 1;
        }
        Ok(flipped)
    }

    /// Wait up to `timeout` for the queued flip: whether it completed.
    pub fn wait_flip(&mut self, timeout: Duration) -> Result<bool, PresentError> {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        if !self.pending {
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
        Ok(!self.pending)
    }

    /// Copy `img` (RGBA, the output's size) into the back buffer and flip
    /// to it at the next vblank. A flip still queued is waited for first.
    pub fn present(&mut self, img: &Image) -> Result<(), PresentError> {
        if self.pending && !self.wait_flip(Duration::from_millis(250))? {
            // The flip never came (a stalled driver): start over with a
            // mode set rather than queue behind it.
            tracing::warn!(output = %self.name, "page flip did not complete in 250 ms; setting the mode again");
            self.pending = false;
            self.restore()?;
        }
        let back = 1 - self.front;
        let (w, h) = self.size();
        {
            let (db, _) = &mut self.buffers[back];
            let pitch = drm::buffer::Buffer::pitch(db) as usize;
            let mut map = self
                .card
                .map_dumb_buffer(db)
                .map_err(|source| PresentError::Io {
                    path: self.path.clone(),
                    what: "mapping a frame buffer",
                    source,
                })?;
            copy_rgba_to_xrgb(img, map.as_mut(), pitch, w, h);
        }
        match self
            .card
            .page_flip(self.crtc, self.buffers[back].1, PageFlipFlags::EVENT, None)
        {
            Ok(()) => {
                self.front = back;
                self.pending = true;
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
        self.pending = false;
        self.restore().is_ok()
    }

    fn restore(&mut self) -> Result<(), PresentError> {
        self.card
            .set_crtc(
                self.crtc,
                Some(self.buffers[self.front].1),
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
        if self.pending {
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
        for (db, fb) in self.buffers.drain(..) {
            let _ = self.card.destroy_framebuffer(fb);
            let _ = self.card.destroy_dumb_buffer(db);
        }
        let _ = drm::Device::release_master_lock(&self.card);
    }
}

/// The mode asked for, else the preferred one, else the first.
fn pick_mode(modes: &[Mode], want: Option<(u16, u16, Option<u32>)>) -> Option<Mode> {
    match want {
        Some((w, h, hz)) => modes
            .iter()
            .filter(|m| m.size() == (w, h) && hz.is_none_or(|hz| m.vrefresh() == hz))
            .max_by_key(|m| m.vrefresh())
            .copied(),
        None => modes
            .iter()
            .find(|m| {
                m.mode_type()
                    .contains(drm::control::ModeTypeFlags::PREFERRED)
            })
            .or_else(|| modes.first())
            .copied(),
    }
}

/// A CRTC for the connector: the one its encoder drives now, else the
/// first its encoders can use.
fn crtc_for(
    card: &Card,
    res: &drm::control::ResourceHandles,
    info: &connector::Info,
) -> Option<crtc::Handle> {
    if let Some(c) = info
        .current_encoder()
        .and_then(|e| card.get_encoder(e).ok())
        .and_then(|e| e.crtc())
    {
        return Some(c);
    }
    info.encoders()
        .iter()
        .filter_map(|&e| card.get_encoder(e).ok())
        .flat_map(|e| res.filter_crtcs(e.possible_crtcs()))
        .next()
}

/// RGBA rows into XRGB8888 (little-endian B, G, R, X) rows of `pitch`
/// bytes; what does not fit is cut, what is missing stays black.
pub fn copy_rgba_to_xrgb(img: &Image, dst: &mut [u8], pitch: usize, width: u32, height: u32) {
    let w = width.min(img.width) as usize;
    for y in 0..height.min(img.height) as usize {
        let src = &img.rgba[y * img.width as usize * 4..][..w * 4];
        let Some(row) = dst.get_mut(y * pitch..y * pitch + w * 4) else {
            break;
        };
        for (d, s) in row.chunks_exact_mut(4).zip(src.chunks_exact(4)) {
            d[0] = s[2];
            d[1] = s[1];
            d[2] = s[0];
            d[3] = 0xff;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_parse_as_written() {
        assert_eq!(
            OutputChoice::parse_mode("1280x800"),
            Some((1280, 800, None))
        );
        assert_eq!(
            OutputChoice::parse_mode("1920x1080@60"),
            Some((1920, 1080, Some(60)))
        );
        assert_eq!(OutputChoice::parse_mode("big"), None);
        assert_eq!(OutputChoice::parse_mode("1280x"), None);
    }

    #[test]
    fn rgba_becomes_xrgb_with_the_pitch() {
        let img = Image {
            width: 2,
            height: 2,
            rgba: vec![
                1, 2, 3, 4, 5, 6, 7, 8, //
                9, 10, 11, 12, 13, 14, 15, 16,
            ],
        };
        let mut dst = vec![0u8; 3 * 12];
        copy_rgba_to_xrgb(&img, &mut dst, 12, 3, 3);
        assert_eq!(&dst[0..8], &[3, 2, 1, 255, 7, 6, 5, 255]);
        assert_eq!(&dst[8..12], &[0, 0, 0, 0], "beyond the image stays black");
        assert_eq!(&dst[12..20], &[11, 10, 9, 255, 15, 14, 13, 255]);
        assert!(dst[24..].iter().all(|b| *b == 0));
    }
}
