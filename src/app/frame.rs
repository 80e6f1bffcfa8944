//! The frame loop the kiosk and headless replays share, and one frame's
//! picture from the controller's state.
//!
//! Each frame takes its time from a [`FrameClock`] (the kiosk's clock, or
//! fixed steps through a recording), the [`Backend`] feeds the controller
//! the touches due by then, the controller advances to that time, and the
//! backend shows or records the result. The kiosk's backend reads the
//! panels and page-flips on KMS (`app::kiosk`); the headless one replays a
//! recording into PNG files (`app::headless`).

use crate::control::marks::Marks;
use crate::control::stage::Stage;
use crate::platform::clock::Clock;
use crate::render::mesh::DrawList;
use crate::render::scene::{self, View};
use crate::screen::Rotation;

/// Whether the loop goes on after a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Stop,
}

/// The time of each frame, in seconds.
pub trait FrameClock {
    /// The next frame's time.
    fn next_frame(&mut self) -> f64;
}

/// Where a frame loop's touches come from and where its frames go.
pub trait Backend {
    type Error;
    /// Whether to stop before the frame at `t` (a signal, a time limit).
    fn stop(&mut self, _t: f64) -> bool {
        false
    }
    /// Hand the table the touches due by `t`.
    fn feed(&mut self, stage: &mut Stage, t: f64);
    /// The table has advanced to `t`: show or record the frame, and wait
    /// for the next if need be.
    fn frame(&mut self, stage: &mut Stage, t: f64) -> Result<Flow, Self::Error>;
}

/// Run frames until the backend stops; returns the last frame's time.
pub fn run<B: Backend>(
    ctl: &mut Stage,
    clock: &mut dyn FrameClock,
    backend: &mut B,
) -> Result<f64, B::Error> {
    loop {
        let t = clock.next_frame();
        if backend.stop(t) {
            return Ok(t);
        }
        backend.feed(ctl, t);
        ctl.advance(t);
        if backend.frame(ctl, t)? == Flow::Stop {
            return Ok(t);
        }
    }
}

/// Fixed steps: frame `n` at `n / hz` seconds (replays).
#[derive(Clone, Debug)]
pub struct Steps {
    hz: f64,
    tick: u64,
}

impl Steps {
    #[must_use]
    pub fn new(hz: f64) -> Self {
        Self { hz, tick: 0 }
    }
}

impl FrameClock for Steps {
    fn next_frame(&mut self) -> f64 {
        self.tick += 1;
        self.tick as f64 / self.hz
    }
}

/// Seconds since a start on a [`Clock`] (the kiosk).
#[derive(Clone, Copy)]
pub struct Since<'a> {
    clock: &'a dyn Clock,
    start_us: i64,
}

impl<'a> Since<'a> {
    /// Time 0 is now.
    #[must_use]
    pub fn new(clock: &'a dyn Clock) -> Self {
        Self {
            clock,
            start_us: clock.now_us(),
        }
    }

    /// The start, on the clock (µs).
    #[must_use]
    pub fn epoch_us(&self) -> i64 {
        self.start_us
    }

    /// A time on the clock (an event's stamp), in seconds since the start.
    #[must_use]
    pub fn seconds(&self, us: i64) -> f64 {
        (us - self.start_us) as f64 / 1e6
    }

    /// Now, in seconds since the start.
    #[must_use]
    pub fn now(&self) -> f64 {
        self.seconds(self.clock.now_us())
    }
}

impl FrameClock for Since<'_> {
    fn next_frame(&mut self) -> f64 {
        self.now()
    }
}

/// The draw list for the table's current postures and view: every
/// character in its tint.
#[must_use]
pub fn compose(stage: &Stage, rotation: Rotation, marks: &Marks) -> DrawList {
    let view = View {
        camera: stage.rig().camera(),
        rotation,
    };
    let held: Vec<Vec<crate::character::roles::Role>> =
        stage.actors().iter().map(|a| a.ctl.held()).collect();
    let figures: Vec<_> = stage.actors().iter().map(|a| a.figure_joints()).collect();
    let bodies: Vec<scene::Body<'_>> = stage
        .actors()
        .iter()
        .zip(&held)
        .zip(&figures)
        .map(|((a, held), figure)| {
            let c = a.ctl.character();
            scene::Body {
                skeleton: &c.lib.skeleton,
                roles: &c.roles,
                world: a.ctl.world(),
                held,
                tint: a.tint,
                figure: figure.as_ref().map(|(s, _)| *s),
                figure_joints: figure.as_ref().map(|(_, j)| j.as_ref()),
            }
        })
        .collect();
    scene::compose_bodies(&view, &bodies, marks)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    struct Fake(Cell<i64>);

    impl Clock for Fake {
        fn now_us(&self) -> i64 {
            self.0.get()
        }
    }

    #[test]
    fn steps_fall_at_whole_multiples_of_the_period() {
        let mut s = Steps::new(30.0);
        let t: Vec<f64> = (0..3).map(|_| s.next_frame()).collect();
        assert_eq!(t, vec![1.0 / 30.0, 2.0 / 30.0, 3.0 / 30.0]);
    }

    #[test]
    fn the_kiosk_clock_counts_from_its_start() {
        let fake = Fake(Cell::new(5_000_000));
        let mut since = Since::new(&fake);
        assert_eq!(since.next_frame(), 0.0);
        fake.0.set(6_500_000);
        assert_eq!(since.next_frame(), 1.5);
        assert_eq!(since.seconds(5_250_000), 0.25);
    }
}
