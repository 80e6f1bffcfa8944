//! The fingers part: the body part each finger holds (the table decided
//! which, [`crate::control::stage`]), the drag it has drawn since it last
//! rested (kept for recognition, and matched against the templates as it
//! grows), and the posing constraints the held parts make.

use std::collections::BTreeMap;

use glam::DVec3;

use super::MAX_TRAIL_S;
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::control::action::recogniser::DragMatch;
use crate::control::action::trail::TrailPoint;
use crate::control::marks::{FingerMark, FingerUse};
use crate::control::posing::constraint::{Constraint, Target};
use crate::input::touch::{ContactId, Phase, ScreenFrame, Tool};
use crate::screen::ScreenPoint;

/// A finger holding a body part.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Grab {
    pub role: Role,
    pub at: ScreenPoint,
    /// The drag since the finger last rested, for recognition.
    pub trail: Vec<TrailPoint>,
    pub trail_start: f64,
    pub moved_at: f64,
    pub moved: bool,
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

/// The fingers holding the body's parts.
#[derive(Clone, Default)]
pub(super) struct Fingers {
    grabs: BTreeMap<ContactId, Grab>,
    /// Each held part's drag matched against the templates so far.
    pub matching: BTreeMap<ContactId, Matching>,
}

impl Fingers {
    /// One frame of this body's touches (its time is `frame.t`): a
    /// finger going down takes the part the table `picked` for it; a held
    /// part's drag grows (and starts anew after a rest of `rest_s`); a
    /// lifted finger lets go. Returns whether a finger took a part while
    /// none was held (posing begins anew). Only fingers count: a pen's or
    /// a touchpad's contacts (in a replayed recording) are passed over.
    pub fn touch(
        &mut self,
        frame: &ScreenFrame,
        rest_s: f64,
        picked: &BTreeMap<ContactId, Role>,
    ) -> bool {
        let mut first_part = false;
        let t = frame.t;
        for c in frame.contacts.iter().filter(|c| c.tool == Tool::Finger) {
            let p = c.screen;
            if c.phase == Phase::Down {
                if let Some(&role) = picked.get(&c.id) {
                    first_part |= self.grabs.is_empty();
                    tracing::debug!(contact = c.id, role = role.name(), "finger holds a part");
                    self.grabs.insert(
                        c.id,
                        Grab {
                            role,
                            at: p,
                            trail: vec![TrailPoint { at: p, t: 0.0 }],
                            trail_start: t,
                            moved_at: t,
                            moved: false,
                        },
                    );
                }
            } else if c.phase.is_down() {
                if let Some(g) = self.grabs.get_mut(&c.id) {
                    g.follow(p, t, rest_s);
                }
            } else {
                self.grabs.remove(&c.id);
            }
        }
        first_part
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

    /// Whether no finger holds a part.
    pub fn none_down(&self) -> bool {
        self.grabs.is_empty()
    }

    /// Body parts held.
    pub fn held(&self) -> Vec<Role> {
        self.grabs.values().map(|g| g.role).collect()
    }

    /// Trail points kept for recognition, over all fingers.
    pub fn trail_points(&self) -> usize {
        self.grabs.values().map(|g| g.trail.len()).sum()
    }

    /// Whether a held part that `which` allows moved since the last
    /// [`Self::settle`].
    pub fn moved(&self, which: impl Fn(Role) -> bool) -> bool {
        self.grabs.values().any(|g| g.moved && which(g.role))
    }

    /// The step has seen the fingers' moves.
    pub fn settle(&mut self) {
        for g in self.grabs.values_mut() {
            g.moved = false;
        }
    }

    /// Every held part's drag starts anew at `t` (an action began or
    /// ended).
    pub fn restart_drags(&mut self, t: f64) {
        for g in self.grabs.values_mut() {
            g.trail.clear();
            g.trail.push(TrailPoint { at: g.at, t: 0.0 });
            g.trail_start = t;
        }
    }

    /// The drags' matches against the templates are dropped (an action
    /// or a walk began).
    pub fn forget_matches(&mut self) {
        self.matching.clear();
    }

    /// The finger holding `role`, if one does.
    pub fn holding(&self, role: Role) -> Option<Holding> {
        self.grabs
            .iter()
            .find(|(_, g)| g.role == role)
            .map(|(id, g)| Holding {
                id: *id,
                at: g.at,
                from: g.trail.first().map_or(g.at, |p| p.at),
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
            .map(|g| {
                let ray = camera.ray(g.at);
                let target = if matches!(g.role, Role::LeftFoot | Role::RightFoot) {
                    // A held foot goes where the finger points, but never
                    // into the floor.
                    let q = ray.closest(now(g.role));
                    Target::Point(q.with_y(q.y.max(ankle_rest)))
                } else {
                    Target::Ray(ray)
                };
                Constraint {
                    role: g.role,
                    target,
                }
            })
            .collect()
    }

    /// The mark of finger `id`, if it holds a part.
    pub fn mark(&self, id: ContactId) -> Option<FingerMark> {
        self.grabs.get(&id).map(|g| FingerMark {
            at: g.at,
            usage: FingerUse::Part(g.role),
            tint: None,
        })
    }
}

impl Grab {
    /// The finger is at `p` at `t`: the drag grows by it (anew after a
    /// rest longer than `rest_s`), keeping only its last seconds.
    fn follow(&mut self, p: ScreenPoint, t: f64, rest_s: f64) {
        if p.distance(self.at) > 0.5 {
            if t - self.moved_at > rest_s {
                // A pause: a new drag starts here.
                self.trail.clear();
                self.trail.push(TrailPoint {
                    at: self.at,
                    t: 0.0,
                });
                self.trail_start = self.moved_at;
            }
            self.moved_at = t;
            self.moved = true;
            self.trail.push(TrailPoint {
                at: p,
                t: t - self.trail_start,
            });
            // Only the last seconds can start an action.
            let keep_from = t - self.trail_start - MAX_TRAIL_S;
            let old = self.trail.partition_point(|q| q.t < keep_from);
            if old > 0 {
                self.trail.drain(..old);
                let shift = self.trail[0].t;
                for q in &mut self.trail {
                    q.t -= shift;
                }
                self.trail_start += shift;
            }
        }
        self.at = p;
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

    /// The table picked the left hand for finger 1 and the right hand
    /// for finger 3; finger 2 is on empty space (the table's camera).
    fn picked() -> BTreeMap<ContactId, Role> {
        BTreeMap::from([(1, Role::LeftHand), (3, Role::RightHand)])
    }

    #[test]
    fn a_finger_holds_what_the_table_picked_until_it_lifts() {
        let mut f = Fingers::default();
        let first = f.touch(
            &frame(
                0.1,
                vec![
                    (1, Phase::Down, 100.0, 100.0),
                    (2, Phase::Down, 900.0, 100.0),
                ],
            ),
            0.8,
            &picked(),
        );
        assert!(first);
        assert_eq!(f.held(), vec![Role::LeftHand]);
        assert!(f.mark(2).is_none(), "a finger on empty space holds nothing");
        let moved = f.touch(
            &frame(0.2, vec![(1, Phase::Move, 120.0, 110.0)]),
            0.8,
            &picked(),
        );
        assert!(!moved);
        assert_eq!(f.mark(1).unwrap().at, ScreenPoint::new(120.0, 110.0));
        // A second part taken while one is held: posing goes on.
        let first = f.touch(
            &frame(0.3, vec![(3, Phase::Down, 200.0, 100.0)]),
            0.8,
            &picked(),
        );
        assert!(!first);
        assert_eq!(f.held(), vec![Role::LeftHand, Role::RightHand]);
        f.touch(
            &frame(
                0.4,
                vec![
                    (1, Phase::Up, 120.0, 110.0),
                    (3, Phase::Cancel, 200.0, 100.0),
                ],
            ),
            0.8,
            &picked(),
        );
        assert!(f.held().is_empty());
        assert!(f.none_down());
    }

    #[test]
    fn a_drag_grows_starts_anew_after_a_rest_and_keeps_only_its_last_seconds() {
        let mut f = Fingers::default();
        let pick = &picked();
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
    fn a_held_foot_stays_on_the_floor_and_a_finger_on_nothing_makes_no_constraint() {
        let camera = Camera {
            eye: DVec3::new(0.0, 1.0, 4.0),
            target: DVec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 40.0,
            width: 1000.0,
            height: 600.0,
        };
        let mut f = Fingers::default();
        let foot = BTreeMap::from([(1, Role::LeftFoot)]);
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
            &foot,
        );
        let c = f.constraints(&camera, |_| DVec3::new(0.0, 0.08, 0.0), 0.08);
        assert_eq!(c.len(), 1);
        match c[0].target {
            Target::Point(q) => assert!(q.y >= 0.08 - 1e-12, "{q}"),
            _ => panic!("a foot is held at a point"),
        }
    }
}
