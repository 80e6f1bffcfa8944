//! Fixed-rate stepping of a table through recorded touch frames: each
//! tick feeds the frames up to its time, then advances the table to it.
//! A touch's effect therefore shows in the first frame rendered after it,
//! and a replay steps identically every run.

use super::stage::Stage;
use crate::input::touch::ScreenFrame;

/// Steps a table at `hz` through `frames` (times in seconds).
#[derive(Clone, Debug)]
pub struct Ticker {
    frames: Vec<ScreenFrame>,
    next: usize,
    hz: f64,
    tick: u64,
}

impl Ticker {
    #[must_use]
    pub fn new(frames: Vec<ScreenFrame>, hz: f64) -> Self {
        Self {
            frames,
            next: 0,
            hz,
            tick: 0,
        }
    }

    /// Time of the current tick (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.tick as f64 / self.hz
    }

    /// Time of the last frame (s), or 0.
    #[must_use]
    pub fn end(&self) -> f64 {
        self.frames.last().map_or(0.0, |f| f.t)
    }

    /// Replace the frames by a longer list with the same beginning (a
    /// recording being authored).
    pub fn extend(&mut self, frames: Vec<ScreenFrame>) {
        self.frames = frames;
    }

    /// One tick: feed the frames due, advance the controller; returns the
    /// tick's time.
    pub fn step(&mut self, ctl: &mut Stage) -> f64 {
        self.tick += 1;
        let t = self.time();
        self.feed(ctl, t);
        ctl.advance(t);
        t
    }

    /// Feed the controller the frames due by `t` (not yet fed), without
    /// advancing it or the ticker's own time.
    pub fn feed(&mut self, ctl: &mut Stage, t: f64) {
        while let Some(f) = self.frames.get(self.next) {
            if f.t > t + 1e-9 {
                break;
            }
            ctl.touch(f);
            self.next += 1;
        }
    }
}
