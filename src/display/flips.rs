//! Which of two scanout buffers may be drawn into: never the one on
//! screen, and the other only once the flip that took it off screen has
//! completed (until then the display engine still scans it out).

/// The two buffers' state.
#[derive(Debug, Default)]
pub struct Flips {
    /// The buffer on screen, or queued to be.
    front: usize,
    /// A flip to `front` is queued and its event not yet read.
    pending: bool,
    /// Flips completed.
    completed: u64,
}

impl Flips {
    /// The buffer on screen (or queued to be).
    #[must_use]
    pub fn front(&self) -> usize {
        self.front
    }

    /// Whether a flip is queued.
    #[must_use]
    pub fn pending(&self) -> bool {
        self.pending
    }

    /// Flips completed.
    #[must_use]
    pub fn completed(&self) -> u64 {
        self.completed
    }

    /// The buffer free to draw into; none while a flip is queued (the
    /// buffer it replaces is on screen until it completes).
    #[must_use]
    pub fn free(&self) -> Option<usize> {
        (!self.pending).then_some(1 - self.front)
    }

    /// A flip to `buffer` (the free one) was queued.
    pub fn queued(&mut self, buffer: usize) {
        debug_assert_eq!(self.free(), Some(buffer), "a flip to a buffer in use");
        self.front = buffer;
        self.pending = true;
    }

    /// The display said the queued flip completed.
    pub fn flipped(&mut self) {
        if self.pending {
            self.pending = false;
            self.completed += 1;
        }
    }

    /// The queued flip is given up (the mode is set again with the front
    /// buffer, which then is on screen).
    pub fn abandoned(&mut self) {
        self.pending = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_is_free_only_after_the_flip_that_replaced_it() {
        let mut f = Flips::default();
        // Buffer 0 shows the mode set's frame; 1 is free.
        assert_eq!(f.free(), Some(1));
        f.queued(1);
        // 0 is still scanned out until the flip completes; 1 is queued.
        assert_eq!(f.free(), None);
        assert!(f.pending());
        f.flipped();
        assert_eq!((f.free(), f.front(), f.completed()), (Some(0), 1, 1));
        f.queued(0);
        assert_eq!(f.free(), None);
        f.flipped();
        assert_eq!((f.free(), f.completed()), (Some(1), 2));
        // An event with nothing queued (a stale one) frees nothing new.
        f.flipped();
        assert_eq!((f.free(), f.completed()), (Some(1), 2));
    }

    #[test]
    fn a_flip_given_up_leaves_the_front_buffer_on_screen() {
        let mut f = Flips::default();
        f.queued(1);
        f.abandoned();
        // The mode set shows buffer 1; 0 is free, and no flip counted.
        assert_eq!((f.free(), f.front(), f.completed()), (Some(0), 1, 0));
    }
}
