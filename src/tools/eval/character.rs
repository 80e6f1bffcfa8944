//! A skinned figure playing a library's clips: how far its mapped parts
//! are from where the library puts them (shares of each one's height),
//! how deep its mesh goes into the floor, how its planted feet slide
//! against the library's own, and frames whose skinned mesh goes
//! non-finite.

use glam::{DMat4, DVec3};
use serde::Serialize;

use crate::character::gltf::{Drive, Figure, Hold};
use crate::character::library::Library;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{WorldPose, forward_kinematics};

/// The parts judged (those a figure's fit is asked for), each measured
/// from the root of its limb: hands and elbows from the shoulder, feet and
/// knees from the hip, the head from the chest, the chest from the pelvis,
/// the pelvis from the floor under it.
const PARTS: [(Role, Option<Role>); 11] = [
    (Role::Pelvis, None),
    (Role::Chest, Some(Role::Pelvis)),
    (Role::Head, Some(Role::Chest)),
    (Role::LeftHand, Some(Role::LeftShoulder)),
    (Role::RightHand, Some(Role::RightShoulder)),
    (Role::LeftFoot, Some(Role::LeftHip)),
    (Role::RightFoot, Some(Role::RightHip)),
    (Role::LeftElbow, Some(Role::LeftShoulder)),
    (Role::RightElbow, Some(Role::RightShoulder)),
    (Role::LeftKnee, Some(Role::LeftHip)),
    (Role::RightKnee, Some(Role::RightHip)),
];

/// The chain whose length scales a part's offset from its root.
fn span(part: Role) -> [Role; 3] {
    match part {
        Role::Pelvis | Role::LeftFoot | Role::LeftKnee => {
            [Role::LeftHip, Role::LeftKnee, Role::LeftFoot]
        }
        Role::RightFoot | Role::RightKnee => [Role::RightHip, Role::RightKnee, Role::RightFoot],
        Role::Chest => [Role::Pelvis, Role::Pelvis, Role::Chest],
        Role::Head => [Role::Chest, Role::Chest, Role::Head],
        Role::LeftHand | Role::LeftElbow => [Role::LeftShoulder, Role::LeftElbow, Role::LeftHand],
        _ => [Role::RightShoulder, Role::RightElbow, Role::RightHand],
    }
}

/// A foot this close above its standing height is planted (m; the
/// library's, and the figure's scaled as it follows the library's
/// motion, so that both count the same part of a step as planted).
const PLANTED_M: f64 = 0.02;

#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct CharacterEval {
    pub clips: usize,
    pub frames: usize,
    /// Mapped parts' distance from where the library puts them: each
    /// part's offset from its limb's root, the library's scaled to the
    /// figure's limb, in shares of the figure's height (%).
    pub mean_pct: f64,
    pub max_pct: f64,
    pub worst: String,
    /// Deepest skinned vertex under the floor (mm), and the joint that
    /// carries it most.
    pub penetration_mm: f64,
    pub penetration_at: String,
    /// Mean slide of a planted foot per frame (mm): the figure's, and the
    /// library's own skeleton's measured the same way.
    pub skate_mm: f64,
    pub library_skate_mm: f64,
    /// Frames whose skinned mesh has a non-finite vertex.
    pub bad_frames: usize,
    /// The angle between each of the figure's body segments and the
    /// library's (pelvis to chest, chest to head, upper arms, forearms,
    /// thighs, shins; shoulder to hand and hip to foot for a one-bone
    /// limb), over every frame judged: mean and 95th percentile (deg).
    pub dir_mean_deg: f64,
    pub dir_p95_deg: f64,
    /// The segment furthest from the library's on the mean.
    pub dir_worst: String,
    /// Over frames where the library plants a foot, the 95th percentile
    /// of that foot's lowest mesh point above the floor (mm): a figure
    /// that floats or stands on tiptoe shows here.
    pub float_mm: f64,
    /// Each limb segment within 25 % of the library's, both scaled by
    /// height; the ratios (figure over library).
    pub human_proportions: bool,
    pub proportions: std::collections::BTreeMap<String, f64>,
}

/// A segment judged by direction: from one role's joint to another's.
const SEGMENTS: [(Role, Role); 10] = [
    (Role::Pelvis, Role::Chest),
    (Role::Chest, Role::Head),
    (Role::LeftShoulder, Role::LeftElbow),
    (Role::LeftElbow, Role::LeftHand),
    (Role::RightShoulder, Role::RightElbow),
    (Role::RightElbow, Role::RightHand),
    (Role::LeftHip, Role::LeftKnee),
    (Role::LeftKnee, Role::LeftFoot),
    (Role::RightHip, Role::RightKnee),
    (Role::RightKnee, Role::RightFoot),
];

/// The segments a figure is judged by: a limb whose middle is made up
/// (one bone) from its root to its end.
fn segments(fig: &Figure) -> Vec<(Role, Role)> {
    let made_up = |r: Role| fig.made_up.get(fig.roles.get(r)).copied().unwrap_or(false);
    let mut out = Vec::new();
    for (a, b) in SEGMENTS {
        if made_up(b)
            && !matches!(
                b,
                Role::LeftHand | Role::RightHand | Role::LeftFoot | Role::RightFoot
            )
        {
            // Upper of a one-bone limb: root to end, once.
            let end = match b {
                Role::LeftElbow => Role::LeftHand,
                Role::RightElbow => Role::RightHand,
                Role::LeftKnee => Role::LeftFoot,
                _ => Role::RightFoot,
            };
            out.push((a, end));
        } else if made_up(a) {
            continue;
        } else {
            out.push((a, b));
        }
    }
    out
}

/// The figure's limb segments over the library's, each over its body's
/// height, and whether every one is within 25 %.
fn proportions(
    fig: &Figure,
    lib: &Library,
    lib_roles: &RoleMap,
) -> (bool, std::collections::BTreeMap<String, f64>) {
    let lib_rest = forward_kinematics(&lib.skeleton, &lib.skeleton.rest_pose());
    let lib_h = 1.0;
    let fig_at = |r: Role| fig.rest[fig.roles.get(r)].w_axis.truncate();
    let lib_at = |r: Role| lib_rest.positions[lib_roles.get(r)];
    let mut ratios = Vec::new();
    for (a, b) in segments(fig).into_iter().skip(2) {
        let f = (fig_at(b) - fig_at(a)).length() / fig.height_m.max(1e-6);
        let l = (lib_at(b) - lib_at(a)).length() / lib_h;
        ratios.push((format!("{}-{}", a.name(), b.name()), f / l.max(1e-9)));
    }
    // Each over their geometric mean: the figure made as large as the
    // library's character overall (a mesh's height counts a helmet or
    // hair that the library's stature does not).
    let mean = (ratios.iter().map(|(_, r)| r.max(1e-9).ln()).sum::<f64>()
        / ratios.len().max(1) as f64)
        .exp();
    let out: std::collections::BTreeMap<String, f64> = ratios
        .into_iter()
        .map(|(k, r)| (k, (r / mean * 1e3).round() / 1e3))
        .collect();
    let human = out.values().all(|r| (0.75..=1.25).contains(r));
    (human, out)
}

/// Plays every clip of `lib` on `fig`, every `step`-th frame.
#[must_use]
pub fn eval_character(fig: &Figure, lib: &Library, step: usize) -> CharacterEval {
    let Some(lib_roles) = lib.clips.values().next().map(|c| c.roles.clone()) else {
        return CharacterEval::default();
    };
    let against = Against {
        fig,
        drive: Drive::new(fig, lib, &lib_roles),
        lengths: limb_lengths(fig, lib, &lib_roles),
        segs: segments(fig),
        ankles: (
            fig.rest[fig.roles.get(Role::LeftFoot)].w_axis.y,
            standing_ankle(lib, &lib_roles),
        ),
        lib_roles,
    };
    let mut t = Tally {
        by_seg: vec![(0.0, 0); against.segs.len()],
        ..Tally::default()
    };
    (t.out.human_proportions, t.out.proportions) = proportions(fig, lib, &against.lib_roles);
    for (name, clip) in &lib.clips {
        t.out.clips += 1;
        let mut last = None;
        // Each clip a sequence of postures: a figure's foot stays where
        // it came down.
        let mut hold = Hold::default();
        for pose in clip.frames.iter().step_by(step.max(1)) {
            t.out.frames += 1;
            let lw = forward_kinematics(&lib.skeleton, pose);
            let w = against.drive.pose_held(fig, &lw, &mut hold);
            let skinned = against.drive.skin(fig, &w);
            if skinned.iter().flatten().any(|v| !v.is_finite()) {
                t.out.bad_frames += 1;
                last = None;
                hold = Hold::default();
                continue;
            }
            t.penetration(fig, &skinned, name);
            t.directions(&against, &w, &lw);
            t.floats(&against, &w, &lw);
            t.parts(&against, &w, &lw, name);
            last = Some(t.skates(&against, &w, &lw, last));
        }
    }
    t.finish(&against.segs)
}

/// Each part's limb length at rest: the figure's and the library's.
fn limb_lengths(fig: &Figure, lib: &Library, lib_roles: &RoleMap) -> [(f64, f64); Role::ALL.len()] {
    let lib_rest = forward_kinematics(&lib.skeleton, &lib.skeleton.rest_pose());
    let fig_rest: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
    let mut lengths = [(1.0, 1.0); Role::ALL.len()];
    for (r, _) in PARTS {
        let [a, b, c] = span(r);
        let len = |p: &[DVec3], at: &dyn Fn(Role) -> usize| {
            (p[at(b)] - p[at(a)]).length() + (p[at(c)] - p[at(b)]).length()
        };
        lengths[r.index()] = (
            len(&fig_rest, &|q| fig.roles.get(q)).max(1e-6),
            len(&lib_rest.positions, &|q| lib_roles.get(q)).max(1e-6),
        );
    }
    lengths
}

/// The library's ankles standing: the lower one's median over its clips
/// (as the figure follows it).
fn standing_ankle(lib: &Library, lib_roles: &RoleMap) -> f64 {
    let mut lows: Vec<f64> = lib
        .clips
        .values()
        .flat_map(|c| c.frames.iter().step_by(5))
        .map(|p| {
            let w = forward_kinematics(&lib.skeleton, p);
            w.positions[lib_roles.get(Role::LeftFoot)]
                .y
                .min(w.positions[lib_roles.get(Role::RightFoot)].y)
        })
        .collect();
    lows.sort_by(f64::total_cmp);
    lows.get(lows.len() / 2).copied().unwrap_or(0.0)
}

/// What a figure is judged against: how it follows the library, each
/// part's limb lengths (figure's, library's), its segments, and the ankles
/// standing (figure's at rest, library's).
struct Against<'a> {
    fig: &'a Figure,
    drive: Drive,
    lib_roles: RoleMap,
    lengths: [(f64, f64); Role::ALL.len()],
    segs: Vec<(Role, Role)>,
    ankles: (f64, f64),
}

/// Where the feet are, the figure's and the library's.
type FeetAt = ([DVec3; 2], [DVec3; 2]);

const FEET: [Role; 2] = [Role::LeftFoot, Role::RightFoot];

/// The frames' measurements before the means are taken.
#[derive(Default)]
struct Tally {
    out: CharacterEval,
    angles: Vec<f64>,
    by_seg: Vec<(f64, usize)>,
    floats: Vec<f64>,
    miss: (f64, usize),
    skate: (f64, usize),
    lib_skate: (f64, usize),
}

impl Tally {
    /// The skinned mesh's deepest point under the floor, and the joint
    /// that carries it most.
    fn penetration(&mut self, fig: &Figure, skinned: &[Vec<DVec3>], clip: &str) {
        let (lowest, at) = skinned
            .iter()
            .enumerate()
            .flat_map(|(k, p)| p.iter().enumerate().map(move |(i, v)| (v.y, (k, i))))
            .fold(
                (f64::INFINITY, (0, 0)),
                |a, b| if b.0 < a.0 { b } else { a },
            );
        if -lowest * 1e3 > self.out.penetration_mm {
            self.out.penetration_mm = -lowest * 1e3;
            let part = &fig.parts[at.0];
            let (j, w) = (part.joints[at.1], part.weights[at.1]);
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            self.out.penetration_at =
                format!("{} in {clip}", fig.skeleton.joints[usize::from(j[k])].name);
        }
    }

    /// Each segment's direction against the library's.
    fn directions(&mut self, a: &Against<'_>, w: &[DMat4], lw: &WorldPose) {
        for (si, &(s, e)) in a.segs.iter().enumerate() {
            let f =
                w[a.fig.roles.get(e)].w_axis.truncate() - w[a.fig.roles.get(s)].w_axis.truncate();
            let l = lw.positions[a.lib_roles.get(e)] - lw.positions[a.lib_roles.get(s)];
            if f.length() > 1e-9 && l.length() > 1e-9 {
                let deg = f.angle_between(l).to_degrees();
                self.angles.push(deg);
                self.by_seg[si].0 += deg;
                self.by_seg[si].1 += 1;
            }
        }
    }

    /// How high the figure's sole is over the floor where the library's
    /// foot is planted.
    fn floats(&mut self, a: &Against<'_>, w: &[DMat4], lw: &WorldPose) {
        for (k, r) in FEET.iter().enumerate() {
            if lw.positions[a.lib_roles.get(*r)].y < a.ankles.1 + PLANTED_M {
                if let Some(low) = a.drive.foot_lowest(w, k) {
                    self.floats.push(low.max(0.0) * 1e3);
                }
            }
        }
    }

    /// Each part's offset from its limb's root against the library's,
    /// scaled to the figure's limb.
    fn parts(&mut self, a: &Against<'_>, w: &[DMat4], lw: &WorldPose, clip: &str) {
        let floor_at = |p: DVec3| DVec3::new(p.x, 0.0, p.z);
        for (r, root) in PARTS {
            let f = w[a.fig.roles.get(r)].w_axis.truncate();
            let l = lw.positions[a.lib_roles.get(r)];
            let (f0, l0) = match root {
                Some(q) => (
                    w[a.fig.roles.get(q)].w_axis.truncate(),
                    lw.positions[a.lib_roles.get(q)],
                ),
                None => (floor_at(f), floor_at(l)),
            };
            let (fl, ll) = a.lengths[r.index()];
            let miss = (f - f0) - (l - l0) * (fl / ll);
            let pct = miss.length() / a.fig.height_m * 100.0;
            self.miss.0 += pct;
            self.miss.1 += 1;
            if pct > self.out.max_pct {
                self.out.max_pct = pct;
                self.out.worst = format!("{} in {clip}", r.name());
            }
        }
    }

    /// The planted feet's slides since `last`, the figure's and the
    /// library's; where the feet are now.
    fn skates(
        &mut self,
        a: &Against<'_>,
        w: &[DMat4],
        lw: &WorldPose,
        last: Option<FeetAt>,
    ) -> FeetAt {
        let (fig_ankle, lib_ankle) = a.ankles;
        let now = (
            FEET.map(|r| w[a.fig.roles.get(r)].w_axis.truncate()),
            FEET.map(|r| lw.positions[a.lib_roles.get(r)]),
        );
        if let Some((pf, pl)) = last {
            for k in 0..2 {
                if pf[k].y < fig_ankle + PLANTED_M * a.drive.scale
                    && now.0[k].y < fig_ankle + PLANTED_M * a.drive.scale
                {
                    self.skate.0 += (now.0[k] - pf[k]).with_y(0.0).length() * 1e3;
                    self.skate.1 += 1;
                }
                if pl[k].y < lib_ankle + PLANTED_M && now.1[k].y < lib_ankle + PLANTED_M {
                    self.lib_skate.0 += (now.1[k] - pl[k]).with_y(0.0).length() * 1e3;
                    self.lib_skate.1 += 1;
                }
            }
        }
        now
    }

    /// The means, the 95th percentiles and the worst segment.
    fn finish(mut self, segs: &[(Role, Role)]) -> CharacterEval {
        let mut out = self.out;
        let r3 = |v: f64| (v * 1e3).round() / 1e3;
        out.mean_pct = r3(self.miss.0 / self.miss.1.max(1) as f64);
        out.max_pct = r3(out.max_pct);
        out.penetration_mm = r3(out.penetration_mm.max(0.0));
        out.skate_mm = r3(self.skate.0 / self.skate.1.max(1) as f64);
        out.library_skate_mm = r3(self.lib_skate.0 / self.lib_skate.1.max(1) as f64);
        let p95 = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.get((v.len() * 95 / 100).min(v.len().saturating_sub(1)))
                .copied()
                .unwrap_or(0.0)
        };
        out.dir_mean_deg = r3(self.angles.iter().sum::<f64>() / self.angles.len().max(1) as f64);
        out.dir_p95_deg = r3(p95(&mut self.angles));
        out.float_mm = r3(p95(&mut self.floats));
        if let Some((k, (sum, n))) =
            self.by_seg.iter().enumerate().max_by(|a, b| {
                (a.1.0 / a.1.1.max(1) as f64).total_cmp(&(b.1.0 / b.1.1.max(1) as f64))
            })
        {
            let (a, b) = segs[k];
            out.dir_worst = format!(
                "{}-{}: {:.1} deg",
                a.name(),
                b.name(),
                sum / (*n).max(1) as f64
            );
        }
        out
    }
}
