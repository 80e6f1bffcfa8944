//! The input thread: the touchscreens read by the hub on a thread of
//! their own, waking the kiosk's loop through a socket.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use crate::app::config::Config;
use crate::input::hub::{HubEvent, InputHub, LiveError};
use crate::platform::clock::monotonic_us;
use crate::platform::evdev::EvdevOpener;

/// The touchscreens are read on their own thread, so that a slow frame
/// (a CPU renderer under load) never lets the kernel's event buffers
/// overflow; it wakes the render loop through a socket.
pub(crate) struct InputThread {
    events: std::sync::mpsc::Receiver<HubEvent>,
    wake: std::os::unix::net::UnixStream,
    stop: Arc<std::sync::atomic::AtomicBool>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl InputThread {
    pub(crate) fn start(config: Config, epoch_us: i64) -> Result<Self, LiveError> {
        use std::io::Write as _;
        let (tx, rx) = std::sync::mpsc::channel();
        let (wake, mut waker) =
            std::os::unix::net::UnixStream::pair().map_err(|source| LiveError::Io {
                path: PathBuf::from("socketpair"),
                source,
            })?;
        wake.set_nonblocking(true).ok();
        waker.set_nonblocking(true).ok();
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stopping = stop.clone();
        let handle = std::thread::Builder::new()
            .name("input".into())
            .spawn(move || {
                let mut hub =
                    InputHub::new(EvdevOpener, config.input.clone(), config.display.picture())
                        .since(epoch_us);
                let mut events = Vec::new();
                let wait = Duration::from_millis(50.min(config.input.rescan_interval_ms));
                while !stopping.load(std::sync::atomic::Ordering::SeqCst) {
                    hub.dispatch(monotonic_us(), &mut events);
                    if !events.is_empty() {
                        for e in events.drain(..) {
                            if tx.send(e).is_err() {
                                return;
                            }
                        }
                        // A full socket already has a wake-up pending.
                        let _ = waker.write(&[1]);
                    }
                    if let Err(e) = hub.wait(wait) {
                        tracing::warn!(error = %e, "waiting for input failed");
                        std::thread::sleep(wait);
                    }
                }
            })
            .map_err(|source| LiveError::Io {
                path: PathBuf::from("input thread"),
                source,
            })?;
        Ok(Self {
            events: rx,
            wake,
            stop,
            handle: Some(handle),
        })
    }

    /// The descriptor that becomes readable when events are waiting.
    pub(crate) fn wake_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        use std::os::fd::AsFd as _;
        self.wake.as_fd()
    }

    /// Everything read since the last call.
    pub(crate) fn drain(&self, out: &mut Vec<HubEvent>) {
        use std::io::Read as _;
        let mut buf = [0u8; 64];
        while matches!((&self.wake).read(&mut buf), Ok(n) if n > 0) {}
        out.extend(self.events.try_iter());
    }

    pub(crate) fn stop(mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}
