//! The feet that carry the body: a foot of the target posture that comes
//! down near the floor and nearly still is planted where it is shown and
//! stays there while tracking moves the body; when the posture wants it
//! elsewhere (farther than a short step, out of the leg's reach, or
//! lifted) it steps there, lifted in an arc, instead of sliding; a foot
//! comes down where it was shown last and keeps pointing where it did
//! while it stands. A body pulled farther than a
//! planted foot's leg reaches is held back over it. Feet held by a finger
//! are the finger's. No sole goes below the floor. A foot that sweeps the
//! floor is lifted clear of it ([`sweep`]), and the stance the fingers
//! leave is put down on both feet ([`stance`]).
//!
//! [`Feet`] owns all of it: the controller hands it, each step, what it
//! needs ([`FeetStep`]) and the posture to correct.

mod stance;
mod sweep;
#[cfg(test)]
mod tests;

use glam::{DQuat, DVec3};

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, WorldPose, forward_kinematics, sole};
use crate::control::posing::ik::{ccd, chain, plant_feet};
use crate::control::tracking::accel::{AccelTracker, Gains};

/// A part this close to the floor touches it (m).
pub(super) const GROUND_CONTACT_M: f64 = 0.03;

/// A planted foot steps when the posture wants it this far away (m, on
/// the floor).
pub(crate) const STEP_TRIGGER_M: f64 = 0.12;

/// The most a planted foot is held turned against the body (radians).
const MAX_TWIST: f64 = 1.2;

/// A planted foot turned farther than this against the body (radians)
/// when a walk ends steps into line.
const SETTLE_TWIST: f64 = 0.15;

/// How long a lifted foot takes to let go of its held turn (s): about a
/// swing.
const TWIST_RELEASE_S: f64 = 0.3;

/// How high a step of at least [`STEP_TRIGGER_M`] lifts the foot (m).
const STEP_HEIGHT_M: f64 = 0.06;

/// The fastest a target foot may move and still come down (m/s).
const LANDING_SPEED_M_S: f64 = 0.3;

/// Where a foot stands, or the step it is taking.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct FootHold {
    /// Where the foot stands while it carries the body.
    anchor: Option<DVec3>,
    /// A step under way: where it left from, how far along it is (0..1),
    /// how long it takes (s) and the least it lifts the foot (a share of
    /// a full step's height).
    step: Option<(DVec3, f64, f64, f64)>,
    /// The way the planted foot points (yaw, radians): it stays so as the
    /// body turns over it...
    held_yaw: Option<f64>,
    /// ...held since a walk (which ends with the foot stepping into line
    /// when the body turned far over it).
    walked: bool,
    /// The turn about the vertical added to the foot (radians): what
    /// holds it to `held_yaw`...
    twist: f64,
    /// ...let go once the foot lifts: the turn it had then, and how far
    /// the letting go is (0..1).
    release: Option<(f64, f64)>,
    /// Where a foot not carrying the body is shown and how fast it moves:
    /// it follows the target posture's foot over the floor as the pelvis
    /// follows the target's (turning the tracked leg's joints alone swung
    /// a raised foot 0.3 m to and fro while the target's stood still).
    track: Option<(DVec3, DVec3)>,
}

/// The most a free foot's shown position accelerates (m/s²).
const MAX_FOOT_ACCEL: f64 = 60.0;

/// How long a step of `dist` metres takes (s): a quick lift for a foot
/// the posture raises where it stands, about a walking step's time for a
/// stride.
fn step_duration(dist: f64) -> f64 {
    (0.12 + dist * 0.8).min(0.3)
}

/// The feet of one character: each foot's hold or step, how fast the
/// target's feet moved, how far each is lifted for sweeping the floor, and
/// the body's measures they go by.
#[derive(Clone, Debug)]
pub(super) struct Feet {
    /// Left and right.
    holds: [FootHold; 2],
    /// The target's foot positions last step, for their speed.
    last_target: [DVec3; 2],
    /// How far each foot is lifted for sweeping the floor (0..1).
    swept: [f64; 2],
    /// How high each foot that swings, steps or sweeps the floor stands
    /// off it before the bound on joint accelerations (m), kept after it.
    clear: [Option<f64>; 2],
    /// Ankle height standing at rest (m): a foot lower than this plus a
    /// little is on the floor.
    ankle_rest: f64,
    /// Hip to ankle along the bones (m): a planted foot farther than
    /// this from its hip steps.
    leg_length: f64,
}

/// What the feet are told each step.
pub(super) struct FeetStep<'a> {
    pub(super) skeleton: &'a Skeleton,
    pub(super) roles: &'a RoleMap,
    /// The posture asked for.
    pub(super) target: &'a Pose,
    /// The posture shown last step.
    pub(super) shown_last: &'a WorldPose,
    /// The parts fingers hold.
    pub(super) held: &'a [Role],
    /// The target switched controllers this step (its feet jumped).
    pub(super) switched: bool,
    /// Tracking's settling time (s; 0: tracking off).
    pub(super) settle_s: f64,
    /// While walking, which foot the clip has on the floor.
    pub(super) contacts: Option<[bool; 2]>,
    pub(super) dt: f64,
}

impl FootHold {
    /// Where the foot is tracked to this step, following the target's
    /// foot `p` (from `shown`, where the tracked posture has it, when it
    /// was not tracked yet) by bounded accelerations settling in about
    /// `settle_s` (0: tracking off, the target's foot).
    fn follow(&mut self, p: DVec3, shown: DVec3, settle_s: f64, dt: f64) -> DVec3 {
        let tracked = match self.track {
            _ if settle_s <= 0.0 => (p, DVec3::ZERO),
            Some((at, v)) => {
                let gains = Gains::critical(settle_s);
                let acc = ((p - at) * gains.k - v * gains.d).clamp_length_max(MAX_FOOT_ACCEL);
                let v = v + acc * dt;
                (at + v * dt, v)
            }
            None => (shown, DVec3::ZERO),
        };
        self.track = Some(tracked);
        tracked.0
    }

    /// The turn added to the foot, its posture's turn being `yaw`: what
    /// holds it to the way it points while held (without wrapping round;
    /// at most [`MAX_TWIST`], beyond which it turns with the body), else
    /// let go smoothly over [`TWIST_RELEASE_S`], easing in and out.
    fn retwist(&mut self, yaw: f64, dt: f64) {
        self.twist = match self.held_yaw {
            Some(y) => {
                let wrap = crate::character::body::wrap;
                let t = self.twist + wrap(wrap(y - yaw) - self.twist);
                let held = t.clamp(-MAX_TWIST, MAX_TWIST);
                if held != t {
                    self.held_yaw = Some(yaw + held);
                }
                held
            }
            None if self.twist != 0.0 => {
                let (from, u) = self.release.unwrap_or((self.twist, 0.0));
                let u = (u + dt / TWIST_RELEASE_S).min(1.0);
                self.release = (u < 1.0).then_some((from, u));
                from * (1.0 - u * u * (3.0 - 2.0 * u))
            }
            None => 0.0,
        };
        if self.held_yaw.is_some() {
            self.release = None;
        }
    }

    /// Where a step under way has the foot now, heading for `tracked`
    /// (`None`: no step, or it has just landed).
    fn stepping(&mut self, tracked: DVec3, dt: f64) -> Option<DVec3> {
        let (from, s, dur, lift) = self.step?;
        let s = s + dt / dur;
        if s >= 1.0 {
            // Landed: where the tracked posture has the foot.
            self.step = None;
            return None;
        }
        self.step = Some((from, s, dur, lift));
        let e = s * s * (3.0 - 2.0 * s);
        let dist = (tracked - from).with_y(0.0).length();
        let arc = STEP_HEIGHT_M
            * (std::f64::consts::PI * s).sin()
            * (dist / STEP_TRIGGER_M).clamp(lift, 1.0);
        Some(from + (tracked - from) * e + DVec3::Y * arc)
    }
}

impl Feet {
    /// The feet of a body standing in `world` (its rest posture), with
    /// legs `leg_length` long from hip to ankle.
    pub(super) fn new(roles: &RoleMap, world: &WorldPose, leg_length: f64) -> Self {
        let now = [
            world.positions[roles.get(Role::LeftFoot)],
            world.positions[roles.get(Role::RightFoot)],
        ];
        Self {
            holds: [FootHold::default(); 2],
            last_target: now,
            swept: [0.0; 2],
            clear: [None; 2],
            ankle_rest: now[0].y.min(now[1].y),
            leg_length,
        }
    }

    /// Ankle height standing at rest (m).
    pub(super) fn ankle_rest(&self) -> f64 {
        self.ankle_rest
    }

    /// Whether foot `k` (0 left, 1 right) is planted, carrying the body.
    pub(super) fn planted(&self, k: usize) -> bool {
        self.holds[k].anchor.is_some()
    }

    /// Whether foot `k` stands where it was planted and no sweep lifts
    /// it: where it stands is to be kept.
    pub(super) fn standing(&self, k: usize) -> bool {
        self.planted(k) && self.swept[k] <= 0.0
    }

    /// Correct the tracked posture `output` (and the tracker's, where a
    /// planted foot holds the body back): plant, hold and step the feet
    /// (see the module), keep every sole above the floor, then lift the
    /// feet that sweep it.
    pub(super) fn step(&mut self, s: &FeetStep, output: &mut Pose, tracker: &mut AccelTracker) {
        self.plant(s, output, tracker);
        self.clear_swept(s, output);
    }

    /// Plant, hold and step the feet of the tracked posture, then keep
    /// every sole above the floor.
    fn plant(&mut self, s: &FeetStep, output: &mut Pose, tracker: &mut AccelTracker) {
        let (sk, roles, dt) = (s.skeleton, s.roles, s.dt);
        let target = forward_kinematics(sk, s.target);
        let shown = forward_kinematics(sk, output);
        let goals = [0, 1].map(|k| self.goal(k, s, &target, &shown));
        self.tether(roles, &shown, output, tracker);
        if goals.iter().any(Option::is_some) {
            plant_feet(sk, roles, output, goals);
        }
        self.hold_turn(sk, roles, output, s.contacts.is_some(), dt);
        onto_floor(sk, roles, self.ankle_rest, s.held, output, goals);
    }

    /// Where foot `k` (0 left, 1 right) goes this step, given the target
    /// posture's and the tracked posture's world poses: on its anchor
    /// while planted, along its step while stepping, else where it is
    /// tracked; `None` while a finger holds it.
    fn goal(
        &mut self,
        k: usize,
        s: &FeetStep,
        target: &WorldPose,
        shown: &WorldPose,
    ) -> Option<DVec3> {
        let (roles, dt) = (s.roles, s.dt);
        let role = [Role::LeftFoot, Role::RightFoot][k];
        let foot_j = roles.get(role);
        let p = target.positions[foot_j];
        // Across a switch of controller the target's feet jump: that is
        // not the foot moving.
        let speed = if dt > 0.0 && !s.switched {
            (p - self.last_target[k]).length() / dt
        } else {
            0.0
        };
        self.last_target[k] = p;
        let other_planted = self.holds[1 - k].anchor.is_some();
        let foot = &mut self.holds[k];
        if s.held.contains(&role) {
            *foot = FootHold::default();
            return None;
        }
        let tracked = foot.follow(p, shown.positions[foot_j], s.settle_s, dt);
        if let Some(g) = foot.stepping(tracked, dt) {
            return Some(g);
        }
        // While walking, the clip's own foot contacts say which foot
        // stands.
        let on_floor = s
            .contacts
            .map_or(p.y <= self.ankle_rest + GROUND_CONTACT_M, |c| c[k]);
        let goal = match foot.anchor {
            Some(a) => {
                let away = (p - a).with_y(0.0).length();
                let hip = shown.positions[roles.get([Role::LeftHip, Role::RightHip][k])];
                let out_of_reach = (hip - a).length() > self.leg_length * 1.02;
                // A foot the posture lifts goes at once; one it moves along
                // the floor waits for the other to stand.
                let lifts = !on_floor;
                let strays = (out_of_reach || (s.contacts.is_none() && away > STEP_TRIGGER_M))
                    && other_planted;
                if lifts || strays {
                    foot.anchor = None;
                    let dist = (tracked - a).with_y(0.0).length();
                    foot.step = Some((a, 0.0, step_duration(dist), 0.0));
                    a
                } else {
                    // Height from the target (a heel may rise over planted
                    // toes), reached smoothly.
                    let settle = 1.0 - (-dt / 0.06).exp();
                    let a = a.with_y(a.y + (p.y - a.y) * settle);
                    foot.anchor = Some(a);
                    a
                }
            }
            None if on_floor && (s.contacts.is_some() || speed < LANDING_SPEED_M_S) => {
                // Comes down where it was shown last (the bound on joint
                // accelerations may have held it off its track): no jump.
                let a = s.shown_last.positions[foot_j].with_y(tracked.y);
                foot.anchor = Some(a);
                a
            }
            None => tracked,
        };
        if let Some(a) = foot.anchor {
            // Carrying the body: shown where it stands.
            foot.track = Some((a, DVec3::ZERO));
        }
        Some(goal)
    }

    /// A planted foot holds the body within its leg's reach (one that
    /// could step has stepped by now; this one stands alone, or stands
    /// until the other comes down): what the body went beyond it, pulled
    /// by a finger or by tracking, is taken back, from the tracked posture
    /// too with its speed that way, so the body waits over the foot
    /// instead of dragging it along the floor.
    fn tether(
        &self,
        roles: &RoleMap,
        shown: &WorldPose,
        output: &mut Pose,
        tracker: &mut AccelTracker,
    ) {
        let reach = self.leg_length;
        let mut shift = DVec3::ZERO;
        for (k, hip) in [Role::LeftHip, Role::RightHip].into_iter().enumerate() {
            let Some(a) = self.holds[k].anchor else {
                continue;
            };
            let d = shown.positions[roles.get(hip)] + shift - a;
            let (flat, up) = (d.with_y(0.0), d.y);
            let h = flat.length();
            let within = (reach * reach - up * up).max(0.0).sqrt();
            if h > within {
                shift -= flat * ((h - within) / h);
            }
        }
        if shift == DVec3::ZERO {
            return;
        }
        output.translations[0] += shift;
        tracker.pose.translations[0] += shift;
        let back = shift.normalize();
        let away = -tracker.root_velocity.dot(back);
        if away > 0.0 {
            tracker.root_velocity += back * away;
        }
    }

    /// A planted foot keeps pointing where it stood when it was planted
    /// (or when the walk began) as the body turns over it (its toes would
    /// sweep the floor round its ankle); a lifted foot takes the
    /// posture's turn again, smoothly, in the air. Once a walk is over, a
    /// foot it left turned far against the body steps into line.
    fn hold_turn(
        &mut self,
        sk: &Skeleton,
        roles: &RoleMap,
        output: &mut Pose,
        walking: bool,
        dt: f64,
    ) {
        if !walking
            && self
                .holds
                .iter()
                .all(|f| f.twist == 0.0 && f.held_yaw.is_none() && f.anchor.is_none())
        {
            // Posing with nothing planted, held or let go: nothing to turn.
            return;
        }
        let w = forward_kinematics(sk, output);
        for (k, role) in [Role::LeftFoot, Role::RightFoot].into_iter().enumerate() {
            let j = roles.get(role);
            let other = self.holds[1 - k];
            let foot = &mut self.holds[k];
            let yaw = foot_yaw(sk, &w, j);
            let turned = !walking
                && foot.walked
                && foot.anchor.is_some()
                && foot.held_yaw.is_some()
                && foot.twist.abs() > SETTLE_TWIST;
            if turned && other.anchor.is_some() && other.step.is_none() {
                // The walk is over with this foot turned against the body:
                // it steps into line, lifted (its turn let go in the air),
                // rather than turning on the floor.
                if let Some(a) = foot.anchor.take() {
                    foot.step = Some((a, 0.0, TWIST_RELEASE_S, 1.0));
                }
                foot.held_yaw = None;
            } else if turned && other.step.is_some() {
                // ...once the other foot, stepping, stands again.
            } else if foot.anchor.is_none() {
                foot.held_yaw = None;
            } else if foot.held_yaw.is_none() {
                // Posing too: a planted foot's toes would sweep the floor
                // round its ankle as the leg above it turns.
                foot.held_yaw = Some(yaw);
            }
            foot.walked = foot.held_yaw.is_some() && (foot.walked || walking);
            foot.retwist(yaw, dt);
            if foot.twist.abs() < 1e-4 {
                foot.twist = 0.0;
                continue;
            }
            let parent = sk.joints[j]
                .parent
                .map_or(DQuat::IDENTITY, |p| w.rotations[p]);
            let turned = DQuat::from_rotation_y(foot.twist) * w.rotations[j];
            output.rotations[j] = (parent.inverse() * turned).normalize();
        }
    }
}

/// The floor: a sole below it (tracking straightens a leg before the
/// pelvis rises, toes tip down) is lifted onto it: the leg bends to
/// raise the foot by as much as its lowest point went under (the foot
/// keeps its turn: turning it instead snaps the ankle round each time a
/// fast foot meets the floor), then any toes still under turn up at
/// the ankle, as toes flatten on the ground. A hand no finger holds
/// (`held`) goes no deeper than the floor either.
fn onto_floor(
    sk: &Skeleton,
    roles: &RoleMap,
    ankle_rest: f64,
    held: &[Role],
    output: &mut Pose,
    mut goals: [Option<DVec3>; 2],
) {
    let feet = [Role::LeftFoot, Role::RightFoot];
    let mut lifted = false;
    let ankle_min = ankle_rest * 0.5;
    let w = forward_kinematics(sk, output);
    for (k, role) in feet.into_iter().enumerate() {
        let j = roles.get(role);
        let ankle = w.positions[j];
        // As deep as the lowest point of the foot went, or the ankle
        // under half its standing height.
        let below = (-sole(sk, &w, j).y).max(ankle_min - ankle.y);
        goals[k] = if below > 0.0 {
            lifted = true;
            Some(ankle + DVec3::Y * below)
        } else {
            goals[k].map(|_| ankle)
        };
    }
    if lifted {
        plant_feet(sk, roles, output, goals);
        // A leg that cannot bend the foot up far enough (pulled
        // straight, or its knee the bound holds back): the body rises.
        rise_over_floor(sk, roles, output, &feet);
    }
    let w = forward_kinematics(sk, output);
    for role in feet {
        let j = roles.get(role);
        let turn = toes_onto_floor(sk, &w, j);
        if turn != DQuat::IDENTITY {
            let parent = sk.joints[j]
                .parent
                .map_or(DQuat::IDENTITY, |p| w.rotations[p]);
            output.rotations[j] = (parent.inverse() * turn * w.rotations[j]).normalize();
        }
    }
    // A hand no finger holds goes no deeper than the floor: the arm
    // lifts it by as much as its lowest point went under.
    let w = forward_kinematics(sk, output);
    let hands: Vec<(usize, Vec<usize>, DVec3)> = [Role::LeftHand, Role::RightHand]
        .into_iter()
        .filter(|r| !held.contains(r))
        .filter_map(|r| {
            let j = roles.get(r);
            let under = -sole(sk, &w, j).y;
            (under > 0.0).then(|| (j, chain(sk, roles, r), w.positions[j] + DVec3::Y * under))
        })
        .collect();
    if !hands.is_empty() {
        ccd(sk, output, &hands, 12);
    }
}

/// Raise the whole body of `pose` by as much as the lowest point of any
/// of `parts` (and what hangs from it) is under the floor, its joints
/// untouched.
pub(super) fn rise_over_floor(sk: &Skeleton, roles: &RoleMap, pose: &mut Pose, parts: &[Role]) {
    let w = forward_kinematics(sk, pose);
    let under = parts
        .iter()
        .map(|r| -sole(sk, &w, roles.get(*r)).y)
        .fold(0.0, f64::max);
    if under > 0.0 {
        pose.translations[0].y += under;
    }
}

/// Which way foot `j` points over the floor (yaw, radians from +Z): its
/// first child's (or End Site's) direction from the ankle.
fn foot_yaw(sk: &Skeleton, w: &WorldPose, j: usize) -> f64 {
    let toe = (0..sk.len())
        .find(|&i| sk.joints[i].parent == Some(j))
        .map_or_else(|| w.end_site(sk, j), |i| Some(w.positions[i]));
    let d = toe.map_or(DVec3::Z, |p| p - w.positions[j]);
    if d.x.hypot(d.z) < 1e-9 {
        // Pointing straight down: the foot's own forward axis.
        let f = w.rotations[j] * DVec3::Z;
        return f.x.atan2(f.z);
    }
    d.x.atan2(d.z)
}

/// The turn at ankle `j` (world frame) that brings the foot's points in
/// front of the ankle (toes, their End Sites) up onto the floor: about the
/// foot's own across axis (level, square to where the toes point), by the
/// most any point needs. Each point's need and their largest change
/// smoothly with the posture, whichever point is lowest, so the foot never
/// flips from one frame to the next.
fn toes_onto_floor(sk: &Skeleton, w: &WorldPose, j: usize) -> DQuat {
    let ankle = w.positions[j];
    let mut points = Vec::new();
    for i in 0..sk.len() {
        if i == j || sk.is_ancestor(j, i) {
            points.extend(std::iter::once(w.positions[i]).chain(w.end_site(sk, i)));
        }
    }
    let Some(tip) = points
        .iter()
        .copied()
        .max_by(|a, b| (*a - ankle).length().total_cmp(&(*b - ankle).length()))
    else {
        return DQuat::IDENTITY;
    };
    let ahead = (tip - ankle).with_y(0.0);
    if ahead.length() < 1e-6 {
        return DQuat::IDENTITY;
    }
    let ahead = ahead.normalize();
    let mut turn = 0.0f64;
    for p in points {
        let r = p - ankle;
        let (u, v) = (r.dot(ahead), r.y);
        if ankle.y + v >= 0.0 || u <= 0.0 {
            continue;
        }
        let want = (-ankle.y / u.hypot(v)).clamp(-1.0, 1.0).asin();
        turn = turn.max(want - v.atan2(u));
    }
    if turn <= 0.0 {
        return DQuat::IDENTITY;
    }
    DQuat::from_axis_angle(ahead.cross(DVec3::Y).normalize(), turn.min(1.2))
}
