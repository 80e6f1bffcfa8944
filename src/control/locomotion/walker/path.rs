//! The finger's path a walk follows: the points kept as the finger leads
//! (bounded, however long the walk), the character's place on it, how far
//! is left, and the point it is steered at.

use glam::DVec3;

use super::{
    KEPT_BEHIND, LOOK_AHEAD_M, MAX_PATH_POINTS, PATH_STEP_M, STEER_SLACK_M, Walker, smoothed_speed,
};

impl Walker {
    /// The finger is at floor point `p` at time `t`.
    pub fn lead(&mut self, p: DVec3, t: f64) {
        let p = p.with_y(0.0);
        if let Some((q, tq)) = self.last_finger {
            let dt = t - tq;
            if dt > 1e-6 {
                self.finger_speed = smoothed_speed(self.finger_speed, (p - q).length(), dt);
                if (p - q).length() < 0.005 {
                    self.still_s += dt;
                } else {
                    self.still_s = 0.0;
                    // The finger goes on: the path's end is its again.
                    self.ended_short = None;
                }
            }
        }
        self.last_finger = Some((p, t));
        // The last point follows the finger until it is 3 cm past the
        // point before it; there it stays, and a new last point follows.
        // (A finger slower than 3 cm a frame dragged one straight segment
        // from where the walk began: a path that turned back was cut
        // short where the character stood.)
        let n = self.path.len();
        if n >= 2 && (self.path[n - 1] - self.path[n - 2]).length() <= PATH_STEP_M {
            self.path[n - 1] = p;
        } else {
            self.path.push(p);
        }
        if self.path.len() > MAX_PATH_POINTS {
            // A finger that keeps going far ahead of the walk: every other
            // point ahead is let go (the path's shape, coarser).
            let keep = self.seg + 2;
            let mut k = 0;
            self.path.retain(|_| {
                k += 1;
                k <= keep || k % 2 == 0 || k == MAX_PATH_POINTS + 1
            });
        }
    }

    /// Another finger took the lead (the first lifted, a new one holds
    /// the pelvis): the path starts again from where the character is,
    /// towards `p`.
    pub fn lead_anew(&mut self, p: DVec3, t: f64) {
        self.path = vec![self.root, p.with_y(0.0)];
        self.ended_short = None;
        self.seg = 0;
        self.dropped_m = 0.0;
        self.leading = true;
        self.last_finger = Some((p.with_y(0.0), t));
        self.still_s = 0.0;
    }

    /// The path still ahead: from the character to its end.
    #[must_use]
    pub fn ahead(&self) -> Vec<DVec3> {
        std::iter::once(self.root)
            .chain(
                self.path[(self.seg + 1).min(self.path.len() - 1)..]
                    .iter()
                    .copied(),
            )
            .collect()
    }

    /// The point `d` metres along the path from the character's nearest
    /// point (the path's end past it).
    pub(super) fn along(&self, d: f64) -> DVec3 {
        let (near, _) = self.nearest();
        let mut here = near;
        let mut left = d;
        for q in &self.path[self.seg + 1..] {
            let l = (*q - here).length();
            if l >= left {
                return here + (*q - here) * (left / l.max(1e-9));
            }
            left -= l;
            here = *q;
        }
        here
    }

    /// The nearest point of the current segment to the root.
    pub(super) fn nearest(&self) -> (DVec3, f64) {
        self.nearest_on(self.seg)
    }

    /// The nearest point of segment `seg` to the root, and how far it is.
    pub(super) fn nearest_on(&self, seg: usize) -> (DVec3, f64) {
        let a = self.path[seg];
        let b = self.path[(seg + 1).min(self.path.len() - 1)];
        let ab = b - a;
        let s = if ab.length_squared() > 1e-12 {
            ((self.root - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let q = a + ab * s;
        (q, (self.root - q).length())
    }

    /// How much of the path is behind the character (0..1).
    #[must_use]
    pub fn progress(&self) -> f64 {
        let (near, _) = self.nearest();
        let behind: f64 = self.dropped_m
            + path_length(&self.path[..=self.seg])
            + (near - self.path[self.seg]).length();
        let left = self.remaining();
        if behind + left > 0.0 {
            behind / (behind + left)
        } else {
            1.0
        }
    }

    /// How far the path's end is along the path (m).
    #[must_use]
    pub fn remaining(&self) -> f64 {
        let (near, _) = self.nearest();
        let mut here = near;
        let mut sum = 0.0;
        for q in &self.path[self.seg + 1..] {
            sum += (*q - here).length();
            here = *q;
        }
        sum
    }

    /// Move the character's nearest segment along as it walks; the path
    /// well behind is dropped.
    pub(super) fn follow(&mut self) {
        while self.seg + 2 < self.path.len() {
            let (_, now) = self.nearest();
            let (_, next) = self.nearest_on(self.seg + 1);
            if next > now + 1e-9 {
                break;
            }
            self.seg += 1;
        }
        // A path that turns back on itself: the turn's segments lie
        // beside a character that turned round short of its apex, farther
        // than the way back a little ahead. Stuck on the turn, the path
        // ahead began behind it and the walk stood still (a turn-back
        // dragged at 0.4 m/s stopped 1.1 m short). The nearest segment
        // within `LOOK_AHEAD_M` of the path ahead is taken.
        //
        // A sharp corner (a zig-zag's) is cut by a walk steered at a point
        // well past it: the character comes onto the next leg as far along
        // as it was steered, so the look goes at least that far (a slow
        // zig-zag's walk stood on the far leg, its path ahead beginning
        // behind it, and gave up 2.7 m short).
        let reach = LOOK_AHEAD_M.max(self.steer_ahead() + STEER_SLACK_M);
        let (mut best, (_, mut best_d)) = (self.seg, self.nearest());
        let mut ahead = 0.0;
        for k in self.seg + 1..self.path.len().saturating_sub(1) {
            ahead += (self.path[k] - self.path[k - 1]).length();
            if ahead > reach {
                break;
            }
            let (_, d) = self.nearest_on(k);
            if d < best_d - 1e-9 {
                (best, best_d) = (k, d);
            }
        }
        self.seg = best;
        if self.seg >= KEPT_BEHIND {
            self.dropped_m += path_length(&self.path[..=self.seg]);
            self.path.drain(..self.seg);
            self.seg = 0;
        }
    }

    /// How far along the path ahead the walk is steered at (m): half a
    /// second at its speed and 30 cm.
    pub(super) fn steer_ahead(&self) -> f64 {
        self.speed.mul_add(0.5, 0.3)
    }
}

/// The length of the polyline `pts` (m).
#[must_use]
pub fn path_length(pts: &[DVec3]) -> f64 {
    pts.windows(2).map(|w| (w[1] - w[0]).length()).sum()
}

/// The point `s` metres along the polyline `pts` (its last point past
/// its end).
#[must_use]
pub fn point_along(pts: &[DVec3], s: f64) -> DVec3 {
    let mut left = s;
    for w in pts.windows(2) {
        let l = (w[1] - w[0]).length();
        if l >= left && l > 0.0 {
            return w[0] + (w[1] - w[0]) * (left / l);
        }
        left -= l;
    }
    pts.last().copied().unwrap_or_default()
}
