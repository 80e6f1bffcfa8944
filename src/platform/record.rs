//! `marionette record`: a live device's events into an evemu file.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::evdev::{EvdevDevice, EvdevOpener};
use crate::input::config::InputConfig;
use crate::input::device::DeviceKind;
use crate::input::evemu;
use crate::input::event::RawEvent;
use crate::input::hub::{DeviceOpener, EventDevice, LiveError, scan_error};
use crate::platform::signals;

/// `marionette record`: write a device's events to an evemu file until
/// Ctrl-C (or `seconds`). Each frame is flushed as it completes, so an
/// interrupted recording keeps everything up to the last frame.
pub fn record(
    input: &InputConfig,
    device: Option<&Path>,
    out: &Path,
    seconds: Option<f64>,
) -> Result<(), LiveError> {
    let opener = EvdevOpener;
    let path = match device {
        Some(p) => p.to_owned(),
        None => find_touchscreen(&opener, &input.dev_dir)?,
    };
    let mut dev = EvdevDevice::open(&path).map_err(|source| LiveError::Io {
        path: path.clone(),
        source,
    })?;
    let file = crate::output::create(out).map_err(|source| LiveError::Write {
        path: out.to_owned(),
        source,
    })?;
    let mut w = io::BufWriter::new(file);
    let werr = |source| LiveError::Write {
        path: out.to_owned(),
        source,
    };
    evemu::write_description(&mut w, dev.description()).map_err(werr)?;
    w.flush().map_err(werr)?;
    signals::install_stop_handler();
    tracing::info!(device = %dev.description().name, path = %path.display(), out = %out.display(), "recording; stop with Ctrl-C");
    let started = Instant::now();
    let deadline = seconds.map(|s| Duration::from_secs_f64(s.max(0.0)));
    let mut t0: Option<i64> = None;
    let mut events = Vec::new();
    let (mut n_events, mut n_frames) = (0u64, 0u64);
    while !signals::stop_requested() && deadline.is_none_or(|d| started.elapsed() < d) {
        {
            use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
            let mut fds = [PollFd::new(dev.fd(), PollFlags::POLLIN)];
            match poll(&mut fds, PollTimeout::from(100u16)) {
                Ok(_) | Err(nix::errno::Errno::EINTR) => {}
                Err(e) => {
                    return Err(LiveError::Io {
                        path: path.clone(),
                        source: e.into(),
                    });
                }
            }
        }
        events.clear();
        let gone = dev.read(&mut events);
        for e in &events {
            let base = *t0.get_or_insert(e.time_us);
            evemu::write_event(
                &mut w,
                &RawEvent {
                    time_us: e.time_us - base,
                    ..*e
                },
            )
            .map_err(werr)?;
            n_events += 1;
            if e.is_syn_report() {
                n_frames += 1;
                w.flush().map_err(werr)?;
            }
        }
        if let Err(e) = gone {
            w.flush().map_err(werr)?;
            tracing::warn!(error = %e, "device went away; recording ends here");
            break;
        }
    }
    w.flush().map_err(werr)?;
    tracing::info!(events = n_events, frames = n_frames, out = %out.display(), "recording written");
    Ok(())
}

/// The first touchscreen in `dir`. When none is found and some node could
/// not be opened for want of permission, that is the error (exit 77: join
/// the `input` group), not "no touchscreen" (69).
fn find_touchscreen(opener: &dyn DeviceOpener, dir: &Path) -> Result<PathBuf, LiveError> {
    let paths = opener.scan(dir).map_err(|source| scan_error(dir, source))?;
    let mut denied = None;
    let found = paths.into_iter().find(|p| match opener.open(p) {
        Ok(d) => d.description().kind() == DeviceKind::Touchscreen,
        Err(source) => {
            if source.kind() == io::ErrorKind::PermissionDenied && denied.is_none() {
                denied = Some(LiveError::Io {
                    path: p.clone(),
                    source,
                });
            }
            false
        }
    });
    match (found, denied) {
        (Some(p), _) => Ok(p),
        (None, Some(e)) => Err(e),
        (None, None) => Err(LiveError::NoTouchscreen(dir.to_owned())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::hub::EventDevice;

    /// Every node is there, none may be opened.
    struct Locked;

    impl DeviceOpener for Locked {
        fn scan(&self, _dir: &Path) -> io::Result<Vec<PathBuf>> {
            Ok(vec![
                PathBuf::from("/dev/input/event0"),
                PathBuf::from("/dev/input/event1"),
            ])
        }
        fn open(&self, _path: &Path) -> io::Result<Box<dyn EventDevice>> {
            Err(io::Error::from(io::ErrorKind::PermissionDenied))
        }
    }

    /// No nodes at all.
    struct Empty;

    impl DeviceOpener for Empty {
        fn scan(&self, _dir: &Path) -> io::Result<Vec<PathBuf>> {
            Ok(Vec::new())
        }
        fn open(&self, _path: &Path) -> io::Result<Box<dyn EventDevice>> {
            Err(io::Error::from(io::ErrorKind::NotFound))
        }
    }

    #[test]
    fn unreadable_nodes_are_a_permission_problem_not_a_missing_panel() {
        let e = find_touchscreen(&Locked, Path::new("/dev/input")).unwrap_err();
        assert!(
            matches!(&e, LiveError::Io { source, path } if source.kind() == io::ErrorKind::PermissionDenied && path.ends_with("event0")),
            "{e:?}"
        );
        assert!(e.to_string().contains("`input` group"), "{e}");
        let e = find_touchscreen(&Empty, Path::new("/dev/input")).unwrap_err();
        assert!(matches!(e, LiveError::NoTouchscreen(_)), "{e:?}");
    }
}
