//! The kiosk's timing decisions, apart from the devices: when to stop,
//! when nobody has touched long enough to rest and start the attract loop,
//! when to try the display or the GPU again after losing it, when systemd's
//! watchdog is due, and how long the loop may sleep. Every decision takes
//! the time it is asked at (seconds on the kiosk's clock), so the loop's
//! behaviour over minutes or days is tested with a made-up clock.

/// After a rest begins, the attract recording starts this much later (s).
pub const ATTRACT_DELAY_S: f64 = 2.0;
/// A display taken by another program (VT switch) is asked back this
/// often (s).
pub const DISPLAY_RETRY_S: f64 = 0.5;
/// A GPU device that failed is rebuilt this often until it works (s).
pub const GPU_RETRY_S: f64 = 1.0;
/// The longest sleep of the loop: input, signals and retries are looked at
/// at least this often (s).
pub const MAX_WAIT_S: f64 = 0.1;

/// The kiosk loop's timers.
#[derive(Clone, Debug, PartialEq)]
pub struct Timers {
    /// Rest after this long without a touch (`kiosk.idle_after_s`).
    idle_after_s: f64,
    /// Stop at this time (`run --seconds`).
    stop_at_s: Option<f64>,
    /// systemd's watchdog interval, when it asks for one.
    watchdog_s: Option<f64>,
    last_watchdog: f64,
    resting: bool,
    display_lost_at: Option<f64>,
    gpu_lost_at: Option<f64>,
    last_touch: f64,
}

impl Timers {
    #[must_use]
    pub fn new(idle_after_s: f64, stop_at_s: Option<f64>, watchdog_s: Option<f64>) -> Self {
        Self {
            idle_after_s,
            stop_at_s,
            watchdog_s,
            last_watchdog: 0.0,
            resting: false,
            display_lost_at: None,
            gpu_lost_at: None,
            last_touch: 0.0,
        }
    }

    /// Whether a run with `--seconds` has had its time.
    #[must_use]
    pub fn stop_due(&self, t: f64) -> bool {
        self.stop_at_s.is_some_and(|s| t >= s)
    }

    /// A touch arrived, stamped `event_t` by its device, at `t`: the time
    /// the controller hears it at, never before the previous touch's nor
    /// after now (a device clock that jumps cannot reorder touches).
    pub fn touch(&mut self, event_t: f64, t: f64) -> f64 {
        self.resting = false;
        let at = event_t.clamp(self.last_touch, t);
        self.last_touch = at;
        at
    }

    /// Whether to rest now, the controller idle for `idle_s`: true once per
    /// stretch without touches.
    pub fn rest_due(&mut self, idle_s: f64) -> bool {
        let due = !self.resting && idle_s > self.idle_after_s;
        self.resting |= due;
        due
    }

    /// Whether frames may be drawn: the display is ours and the GPU works.
    #[must_use]
    pub fn can_draw(&self) -> bool {
        self.display_lost_at.is_none() && self.gpu_lost_at.is_none()
    }

    /// Another program took the display at `t`.
    pub fn display_lost(&mut self, t: f64) {
        self.display_lost_at = Some(t);
    }

    /// Whether to ask for the display again at `t`; the next try is
    /// [`DISPLAY_RETRY_S`] later unless [`Self::display_back`] is called.
    pub fn display_retry_due(&mut self, t: f64) -> bool {
        retry_due(&mut self.display_lost_at, t, DISPLAY_RETRY_S)
    }

    /// The display is ours again.
    pub fn display_back(&mut self) {
        self.display_lost_at = None;
    }

    /// Rendering failed at `t`: the GPU device is to be rebuilt.
    pub fn gpu_lost(&mut self, t: f64) {
        self.gpu_lost_at = Some(t);
    }

    /// Whether to rebuild the GPU device at `t`; the next try is
    /// [`GPU_RETRY_S`] later unless [`Self::gpu_back`] is called.
    pub fn gpu_retry_due(&mut self, t: f64) -> bool {
        retry_due(&mut self.gpu_lost_at, t, GPU_RETRY_S)
    }

    /// The GPU device works again.
    pub fn gpu_back(&mut self) {
        self.gpu_lost_at = None;
    }

    /// Whether systemd's watchdog is to be fed at `t`.
    pub fn watchdog_due(&mut self, t: f64) -> bool {
        match self.watchdog_s {
            Some(w) if t - self.last_watchdog >= w => {
                self.last_watchdog = t;
                true
            }
            _ => false,
        }
    }
}

/// Whether a retry is due `every` seconds after `since`; a due retry
/// restarts the wait.
fn retry_due(since: &mut Option<f64>, t: f64, every: f64) -> bool {
    match since {
        Some(s) if t - *s > every => {
            *since = Some(t);
            true
        }
        _ => false,
    }
}

/// How long the loop may sleep (s): not at all when the swapchain (no
/// page-flip descriptor: `direct`) already waited for vblank and something
/// moves, a frame when something moves, else [`MAX_WAIT_S`], so that an
/// idle kiosk does not spin.
#[must_use]
pub fn wait_s(moving: bool, direct: bool, frame_s: f64) -> f64 {
    let s = if moving && direct {
        0.0
    } else if moving {
        frame_s
    } else {
        MAX_WAIT_S
    };
    s.min(MAX_WAIT_S)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up clock: the loop's time, moved by hand.
    struct FakeClock(f64);

    impl FakeClock {
        fn tick(&mut self, s: f64) -> f64 {
            self.0 += s;
            self.0
        }
    }

    #[test]
    fn rests_once_after_the_idle_time_and_again_only_after_a_touch() {
        let mut timers = Timers::new(45.0, None, None);
        let mut clock = FakeClock(0.0);
        let mut idle_since = 0.0;
        let mut rests = Vec::new();
        // Two minutes at 30 frames a second, a touch at 100 s.
        while clock.0 < 120.0 {
            let t = clock.tick(1.0 / 30.0);
            if (100.0..100.04).contains(&t) {
                timers.touch(t, t);
                idle_since = t;
            }
            if timers.rest_due(t - idle_since) {
                rests.push(t);
            }
        }
        assert_eq!(rests.len(), 1, "{rests:?}");
        assert!((rests[0] - 45.0).abs() <= 1.0 / 30.0, "{rests:?}");
        // Idle for another 45 s after the touch: a second rest.
        while clock.0 < 150.0 {
            let t = clock.tick(1.0 / 30.0);
            if timers.rest_due(t - idle_since) {
                rests.push(t);
            }
        }
        assert_eq!(rests.len(), 2);
        let late = rests[1] - (idle_since + 45.0);
        assert!((0.0..=1.0 / 30.0 + 1e-9).contains(&late), "{rests:?}");
    }

    #[test]
    fn touches_are_never_stamped_before_the_last_nor_after_now() {
        let mut timers = Timers::new(45.0, None, None);
        assert_eq!(timers.touch(1.0, 2.0), 1.0);
        // A device clock that went back: held at the last touch.
        assert_eq!(timers.touch(0.5, 2.1), 1.0);
        // One from the future: now.
        assert_eq!(timers.touch(9.0, 2.2), 2.2);
        assert_eq!(timers.touch(2.3, 2.4), 2.3);
    }

    #[test]
    fn a_lost_display_is_asked_back_after_each_half_second_until_it_returns() {
        let mut timers = Timers::new(45.0, None, None);
        let mut clock = FakeClock(10.0);
        timers.display_lost(clock.0);
        assert!(!timers.can_draw());
        let mut tries = Vec::new();
        for _ in 0..60 {
            let t = clock.tick(0.125);
            if timers.display_retry_due(t) {
                tries.push(t);
                if tries.len() == 3 {
                    timers.display_back();
                }
            }
        }
        assert_eq!(tries.len(), 3, "{tries:?}");
        for w in tries.windows(2) {
            // The first tick past half a second after the last try.
            assert_eq!(w[1] - w[0], 0.625, "{tries:?}");
        }
        assert!(timers.can_draw());
        assert!(
            !timers.display_retry_due(clock.tick(5.0)),
            "no retries once back"
        );
    }

    #[test]
    fn a_failed_gpu_is_rebuilt_every_second_and_blocks_drawing_meanwhile() {
        let mut timers = Timers::new(45.0, None, None);
        let mut clock = FakeClock(0.0);
        timers.gpu_lost(clock.0);
        let mut tries = 0;
        while clock.0 < 3.5 {
            let t = clock.tick(0.125);
            assert!(!timers.can_draw());
            if timers.gpu_retry_due(t) {
                tries += 1;
            }
        }
        assert_eq!(tries, 3);
        timers.gpu_back();
        assert!(timers.can_draw());
        // Both lost: drawing waits for both.
        timers.gpu_lost(4.0);
        timers.display_lost(4.0);
        timers.gpu_back();
        assert!(!timers.can_draw());
    }

    #[test]
    fn the_watchdog_is_fed_at_its_interval_and_never_without_one() {
        let mut timers = Timers::new(45.0, None, Some(5.0));
        let mut clock = FakeClock(0.0);
        let mut fed = Vec::new();
        while clock.0 < 20.0 {
            let t = clock.tick(0.25);
            if timers.watchdog_due(t) {
                fed.push(t);
            }
        }
        assert_eq!(fed, vec![5.0, 10.0, 15.0, 20.0]);
        let mut none = Timers::new(45.0, None, None);
        assert!(!none.watchdog_due(1e6));
    }

    #[test]
    fn stops_at_its_time_limit_only_when_given_one() {
        let timers = Timers::new(45.0, Some(3.0), None);
        assert!(!timers.stop_due(2.999));
        assert!(timers.stop_due(3.0));
        assert!(!Timers::new(45.0, None, None).stop_due(1e9));
    }

    #[test]
    fn sleeps_a_frame_while_moving_and_a_tenth_when_still() {
        assert_eq!(wait_s(true, true, 1.0 / 60.0), 0.0);
        assert!((wait_s(true, false, 1.0 / 60.0) - 1.0 / 60.0).abs() < 1e-12);
        assert_eq!(wait_s(false, false, 1.0 / 60.0), MAX_WAIT_S);
        assert_eq!(wait_s(false, true, 1.0 / 60.0), MAX_WAIT_S);
        // A slow output's frame is still capped.
        assert_eq!(wait_s(true, false, 0.5), MAX_WAIT_S);
    }
}
