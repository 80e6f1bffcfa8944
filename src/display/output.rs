//! Which output to drive and how: the output and mode a configuration
//! asks for, finding it on the cards, becoming DRM master, and the
//! presenters to try in turn.

use std::path::{Path, PathBuf};

use drm::control::{Device as _, Mode, connector, crtc};

use super::error::PresentError;
use crate::platform::kms::Card;

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
    /// `1920x1080@60`; no size or rate of 0.
    #[must_use]
    pub fn parse_mode(s: &str) -> Option<(u16, u16, Option<u32>)> {
        let (size, hz) = match s.split_once('@') {
            Some((size, hz)) => (size, Some(hz.trim().parse().ok()?)),
            None => (s, None),
        };
        let (w, h) = size.split_once('x')?;
        let (w, h): (u16, u16) = (w.trim().parse().ok()?, h.trim().parse().ok()?);
        (w > 0 && h > 0 && hz != Some(0)).then_some((w, h, hz))
    }
}

pub(crate) fn connector_name(info: &connector::Info) -> String {
    format!("{}-{}", info.interface().as_str(), info.interface_id())
}

/// How frames reach the output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PresenterKind {
    /// Direct where the Vulkan driver can drive the display, else gbm
    /// (zero copy, else copied into), else copy.
    #[default]
    Auto,
    /// Vulkan drives the display (VK_EXT_acquire_drm_display).
    Direct,
    /// gbm's scanout buffers: rendered into where the Vulkan driver
    /// imports them (zero copy), else frames rendered offscreen written
    /// into them.
    Gbm,
    /// Frames rendered offscreen and copied into dumb buffers.
    Copy,
}

impl PresenterKind {
    /// `auto`, `direct`, `gbm` or `copy`, as written in `[display]
    /// presenter`.
    #[must_use]
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(Self::Auto),
            "direct" => Some(Self::Direct),
            "gbm" => Some(Self::Gbm),
            "copy" => Some(Self::Copy),
            _ => None,
        }
    }
}

/// One presenter to try.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attempt {
    Direct,
    /// gbm's buffers rendered into (zero copy).
    GbmZeroCopy,
    /// gbm's buffers written into.
    Gbm,
    Dumb,
}

impl Attempt {
    /// As the journal names it.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Direct => "direct",
            Self::GbmZeroCopy => "gbm zero-copy",
            Self::Gbm => "gbm",
            Self::Dumb => "copy",
        }
    }
}

impl PresenterKind {
    /// The presenters to try, in order, until one opens: `auto` tries
    /// direct (unless the frames are rendered on the CPU, which cannot
    /// drive a display), then gbm's buffers rendered into, then written
    /// into, then dumb buffers; `gbm` tries its two ways; `direct` and
    /// `copy` are the only one tried.
    #[must_use]
    pub fn attempts(self, cpu_rendering: bool) -> &'static [Attempt] {
        match (self, cpu_rendering) {
            (Self::Direct, _) => &[Attempt::Direct],
            (Self::Gbm, _) => &[Attempt::GbmZeroCopy, Attempt::Gbm],
            (Self::Copy, _) => &[Attempt::Dumb],
            (Self::Auto, true) => &[Attempt::GbmZeroCopy, Attempt::Gbm, Attempt::Dumb],
            (Self::Auto, false) => &[
                Attempt::Direct,
                Attempt::GbmZeroCopy,
                Attempt::Gbm,
                Attempt::Dumb,
            ],
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_tries_direct_then_gbm_zero_copy_then_gbm_then_dumb_buffers() {
        use Attempt::{Direct, Dumb, Gbm, GbmZeroCopy};
        assert_eq!(
            PresenterKind::Auto.attempts(false),
            &[Direct, GbmZeroCopy, Gbm, Dumb]
        );
        // Frames drawn on the CPU never go to a Vulkan display, but may be
        // drawn into gbm's buffers.
        assert_eq!(
            PresenterKind::Auto.attempts(true),
            &[GbmZeroCopy, Gbm, Dumb]
        );
        for cpu in [false, true] {
            assert_eq!(PresenterKind::Direct.attempts(cpu), &[Direct]);
            assert_eq!(PresenterKind::Gbm.attempts(cpu), &[GbmZeroCopy, Gbm]);
            assert_eq!(PresenterKind::Copy.attempts(cpu), &[Dumb]);
        }
        assert_eq!(PresenterKind::parse("gbm"), Some(PresenterKind::Gbm));
    }

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
        // No size or rate of nothing.
        for zero in ["0x0@0", "0x800", "1280x0", "1920x1080@0"] {
            assert_eq!(OutputChoice::parse_mode(zero), None, "{zero}");
        }
    }
}
