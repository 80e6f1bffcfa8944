//! The monotonic clock: `CLOCK_MONOTONIC`, the clock evdev stamps events
//! with. Only the kiosk's loop and the input thread read it; everything
//! they drive is given times.

/// `CLOCK_MONOTONIC` in microseconds.
#[must_use]
pub fn monotonic_us() -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &raw mut ts) };
    ts.tv_sec * 1_000_000 + ts.tv_nsec / 1_000
}

/// A source of the time in microseconds, injected where a loop needs the
/// time so that tests can give it their own.
pub trait Clock {
    fn now_us(&self) -> i64;
}

/// The monotonic clock ([`monotonic_us`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Monotonic;

impl Clock for Monotonic {
    fn now_us(&self) -> i64 {
        monotonic_us()
    }
}
