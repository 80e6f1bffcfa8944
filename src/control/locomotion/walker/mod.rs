//! Walking along a finger's path: the character plays the library's
//! locomotion frames, choosing every tenth of a second the frame whose
//! next second best follows the path ahead, facing the way it goes (and
//! whose feet continue the ones shown), crossfading to it; its root moves
//! as the frames' roots do, turned towards a point a little ahead on the
//! path. Near the path's end the frames chosen are those that slow down
//! and stand: the walk ends there.

mod path;

use glam::{DQuat, DVec3};

use super::gait::{FACING, FACING_S, FEATURES, FUTURE_S, Gait, cost};
use crate::character::body::{facing_yaw, wrap};
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

pub use self::path::{path_length, point_along};

/// A finger ahead of the walk is caught up with in this long (s): the
/// walk goes at least as fast as that takes.
const CATCH_UP_S: f64 = 1.0;

/// The finger's speed over the floor is smoothed over about this long (s).
const FINGER_SMOOTH_S: f64 = 0.3;

/// A finger's smoothed speed over the floor (m/s), `was` before, once it
/// moved `moved_m` in `dt` seconds.
#[must_use]
pub fn smoothed_speed(was: f64, moved_m: f64, dt: f64) -> f64 {
    let k = 1.0 - (-dt / FINGER_SMOOTH_S).exp();
    was + (moved_m / dt - was) * k
}

/// How often a better frame is looked for (s).
const SEARCH_S: f64 = 0.1;

/// How long a crossfade to another frame takes (s).
const BLEND_S: f64 = 0.25;

/// ... and from the standing posture the walk starts from (s): the
/// first step comes sooner.
const BLEND_FROM_POSE_S: f64 = 0.15;

/// A frame of the same clip this close to the one playing (s) is not a
/// change.
const SAME_S: f64 = 0.3;

/// A better frame must be cheaper by this much to be switched to.
const HYSTERESIS: f64 = 0.01;

/// The fastest the walk turns towards the path (rad/s).
const MAX_TURN: f64 = 2.0;

/// The walk is over when the path's end is this close (m) and the feet
/// have come to rest.
pub(crate) const ARRIVE_M: f64 = 0.25;

/// The root slower than this (m/s) is coming to rest...
const STILL_MPS: f64 = 0.15;
/// ...and, still coming closer to the path's end, has come to rest once
/// it has been that slow this long (s: the last step of a stop).
const SETTLE_S: f64 = 0.2;

/// Path segments kept behind the character before they are dropped.
const KEPT_BEHIND: usize = 32;

/// A walk whose finger has lifted and that has come no closer to the
/// path's end for this long stops where it is (s).
const STALLED_S: f64 = 2.0;
/// A walk starts from a frame with at least this much of its clip after
/// it (s): the frames of a clip's stop stand as still as the character,
/// and a walk started there stood a while longer (0.47 s to the first
/// step, the target's 0.3).
const START_ROOM_S: f64 = 1.5;

/// A walk starts from a frame from which a foot leaves the floor within
/// this long (s): started in the stand a clip begins with, its first step
/// came after the clip's own weight shift (0.37 s after the finger left
/// posing's reach, the target's 0.3; within 0.1 s, a slow loop's walk
/// ended 32 cm from its end).
const START_LIFT_S: f64 = 0.15;

/// How far along the path ahead (m) a nearer segment is looked for (see
/// `Walker::follow`).
const LOOK_AHEAD_M: f64 = 0.6;

/// How much farther than it is steered (m) a walk looks along the path
/// for the segment it is nearest (see `Walker::follow`).
const STEER_SLACK_M: f64 = 0.3;

/// How far apart (m) the points a finger's path keeps are, at least.
const PATH_STEP_M: f64 = 0.03;

/// The most points a path keeps (ahead of the character and behind).
const MAX_PATH_POINTS: usize = 1024;

/// A path's end closer than this (m, about a stride) but beside or
/// behind the character ends the walk where it is.
const STRIDE_M: f64 = 0.6;

/// Feature weights: the root's future places, the feet, the feet's and
/// the root's motion.
const WEIGHTS: [f64; FEATURES] = [
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, // future root
    0.5, 0.5, 0.5, 0.5, 0.5, 0.5, // feet
    1.0, 1.0, 1.0, 1.0, // feet's motion
    0.5, 0.5, // root's motion
    0.5, 0.5, // facing
];

/// What is faded out of.
#[derive(Clone, Debug)]
enum Source {
    /// A place among the gait frames (fractional frame index).
    Frame(f64),
    /// The posture the walk started from (facing removed).
    Pose { rotations: Vec<DQuat>, root_y: f64 },
}

/// A walk under way.
#[derive(Clone, Debug)]
pub struct Walker {
    /// The frame playing (fractional index into [`Gait::frames`]).
    pos: f64,
    /// The frame or posture faded out of, and how far the fade is (0..1).
    from: Option<(Source, f64)>,
    /// The root's floor point and facing.
    root: DVec3,
    yaw: f64,
    /// The path: floor points, from where the walk began (or where the
    /// finger leading it took over), the oldest ones behind dropped.
    path: Vec<DVec3>,
    /// The path segment the character is nearest.
    seg: usize,
    /// How long the path dropped from behind the character is (m): the
    /// path kept is bounded, however long the walk.
    dropped_m: f64,
    /// The least distance left to the path's end since the finger lifted
    /// (m), and how long since the walk last came 5 cm closer (s).
    closest_m: f64,
    stalled_s: f64,
    /// Whether the finger still leads, and how fast it goes over the
    /// floor (m/s, smoothed).
    leading: bool,
    finger_speed: f64,
    last_finger: Option<(DVec3, f64)>,
    /// Seconds the finger has been still.
    still_s: f64,
    /// The speed the walk aims at (m/s).
    speed: f64,
    search_in: f64,
    walked_s: f64,
    /// How far the root has gone over the floor (m).
    travelled_m: f64,
    /// How long the root has gone slower than [`STILL_MPS`] (s), and how
    /// far from the path's end it was a frame before (m).
    slow_s: f64,
    was_remaining: f64,
    /// The path's end, while the walk ends short of it (beside or behind
    /// it, within the arrival distance).
    ended_short: Option<DVec3>,
    done: bool,
}

impl Walker {
    /// Start walking from posture `pose` towards `goal` (a floor point),
    /// the finger there at time `t` going `finger_speed` m/s over the
    /// floor (as it went before the walk began: a walk behind a quick
    /// finger sets off as fast as it goes, rather than from a stroll).
    #[must_use]
    pub fn start(
        gait: &Gait,
        sk: &Skeleton,
        roles: &RoleMap,
        pose: &Pose,
        (goal, t, finger_speed): (DVec3, f64, f64),
    ) -> Self {
        let w = forward_kinematics(sk, pose);
        let root = w.positions[0].with_y(0.0);
        let yaw = facing_yaw(&w, roles);
        let mut rotations = pose.rotations.clone();
        rotations[0] = (DQuat::from_rotation_y(-yaw) * w.rotations[0]).normalize();
        let unyaw = DQuat::from_rotation_y(-yaw);
        // The starting posture's features: its feet, nothing moving.
        let mut current = [0.0; FEATURES];
        current[FACING + 1] = 1.0;
        for (i, r) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
            let p = unyaw * (w.positions[roles.get(r)] - root);
            current[6 + 3 * i..9 + 3 * i].copy_from_slice(&[p.x, p.y, p.z]);
        }
        let mut walker = Self {
            pos: 0.0,
            from: Some((
                Source::Pose {
                    rotations,
                    root_y: w.positions[0].y,
                },
                0.0,
            )),
            root,
            yaw,
            path: vec![root, goal.with_y(0.0)],
            seg: 0,
            leading: true,
            finger_speed,
            last_finger: Some((goal.with_y(0.0), t)),
            still_s: 0.0,
            speed: gait.low_speed().max(0.3),
            search_in: 0.0,
            closest_m: f64::INFINITY,
            stalled_s: 0.0,
            dropped_m: 0.0,
            walked_s: 0.0,
            travelled_m: 0.0,
            slow_s: 0.0,
            was_remaining: f64::INFINITY,
            ended_short: None,
            done: false,
        };
        let query = walker.query(&current);
        walker.pos = gait
            .best_with_room(&query, &WEIGHTS, (START_ROOM_S, START_LIFT_S))
            .map_or(0.0, |(i, _)| i as f64);
        if let Some(f) = gait.frames.get(walker.pos as usize) {
            let c = &gait.clips[f.clip];
            tracing::debug!(
                clip = %c.name,
                at_s = (walker.pos - c.first as f64) * c.frame_time,
                "the walk starts from"
            );
        }
        walker
    }

    /// The finger lifted: walk on to the path's end and stop there.
    pub fn release(&mut self) {
        self.leading = false;
    }

    /// Whether the walk is over (the character stands near the path's
    /// end).
    #[must_use]
    pub fn done(&self) -> bool {
        self.done
    }

    /// Whether each foot (left, right) stands on the floor in the frames
    /// playing: those of the frame that weighs most (both, in the
    /// posture the walk started from).
    #[must_use]
    pub fn contacts(&self, gait: &Gait) -> [bool; 2] {
        let of = |pos: f64| gait.frames[(pos.round() as usize).min(gait.frames.len() - 1)].contacts;
        match &self.from {
            Some((Source::Frame(p), w)) if *w < 0.5 => of(*p),
            Some((Source::Pose { .. }, w)) if *w < 0.5 => [true, true],
            _ => of(self.pos),
        }
    }

    /// The query: the path's next second in the character's frame, with
    /// the feet and motion of `current`.
    fn query(&self, current: &[f64; FEATURES]) -> [f64; FEATURES] {
        let mut q = *current;
        let unyaw = DQuat::from_rotation_y(-self.yaw);
        for (i, s) in FUTURE_S.iter().enumerate() {
            let p = self.along(self.speed * s);
            let l = unyaw * (p - self.root);
            q[2 * i] = l.x;
            q[2 * i + 1] = l.z;
        }
        // The facing asked for: the way the path goes where the walk will
        // be (a library's walks back and sidesteps carry the body as far,
        // turned away from where it goes and slower than its walks ahead;
        // matched on places alone, a path that set off across the
        // character's facing was walked backwards or sideways).
        let d = (self.speed * FACING_S).max(0.1);
        let way = unyaw * (self.along(d + 0.1) - self.along(d - 0.1)).with_y(0.0);
        if way.length() > 0.05 {
            let a = way.x.atan2(way.z);
            q[FACING] = a.sin();
            q[FACING + 1] = a.cos();
        }
        q
    }

    /// Advance `dt` seconds: the posture to show.
    pub fn step(&mut self, gait: &Gait, sk: &Skeleton, dt: f64) -> Pose {
        self.walked_s += dt;
        self.follow();
        let mut remaining = self.remaining();
        if self.leading {
            // As fast as the finger goes, or as it takes to catch up with
            // it in `CATCH_UP_S` (a finger that stopped ahead is walked
            // to, not crept up on).
            let catch_up = remaining / CATCH_UP_S;
            self.speed = self
                .finger_speed
                .max(catch_up)
                .clamp(gait.low_speed() * 0.8, gait.top_speed() * 1.1);
        }
        self.search(gait, dt);
        // Root motion, from the frames playing (blended).
        let (step, turn) = self.motion(gait, dt);
        let steer_to = self.along(self.steer_ahead());
        let to = DQuat::from_rotation_y(-self.yaw) * (steer_to - self.root);
        let finger_done = !self.leading || self.still_s > 0.3;
        // The end itself, from the character (its place on the path can
        // be on the way back of a turn it cut, the end still far).
        let to_end = DQuat::from_rotation_y(-self.yaw)
            * (*self.path.last().unwrap_or(&self.root) - self.root).with_y(0.0);
        let past_end = self
            .ended_short
            .map(|e| (e, (e - self.root).with_y(0.0).length()))
            .filter(|(_, from_end)| *from_end > ARRIVE_M);
        if let Some((end, from_end_m)) = past_end {
            // Ended short of an end beside or behind, the walk carried on
            // past it (a library whose takes never stop slows only as its
            // crossfades allow; ended where the root was each frame, a
            // fast turn-back stood 43 cm from where the finger lifted): the
            // end is walked back to.
            tracing::debug!(
                from_end_m,
                "the walk went on past an end it ended by: it walks back to it"
            );
            self.ended_short = None;
            self.cut_path_here();
            self.path.push(end);
            remaining = self.remaining();
        } else if finger_done
            && remaining < STRIDE_M
            && to_end.length() < ARRIVE_M
            && self.travelled_m >= STRIDE_M
            && wrap(to_end.x.atan2(to_end.z)).abs() > 1.0
        {
            // The end is beside or behind a walk that went past it, within
            // the arrival distance: turning round it would circle it. The
            // walk ends here. (A walk that has not gone a stride turns to a
            // finger that stopped behind it: ended here it stood where it
            // began, and the finger out of posing's reach started it again
            // and again.)
            tracing::debug!(
                remaining_m = remaining,
                from_end_m = to_end.length(),
                bearing_deg = wrap(to_end.x.atan2(to_end.z)).to_degrees(),
                "the path's end is beside or behind, within the arrival distance: the walk ends here"
            );
            if self.ended_short.is_none() {
                self.ended_short = self.path.last().copied();
            }
            self.cut_path_here();
            remaining = 0.0;
        }
        let steer = if remaining > ARRIVE_M && to.length() > 0.05 {
            (3.0 * wrap(to.x.atan2(to.z))).clamp(-MAX_TURN, MAX_TURN) * dt
        } else {
            0.0
        };
        self.root += DQuat::from_rotation_y(self.yaw) * step;
        self.travelled_m += step.length();
        self.yaw = wrap(self.yaw + turn + steer);
        // Time moves on.
        self.pos = advance(gait, self.pos, dt);
        self.blend_on(gait, dt);
        let speed_now = step.length() / dt.max(1e-6);
        if speed_now < STILL_MPS {
            self.slow_s += dt;
        } else {
            self.slow_s = 0.0;
        }
        // A lifted finger's walk still coming closer to the end as it
        // slows is let finish its last step (ended at the first slow
        // frame, walks stood 15 to 20 cm short); one under a finger that
        // stopped stands at once, as does one no longer coming closer.
        let closing = remaining < self.was_remaining - 1e-4;
        self.was_remaining = remaining;
        if finger_done
            && remaining < ARRIVE_M
            && speed_now < STILL_MPS
            && (self.slow_s > SETTLE_S || !closing || self.leading)
            && self.from.is_none()
        {
            tracing::debug!(
                remaining_m = remaining,
                from_end_m = (*self.path.last().unwrap_or(&self.root) - self.root).length(),
                "the walk arrives"
            );
            self.done = true;
        }
        self.give_up(remaining, dt);
        self.pose(gait, sk)
    }

    /// The path ends where the character is: what lay ahead of its
    /// segment is dropped.
    fn cut_path_here(&mut self) {
        self.path.truncate(self.seg + 1);
        self.path.push(self.root);
    }

    /// Every [`SEARCH_S`], or at a clip's end, the frame that best
    /// continues the path (kept unless another clip's is clearly better):
    /// a blend begins from the frame playing.
    fn search(&mut self, gait: &Gait, dt: f64) {
        let frame = |pos: f64| &gait.frames[(pos.round() as usize).min(gait.frames.len() - 1)];
        let clip = &gait.clips[frame(self.pos).clip];
        let at_end = self.pos >= (clip.first + clip.len - 1) as f64 - 0.5;
        self.search_in -= dt;
        if (self.search_in <= 0.0 || at_end) && self.from.is_none() {
            self.search_in = SEARCH_S;
            let current = frame(self.pos).features;
            let query = self.query(&current);
            let now = cost(&current, &query, &WEIGHTS);
            if let Some((best, c)) = gait.best(&query, &WEIGHTS) {
                let same = gait.frames[best].clip == frame(self.pos).clip
                    && (best as f64 - self.pos).abs() * clip.frame_time < SAME_S;
                if at_end || (!same && c < now - HYSTERESIS) {
                    let cl = &gait.clips[gait.frames[best].clip];
                    tracing::trace!(
                        clip = %cl.name,
                        at_s = (best - cl.first) as f64 * cl.frame_time,
                        cost = c,
                        was = now,
                        walked_s = self.walked_s,
                        speed = self.speed,
                        "the walk changes frame"
                    );
                    self.from = Some((Source::Frame(self.pos), 0.0));
                    self.pos = best as f64;
                }
            }
        }
    }

    /// A blend from an earlier frame (or the posture the walk began from)
    /// moves on by `dt`, and ends once complete.
    fn blend_on(&mut self, gait: &Gait, dt: f64) {
        if let Some((src, s)) = self.from.take() {
            let blend = if matches!(src, Source::Pose { .. }) {
                BLEND_FROM_POSE_S
            } else {
                BLEND_S
            };
            let s = s + dt / blend;
            if s < 1.0 {
                let src = match src {
                    Source::Frame(p) => Source::Frame(advance(gait, p, dt)),
                    other => other,
                };
                self.from = Some((src, s));
            }
        }
    }

    /// A walk that cannot reach the end stops in the end: once it has come
    /// no closer (`remaining` m left) for a while after the finger lifted
    /// (frames that cannot carry the body there: a sideways walk asked to
    /// go ahead), or taken far longer than the path needs.
    fn give_up(&mut self, remaining: f64, dt: f64) {
        if self.leading {
            self.closest_m = f64::INFINITY;
            self.stalled_s = 0.0;
        } else if remaining < self.closest_m - 0.05 {
            self.closest_m = remaining;
            self.stalled_s = 0.0;
        } else {
            self.stalled_s += dt;
        }
        let path_len = self.dropped_m + path_length(&self.path);
        if !self.leading && (self.stalled_s > STALLED_S || self.walked_s > 4.0 + path_len / 0.3) {
            tracing::debug!(
                remaining_m = remaining,
                "a walk that did not reach the path's end stops"
            );
            self.done = true;
        }
    }

    /// The root's move over `dt` (in the character's frame) and its turn,
    /// blended between the frames playing.
    fn motion(&self, gait: &Gait, dt: f64) -> (DVec3, f64) {
        let of = |pos: f64| {
            let f = &gait.frames[(pos.floor() as usize).min(gait.frames.len() - 1)];
            let r = dt / gait.clips[f.clip].frame_time;
            (f.step * r, f.turn * r)
        };
        let (s, t) = of(self.pos);
        match &self.from {
            Some((Source::Frame(p), w)) => {
                let (s0, t0) = of(*p);
                let w = smooth(*w);
                (s0.lerp(s, w), t0 + (t - t0) * w)
            }
            Some((Source::Pose { .. }, w)) => (s * smooth(*w), t * smooth(*w)),
            None => (s, t),
        }
    }

    /// The posture now: the frames playing blended, at the root's place.
    fn pose(&self, gait: &Gait, sk: &Skeleton) -> Pose {
        let (mut rotations, mut root_y) = sampled(gait, self.pos);
        if let Some((src, w)) = &self.from {
            let (r0, y0) = match src {
                Source::Frame(p) => sampled(gait, *p),
                Source::Pose { rotations, root_y } => (rotations.clone(), *root_y),
            };
            let w = smooth(*w);
            for (a, b) in rotations.iter_mut().zip(&r0) {
                *a = b.slerp(*a, w).normalize();
            }
            root_y = y0 + (root_y - y0) * w;
        }
        let mut pose = sk.rest_pose();
        rotations[0] = (DQuat::from_rotation_y(self.yaw) * rotations[0]).normalize();
        pose.rotations = rotations;
        pose.translations[0] = self.root + DVec3::Y * root_y;
        pose
    }
}

/// Ease in and out over 0..1.
fn smooth(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// A fractional frame's rotations and root height, between its two
/// frames.
fn sampled(gait: &Gait, pos: f64) -> (Vec<DQuat>, f64) {
    let i = (pos.floor() as usize).min(gait.frames.len() - 1);
    let clip = &gait.clips[gait.frames[i].clip];
    let j = (i + 1).min(clip.first + clip.len - 1);
    let u = (pos - i as f64).clamp(0.0, 1.0);
    let (a, b) = (&gait.frames[i], &gait.frames[j]);
    let rotations = a
        .rotations
        .iter()
        .zip(&b.rotations)
        .map(|(p, q)| p.slerp(*q, u).normalize())
        .collect();
    (rotations, a.root_y + (b.root_y - a.root_y) * u)
}

/// `pos` moved on by `dt` seconds in its clip, stopping at its last frame.
fn advance(gait: &Gait, pos: f64, dt: f64) -> f64 {
    let i = (pos.floor() as usize).min(gait.frames.len() - 1);
    let clip = &gait.clips[gait.frames[i].clip];
    (pos + dt / clip.frame_time).min((clip.first + clip.len - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::library::Library;

    #[test]
    fn a_long_walk_keeps_a_bounded_path_and_a_new_finger_starts_it_again() {
        let lib = Library::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/library"
        )))
        .unwrap();
        let roles = lib.clips["walk_path.bvh"].roles.clone();
        let gait = Gait::build(&lib, &roles);
        let pose = lib.clips["walk_path.bvh"].frames[0].clone();
        let mut w = Walker::start(&gait, &lib.skeleton, &roles, &pose, (DVec3::X, 0.0, 0.0));
        // A finger that goes round and round for ten minutes, far faster
        // than the walk.
        let dt = 1.0 / 30.0;
        for k in 0..18_000 {
            let t = f64::from(k) * dt;
            let p = DVec3::new(3.0 * (t * 2.0).cos(), 0.0, 3.0 * (t * 2.0).sin());
            w.lead(p, t);
            let _ = w.step(&gait, &lib.skeleton, dt);
            assert!(w.path.len() <= MAX_PATH_POINTS, "{} points", w.path.len());
        }
        assert!(w.progress().is_finite());
        // Another finger: the path goes from where the character is.
        w.lead_anew(DVec3::new(0.0, 0.0, -2.0), 600.0);
        assert_eq!(w.path.len(), 2);
        assert_eq!(w.path[0], w.root);
        assert!(w.remaining() > 0.0);
    }
}
