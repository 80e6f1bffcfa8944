//! DRM/KMS outputs: the cards in `/dev/dri`, their connectors, whether a
//! display is connected, and its modes (`marionette list-outputs`).

use std::os::fd::{AsFd, BorrowedFd};
use std::path::{Path, PathBuf};

use drm::control::Device as _;
use serde::Serialize;
use thiserror::Error;

/// Why outputs could not be listed.
#[derive(Debug, Error)]
pub enum KmsError {
    #[error(
        "no DRM devices in {0} (is a GPU or display driver loaded? virtio-gpu, i915, amdgpu, ...)"
    )]
    NoDevices(PathBuf),
    #[error("cannot read {path}: {source}{hint}", hint = if source.kind() == std::io::ErrorKind::PermissionDenied { " (add the user to the video group)" } else { "" })]
    Open {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {what}: {source}")]
    Query {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
}

/// An open DRM card.
pub struct Card(std::fs::File);

impl AsFd for Card {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.0.as_fd()
    }
}

impl drm::Device for Card {}
impl drm::control::Device for Card {}

impl Card {
    /// Open a card node read-write.
    #[tracing::instrument(level = "debug", err(level = "debug"))]
    pub fn open(path: &Path) -> Result<Self, KmsError> {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map(Card)
            .map_err(|source| KmsError::Open {
                path: path.to_owned(),
                source,
            })
    }
}

/// A display mode.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ModeInfo {
    pub width: u16,
    pub height: u16,
    pub refresh_hz: u32,
    pub preferred: bool,
}

/// A connector of a card.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct OutputInfo {
    pub card: PathBuf,
    pub driver: String,
    /// As the kernel names it: `HDMI-A-1`, `eDP-1`, `Virtual-1`.
    pub name: String,
    pub connected: bool,
    pub modes: Vec<ModeInfo>,
}

impl OutputInfo {}

impl std::fmt::Display for OutputInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}) {}: {}",
            self.card.display(),
            self.driver,
            self.name,
            if self.connected {
                "connected"
            } else {
                "disconnected"
            }
        )?;
        for (i, m) in self.modes.iter().enumerate() {
            write!(
                f,
                "{}{}x{}@{}{}",
                if i == 0 { ", modes " } else { " " },
                m.width,
                m.height,
                m.refresh_hz,
                if m.preferred { " (preferred)" } else { "" }
            )?;
        }
        Ok(())
    }
}

/// The outputs of one card.
pub fn outputs_of(path: &Path) -> Result<Vec<OutputInfo>, KmsError> {
    let card = Card::open(path)?;
    let query = |what, source| KmsError::Query {
        path: path.to_owned(),
        what,
        source,
    };
    let driver = drm::Device::get_driver(&card)
        .map(|d| d.name().to_string_lossy().into_owned())
        .unwrap_or_default();
    let res = card
        .resource_handles()
        .map_err(|e| query("reading its resources (not a KMS device?)", e))?;
    let mut out = Vec::new();
    for &h in res.connectors() {
        let c = card
            .get_connector(h, true)
            .map_err(|e| query("reading a connector", e))?;
        let modes = c
            .modes()
            .iter()
            .map(|m| {
                let (width, height) = m.size();
                ModeInfo {
                    width,
                    height,
                    refresh_hz: m.vrefresh(),
                    preferred: m
                        .mode_type()
                        .contains(drm::control::ModeTypeFlags::PREFERRED),
                }
            })
            .collect();
        out.push(OutputInfo {
            card: path.to_owned(),
            driver: driver.clone(),
            name: format!("{}-{}", c.interface().as_str(), c.interface_id()),
            connected: c.state() == drm::control::connector::State::Connected,
            modes,
        });
    }
    Ok(out)
}

/// The card nodes under `dir` (normally `/dev/dri`), sorted.
pub fn card_paths(dir: &Path) -> Result<Vec<PathBuf>, KmsError> {
    let mut cards: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|_| KmsError::NoDevices(dir.to_owned()))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("card"))
        })
        .collect();
    cards.sort();
    if cards.is_empty() {
        return Err(KmsError::NoDevices(dir.to_owned()));
    }
    Ok(cards)
}

/// Every card's outputs under `dir` (normally `/dev/dri`).
pub fn list_outputs(dir: &Path) -> Result<Vec<OutputInfo>, KmsError> {
    let mut out = Vec::new();
    for c in card_paths(dir)? {
        out.extend(outputs_of(&c)?);
    }
    Ok(out)
}
