//! Process exit codes (sysexits.h), so that systemd units can act on them
//! (`RestartPreventExitStatus=65 78`). The subsystems' errors are typed
//! (`thiserror`) and know nothing of exit codes; [`ExitStatus`] maps each
//! of them to its code in this one place.

use std::io;

use super::calibrate::CalibrateError;
use super::character::LoadError;
use super::config::ConfigError;
use super::headless::HeadlessError;
use super::kiosk::RunError;
use crate::character::gltf::GltfError;
use crate::display::present::PresentError;
use crate::input::evemu::EvemuError;
use crate::input::hub::LiveError;
use crate::platform::kms::KmsError;
use crate::platform::uinput::PlayError;

/// Success.
pub const OK: u8 = 0;
/// Something failed that has no more specific code.
pub const FAILURE: u8 = 1;
/// Wrong command-line usage (clap's own code).
pub const USAGE: u8 = 2;
/// Malformed input data: a recording or motion file that cannot be parsed.
pub const DATAERR: u8 = 65;
/// An input file does not exist or cannot be opened.
pub const NOINPUT: u8 = 66;
/// A required service or device is unavailable (no touchscreen, no uinput).
pub const UNAVAILABLE: u8 = 69;
/// An internal error: the program contradicted itself.
pub const SOFTWARE: u8 = 70;
/// Cannot create an output file.
pub const CANTCREAT: u8 = 73;
/// An I/O error on a device or file.
pub const IOERR: u8 = 74;
/// Permission denied (e.g. not in the `input` group).
pub const NOPERM: u8 = 77;
/// The configuration is invalid: fix the file, restarting will not help.
pub const CONFIG: u8 = 78;

/// The exit code an error stops the process with. Every error type that
/// can end a command is mapped here, and only here.
pub trait ExitStatus {
    /// The sysexits code for this error.
    fn exit_code(&self) -> u8;
}

impl ExitStatus for LiveError {
    /// The exit code this error deserves.
    fn exit_code(&self) -> u8 {
        match self {
            LiveError::Gone(_) | LiveError::NoTouchscreen(_) | LiveError::NoDeviceDir(_) => {
                UNAVAILABLE
            }
            LiveError::Io { source, .. } if source.kind() == io::ErrorKind::PermissionDenied => {
                NOPERM
            }
            LiveError::Io { source, .. } if source.kind() == io::ErrorKind::NotFound => NOINPUT,
            LiveError::Io { .. } => IOERR,
            LiveError::Write { .. } => CANTCREAT,
        }
    }
}

impl ExitStatus for PlayError {
    fn exit_code(&self) -> u8 {
        match self {
            PlayError::Uinput(e) if e.kind() == io::ErrorKind::PermissionDenied => NOPERM,
            PlayError::Uinput(_) => UNAVAILABLE,
            PlayError::Create { .. } | PlayError::Write(_) => IOERR,
        }
    }
}

impl ExitStatus for KmsError {
    /// The exit code (sysexits).
    fn exit_code(&self) -> u8 {
        match self {
            Self::NoDevices(_) | Self::Query { .. } => UNAVAILABLE,
            Self::Open { source, .. } if source.kind() == io::ErrorKind::PermissionDenied => NOPERM,
            Self::Open { .. } => UNAVAILABLE,
        }
    }
}

impl ExitStatus for PresentError {
    /// The exit code (sysexits).
    fn exit_code(&self) -> u8 {
        match self {
            Self::Kms(e) => e.exit_code(),
            Self::NoOutput(_)
            | Self::Master { .. }
            | Self::LostMaster(_)
            | Self::Direct { .. }
            | Self::ZeroCopy { .. }
            | Self::Gbm { .. } => UNAVAILABLE,
            Self::Gpu(e) if e.is_configuration() => CONFIG,
            Self::Gpu(_) => UNAVAILABLE,
            Self::Io { .. } => IOERR,
            Self::NoRenderer => SOFTWARE,
        }
    }
}

impl ExitStatus for RunError {
    /// The exit code (sysexits): 69 no display/adapter, 77 permissions,
    /// 78 a bad attract recording in the configuration.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Present(e) => e.exit_code(),
            Self::Gpu(_) => UNAVAILABLE,
            Self::Input(e) => e.exit_code(),
            Self::Attract { .. } => CONFIG,
        }
    }
}

impl ExitStatus for HeadlessError {
    /// The exit code (sysexits) for systemd and scripts.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Gpu(e) if e.is_configuration() => CONFIG,
            Self::Gpu(_) => UNAVAILABLE,
            Self::Write { .. } => CANTCREAT,
        }
    }
}

impl ExitStatus for CalibrateError {
    /// The exit code (sysexits): 65 touches refused, 69 no display or
    /// device, 73 cannot write, 78 a config file that cannot be edited.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Present(e) => e.exit_code(),
            Self::Input(e) => e.exit_code(),
            Self::Device(_) | Self::NoTouch { .. } => UNAVAILABLE,
            Self::Refused { .. } => DATAERR,
            Self::Stopped => FAILURE,
            Self::Write { .. } => CANTCREAT,
            Self::ConfigText { .. } => CONFIG,
        }
    }
}

impl ExitStatus for ConfigError {
    fn exit_code(&self) -> u8 {
        CONFIG
    }
}

impl ExitStatus for EvemuError {
    fn exit_code(&self) -> u8 {
        match self {
            EvemuError::Io { source, .. } if crate::reading::unreadable(source) => NOINPUT,
            EvemuError::Io { .. } => IOERR,
            _ => DATAERR,
        }
    }
}

impl ExitStatus for GltfError {
    fn exit_code(&self) -> u8 {
        match self {
            // A file that is not there (or cannot be read) is missing
            // input; anything wrong inside it is bad data.
            Self::Io { source, .. } if crate::reading::unreadable(source) => NOINPUT,
            Self::Io { .. } => IOERR,
            _ => DATAERR,
        }
    }
}

impl ExitStatus for LoadError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::Library(_) => DATAERR,
            Self::Figure(e) => e.exit_code(),
        }
    }
}

impl ExitStatus for crate::app::visits::store::VisitsError {
    /// 66 no such file; 65 a file that is not marionette's record, or of a
    /// newer schema; 74 SQLite failing to read it.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Missing(_) => NOINPUT,
            Self::NotOurs { .. } | Self::Newer { .. } => DATAERR,
            Self::Sqlite { source, .. } => match source.sqlite_error_code() {
                Some(rusqlite::ErrorCode::NotADatabase | rusqlite::ErrorCode::DatabaseCorrupt) => {
                    DATAERR
                }
                _ => IOERR,
            },
        }
    }
}
