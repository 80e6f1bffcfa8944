//! What the fingers hold: a finger that goes down grabs a body part (or
//! the camera), its drag is kept for recognition, and the parts held
//! become the posing constraints.

use std::collections::BTreeMap;

use super::{Controller, Grab, MAX_TRAIL_S, Mode};
use crate::character::roles::Role;
use crate::character::skeleton::forward_kinematics;
use crate::control::action::trail::TrailPoint;
use crate::control::posing::constraint::{Constraint, Target};
use crate::input::touch::{ContactId, ScreenFrame};
use crate::screen::ScreenPoint;

impl Controller {
    /// Apply one frame of touches (its time is `frame.t`). Only fingers
    /// drive the character: a pen's or a touchpad's contacts (in a replayed
    /// recording; live, such devices are not read) are passed over.
    pub fn touch(&mut self, frame: &ScreenFrame) {
        let before: BTreeMap<ContactId, ScreenPoint> = self
            .grabs
            .iter()
            .filter_map(|(id, g)| match g {
                Grab::Camera { at } => Some((*id, *at)),
                Grab::Part { .. } => None,
            })
            .collect();
        let t = frame.t;
        for c in frame
            .contacts
            .iter()
            .filter(|c| c.tool == crate::input::touch::Tool::Finger)
        {
            let p = c.screen;
            if c.phase == crate::input::touch::Phase::Down {
                let camera = self.rig.camera();
                let role = self.pick_part(&camera, p);
                let grab = match role {
                    Some(role) => {
                        if matches!(self.mode, Mode::Posing) && self.held().is_empty() {
                            self.begin_posing();
                        }
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
                            if t - *moved_at > self.settings.rest_s {
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
        // Camera gestures from the fingers on empty space.
        let moves: Vec<(ScreenPoint, ScreenPoint)> = self
            .grabs
            .iter()
            .filter_map(|(id, g)| match g {
                Grab::Camera { at } => before.get(id).map(|b| (*b, *at)),
                Grab::Part { .. } => None,
            })
            .collect();
        self.rig.gesture(&moves);
    }

    pub(super) fn begin_posing(&mut self) {
        let w = forward_kinematics(&self.ch.lib.skeleton, &self.target);
        let r = &self.ch.roles;
        self.planted = Some([
            w.positions[r.get(Role::LeftFoot)],
            w.positions[r.get(Role::RightFoot)],
        ]);
    }

    pub(super) fn constraints(&self, camera: &crate::character::camera::Camera) -> Vec<Constraint> {
        self.grabs
            .values()
            .filter_map(|g| match g {
                Grab::Part { role, at, .. } => {
                    let ray = camera.ray(*at);
                    let target = if matches!(role, Role::LeftFoot | Role::RightFoot) {
                        // A held foot goes where the finger points, but
                        // never into the floor.
                        let now = self.world.positions[self.ch.roles.get(*role)];
                        let q = ray.closest(now);
                        Target::Point(q.with_y(q.y.max(self.feet.ankle_rest())))
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
}
