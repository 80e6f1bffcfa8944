//! The fingers part: what each finger holds (a body part, or the camera
//! on empty space), the drag it has drawn since it last rested (kept for
//! recognition, and matched against the templates as it grows), when the
//! table was last touched, and the posing constraints the held parts
//! make.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;

use super::MAX_TRAIL_S;
use crate::character::camera::Camera;
use crate::character::gltf::Skin;
use crate::character::roles::Role;
use crate::control::action::recogniser::DragMatch;
use crate::control::action::trail::TrailPoint;
use crate::control::marks::{FingerMark, FingerUse};
use crate::control::posing::constraint::{Constraint, Target};
use crate::input::touch::{ContactId, Phase, ScreenFrame, Tool};
use crate::screen::ScreenPoint;

/// What a finger holds.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Grab {
    Part {
        role: Role,
        at: ScreenPoint,
        /// The drag since the finger last rested, for recognition.
        trail: Vec<TrailPoint>,
        trail_start: f64,
        moved_at: f64,
        moved: bool,
    },
    Camera {
        at: ScreenPoint,
    },
}

/// A drag's match against the templates, kept between steps: the trail it
/// was fed (from `start`, `fed` points).
#[derive(Clone, Debug)]
pub(super) struct Matching {
    pub start: f64,
    pub fed: usize,
    pub drag: DragMatch,
}

/// The finger holding a part: its contact, where it is on the screen and
/// where its drag began.
#[derive(Clone, Copy, Debug)]
pub(super) struct Holding {
    pub id: ContactId,
    pub at: ScreenPoint,
    pub from: ScreenPoint,
}

/// What one frame of touches did.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Touched {
    /// A finger took a part while no part was held (posing begins anew).
    pub first_part: bool,
    /// Fingers on empty space: where each was and is (a camera gesture).
    pub camera_moves: Vec<(ScreenPoint, ScreenPoint)>,
}

/// The fingers on the table and what they hold.
#[derive(Clone)]
pub(super) struct Fingers {
    grabs: BTreeMap<ContactId, Grab>,
    /// Each held part's drag matched against the templates so far.
    pub matching: BTreeMap<ContactId, Matching>,
    /// When a frame last had a contact (s).
    last_touch: f64,
    /// A glTF figure shown over the body: a touch on its surface grabs.
    pub surface: Option<Arc<Skin>>,
}

impl Fingers {
    /// No finger down, at time `t`.
    pub fn new(t: f64) -> Self {
        Self {
            grabs: BTreeMap::new(),
            matching: BTreeMap::new(),
            last_touch: t,
            surface: None,
        }
    }

    /// One frame of touches (its time is `frame.t`): a finger going down
    /// takes the part `pick` finds under it (given the figure shown over
    /// the body, if any), else the camera; a held part's drag grows (and
    /// starts anew after a rest of `rest_s`); a lifted finger lets go.
    /// Only fingers count: a pen's or a touchpad's contacts (in a
    /// replayed recording) are passed over.
    pub fn touch(
        &mut self,
        frame: &ScreenFrame,
        rest_s: f64,
        mut pick: impl FnMut(Option<&Skin>, ScreenPoint) -> Option<Role>,
    ) -> Touched {
        let before: BTreeMap<ContactId, ScreenPoint> = self
            .grabs
            .iter()
            .filter_map(|(id, g)| match g {
                Grab::Camera { at } => Some((*id, *at)),
                Grab::Part { .. } => None,
            })
            .collect();
        let mut out = Touched::default();
        let t = frame.t;
        for c in frame.contacts.iter().filter(|c| c.tool == Tool::Finger) {
            let p = c.screen;
            if c.phase == Phase::Down {
                let grab = match pick(self.surface.as_deref(), p) {
                    Some(role) => {
                        out.first_part |= self.held().is_empty();
                        tracing::debug!(contact = c.id, role = role.name(), "finger holds a part");
                        Grab::Part {
                            role,
                            at: p,
                            trail: vec![TrailPoint { at: p, t: 0.0 }],
                            trail_start: t,
                            moved_at: t,
                            moved: false,
                        }
                    }
                    None => Grab::Camera { at: p },
                };
                self.grabs.insert(c.id, grab);
            } else if c.phase.is_down() {
                match self.grabs.get_mut(&c.id) {
                    Some(Grab::Camera { at }) => *at = p,
                    Some(Grab::Part {
                        at,
                        trail,
                        trail_start,
                        moved_at,
                        moved,
                        ..
                    }) => {
                        if p.distance(*at) > 0.5 {
                            if t - *moved_at > rest_s {
                                // A pause: a new drag starts here.
                                trail.clear();
                                trail.push(TrailPoint { at: *at, t: 0.0 });
                                *trail_start = *moved_at;
                            }
                            *moved_at = t;
                            *moved = true;
                            trail.push(TrailPoint {
                                at: p,
                                t: t - *trail_start,
                            });
                            // Only the last seconds can start an action.
                            let keep_from = t - *trail_start - MAX_TRAIL_S;
                            let old = trail.partition_point(|q| q.t < keep_from);
                            if old > 0 {
                                trail.drain(..old);
                                let shift = trail[0].t;
                                for q in trail.iter_mut() {
                                    q.t -= shift;
                                }
                                *trail_start += shift;
                            }
                        }
                        *at = p;
                    }
                    None => {}
                }
            } else {
                self.grabs.remove(&c.id);
            }
        }
        if !frame.contacts.is_empty() {
            self.last_touch = t;
        }
        out.camera_moves = self
            .grabs
            .iter()
            .filter_map(|(id, g)| match g {
                Grab::Camera { at } => before.get(id).map(|b| (*b, *at)),
                Grab::Part { .. } => None,
            })
            .collect();
        out
    }

    /// Every finger down, with what it holds.
    pub fn grabs(&self) -> impl Iterator<Item = (&ContactId, &Grab)> {
        self.grabs.iter()
    }

    /// Every finger down with what it holds, and the held parts' matches
    /// to update.
    pub fn grabs_and_matches(
        &mut self,
    ) -> (
        &BTreeMap<ContactId, Grab>,
        &mut BTreeMap<ContactId, Matching>,
    ) {
        (&self.grabs, &mut self.matching)
    }

    /// Whether no finger is down.
    pub fn none_down(&self) -> bool {
        self.grabs.is_empty()
    }

    /// Body parts held.
    pub fn held(&self) -> Vec<Role> {
        self.grabs
            .values()
            .filter_map(|g| match g {
                Grab::Part { role, .. } => Some(*role),
                Grab::Camera { .. } => None,
            })
            .collect()
    }

    /// Whether a finger on empty space is moving the camera.
    pub fn touching_camera(&self) -> bool {
        self.grabs
            .values()
            .any(|g| matches!(g, Grab::Camera { .. }))
    }

    /// Trail points kept for recognition, over all fingers.
    pub fn trail_points(&self) -> usize {
        self.grabs
            .values()
            .map(|g| match g {
                Grab::Part { trail, .. } => trail.len(),
                Grab::Camera { .. } => 0,
            })
            .sum()
    }

    /// Seconds since the table was last touched, at `now` (0 while a
    /// finger is down).
    pub fn idle_s(&self, now: f64) -> f64 {
        if self.grabs.is_empty() {
            now - self.last_touch
        } else {
            0.0
        }
    }

    /// Whether a held part that `which` allows moved since the last
    /// [`Self::settle`].
    pub fn moved(&self, which: impl Fn(Role) -> bool) -> bool {
        self.grabs
            .values()
            .any(|g| matches!(g, Grab::Part { role, moved: true, .. } if which(*role)))
    }

    /// The step has seen the fingers' moves.
    pub fn settle(&mut self) {
        for g in self.grabs.values_mut() {
            if let Grab::Part { moved, .. } = g {
                *moved = false;
            }
        }
    }

    /// Every held part's drag starts anew at `t` (an action began or
    /// ended).
    pub fn restart_drags(&mut self, t: f64) {
        for g in self.grabs.values_mut() {
            if let Grab::Part {
                at,
                trail,
                trail_start,
                ..
            } = g
            {
                trail.clear();
                trail.push(TrailPoint { at: *at, t: 0.0 });
                *trail_start = t;
            }
        }
    }

    /// The drags' matches against the templates are dropped (an action
    /// or a walk began).
    pub fn forget_matches(&mut self) {
        self.matching.clear();
    }

    /// The finger holding `role`, if one does.
    pub fn holding(&self, role: Role) -> Option<Holding> {
        self.grabs.iter().find_map(|(id, g)| match g {
            Grab::Part {
                role: r, at, trail, ..
            } if *r == role => Some(Holding {
                id: *id,
                at: *at,
                from: trail.first().map_or(*at, |p| p.at),
            }),
            _ => None,
        })
    }

    /// The posing constraints of the held parts, seen through `camera`: a
    /// part on the ray through its finger; a foot at the ray's point
    /// nearest where it is now (`now`), never lower than `ankle_rest`.
    pub fn constraints(
        &self,
        camera: &Camera,
        now: impl Fn(Role) -> DVec3,
        ankle_rest: f64,
    ) -> Vec<Constraint> {
        self.grabs
            .values()
            .filter_map(|g| match g {
                Grab::Part { role, at, .. } => {
                    let ray = camera.ray(*at);
                    let target = if matches!(role, Role::LeftFoot | Role::RightFoot) {
                        // A held foot goes where the finger points, but
                        // never into the floor.
                        let q = ray.closest(now(*role));
                        Target::Point(q.with_y(q.y.max(ankle_rest)))
                    } else {
                        Target::Ray(ray)
                    };
                    Some(Constraint {
                        role: *role,
                        target,
                    })
                }
                Grab::Camera { .. } => None,
            })
            .collect()
    }

    /// A mark for each finger: the part it holds, or the camera.
    pub fn marks(&self) -> Vec<FingerMark> {
        self.grabs
            .values()
            .map(|g| match g {
                Grab::Part { role, at, .. } => FingerMark {
                    at: *at,
                    usage: FingerUse::Part(*role),
                    tint: None,
                },
                Grab::Camera { at } => FingerMark {
                    at: *at,
                    usage: FingerUse::Camera,
                    tint: None,
                },
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::calibration::RawPoint;
    use crate::input::touch::{ScreenContact, ScreenFrame};

    fn frame(t: f64, contacts: Vec<(ContactId, Phase, f64, f64)>) -> ScreenFrame {
        ScreenFrame {
            t,
            contacts: contacts
                .into_iter()
                .map(|(id, phase, x, y)| ScreenContact {
                    id,
                    phase,
                    tool: Tool::Finger,
                    raw: RawPoint::default(),
                    screen: ScreenPoint::new(x, y),
                })
                .collect(),
        }
    }

    /// Left half of the screen: the left hand; right half: nothing.
    fn pick(_: Option<&Skin>, p: ScreenPoint) -> Option<Role> {
        (p.x < 500.0).then_some(Role::LeftHand)
    }

    #[test]
    fn a_finger_holds_what_it_went_down_on_until_it_lifts() {
        let mut f = Fingers::new(0.0);
        let got = f.touch(
            &frame(
                0.1,
                vec![
                    (1, Phase::Down, 100.0, 100.0),
                    (2, Phase::Down, 900.0, 100.0),
                ],
            ),
            0.8,
            pick,
        );
        assert!(got.first_part);
        assert_eq!(f.held(), vec![Role::LeftHand]);
        assert!(f.touching_camera());
        // The camera finger moves: a gesture from where it was.
        let got = f.touch(&frame(0.2, vec![(2, Phase::Move, 950.0, 120.0)]), 0.8, pick);
        assert!(!got.first_part);
        assert_eq!(
            got.camera_moves,
            vec![(
                ScreenPoint::new(900.0, 100.0),
                ScreenPoint::new(950.0, 120.0)
            )]
        );
        // A second part taken while one is held: posing goes on.
        let got = f.touch(&frame(0.3, vec![(3, Phase::Down, 200.0, 100.0)]), 0.8, pick);
        assert!(!got.first_part);
        f.touch(
            &frame(
                0.4,
                vec![(1, Phase::Up, 100.0, 100.0), (3, Phase::Up, 200.0, 100.0)],
            ),
            0.8,
            pick,
        );
        assert!(f.held().is_empty());
        assert_eq!(f.idle_s(1.0), 0.0, "the camera finger is still down");
        f.touch(&frame(0.5, vec![(2, Phase::Up, 950.0, 120.0)]), 0.8, pick);
        assert!(f.none_down());
        assert!((f.idle_s(2.0) - 1.5).abs() < 1e-12);
    }

    #[test]
    fn a_drag_grows_starts_anew_after_a_rest_and_keeps_only_its_last_seconds() {
        let mut f = Fingers::new(0.0);
        f.touch(&frame(0.0, vec![(1, Phase::Down, 100.0, 100.0)]), 0.8, pick);
        for k in 1..=10 {
            let t = 0.1 * f64::from(k);
            f.touch(
                &frame(
                    t,
                    vec![(1, Phase::Move, 100.0 + 10.0 * f64::from(k), 100.0)],
                ),
                0.8,
                pick,
            );
        }
        assert_eq!(f.trail_points(), 11);
        assert!(f.moved(|r| r == Role::LeftHand));
        assert!(!f.moved(|r| r == Role::Head));
        f.settle();
        assert!(!f.moved(|_| true));
        // A rest longer than 0.8 s: the drag starts where the finger
        // rested.
        f.touch(&frame(2.5, vec![(1, Phase::Move, 300.0, 100.0)]), 0.8, pick);
        assert_eq!(f.trail_points(), 2);
        let h = f.holding(Role::LeftHand).unwrap();
        assert_eq!(h.from, ScreenPoint::new(200.0, 100.0));
        assert_eq!(h.at, ScreenPoint::new(300.0, 100.0));
        // A drag that never rests keeps its last MAX_TRAIL_S seconds.
        for k in 1..=200 {
            let t = 2.5 + 0.05 * f64::from(k);
            f.touch(
                &frame(
                    t,
                    vec![(1, Phase::Move, 300.0 + f64::from(k % 2) * 5.0, 100.0)],
                ),
                0.8,
                pick,
            );
        }
        let kept = f.trail_points();
        assert!((80..=82).contains(&kept), "{kept}");
        f.restart_drags(20.0);
        assert_eq!(f.trail_points(), 1);
    }

    #[test]
    fn a_held_foot_stays_on_the_floor_and_the_camera_makes_no_constraint() {
        let camera = Camera {
            eye: DVec3::new(0.0, 1.0, 4.0),
            target: DVec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 40.0,
            width: 1000.0,
            height: 600.0,
        };
        let mut f = Fingers::new(0.0);
        let foot = |_: Option<&Skin>, p: ScreenPoint| (p.x < 500.0).then_some(Role::LeftFoot);
        // A finger low on the screen: its ray meets the floor in front.
        f.touch(
            &frame(
                0.0,
                vec![
                    (1, Phase::Down, 400.0, 590.0),
                    (2, Phase::Down, 900.0, 10.0),
                ],
            ),
            0.8,
            foot,
        );
        let c = f.constraints(&camera, |_| DVec3::new(0.0, 0.08, 0.0), 0.08);
        assert_eq!(c.len(), 1);
        match c[0].target {
            Target::Point(q) => assert!(q.y >= 0.08 - 1e-12, "{q}"),
            _ => panic!("a foot is held at a point"),
        }
    }
}
