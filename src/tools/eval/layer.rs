//! An action laid over a walk, measured (`marionette eval walk --layer
//! ACTION`): while the pelvis finger walks the character, a second finger
//! goes down on the action's own part and drags its first clip's path as it
//! looks from where the character is, following the body as it moves on
//! the screen (as a visitor's finger stays with the walking figure). The
//! action should start on the upper body, and put its part where the
//! action alone puts it, in the character's frame.

use glam::{DQuat, DVec3};
use serde::Serialize;

use crate::character::body::Placement;
use crate::character::camera::Camera;
use crate::character::roles::Role;
use crate::character::skeleton::{Pose, forward_kinematics};
use crate::control::action::trail::TrailPoint;
use crate::control::character::Character;
use crate::control::controller::{Controller, Mode};
use crate::input::touch::Phase;
use crate::screen::ScreenPoint;

/// The second finger goes down this long after the walk started (s).
const AFTER_WALK_S: f64 = 0.3;

/// ... and rests this long at the trajectory's end before it lifts (s).
const REST_S: f64 = 0.2;

/// One path's layered action.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LayerRow {
    /// The action laid over the walk played (at full weight).
    pub started: bool,
    /// The action's part, from where the action alone puts it, in the
    /// character's frame: in the posture asked for (mean and worst), and
    /// as shown (tracked, with the physical effects; mean).
    pub part_cm: f64,
    pub part_max_cm: f64,
    pub shown_cm: f64,
}

/// All paths' layered action.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LayerReport {
    pub action: String,
    /// Fraction of the paths whose layered action played.
    pub started: f64,
    pub part_cm: f64,
    pub part_max_cm: f64,
    pub shown_cm: f64,
}

/// The second finger, dragging `action`'s trajectory over the walk.
pub struct SecondFinger {
    action: usize,
    walk_from: Option<f64>,
    drag: Option<Drag>,
    lifted: bool,
    sum: f64,
    shown: f64,
    n: usize,
    row: LayerRow,
}

struct Drag {
    from: f64,
    down: ScreenPoint,
    pelvis: ScreenPoint,
    path: Vec<TrailPoint>,
}

impl SecondFinger {
    #[must_use]
    pub fn new(action: usize) -> Self {
        Self {
            action,
            walk_from: None,
            drag: None,
            lifted: false,
            sum: 0.0,
            shown: 0.0,
            n: 0,
            row: LayerRow::default(),
        }
    }

    /// Whether the finger has lifted (or never will go down).
    #[must_use]
    pub fn lifted(&self) -> bool {
        self.lifted
    }

    /// Where the finger is in the frame at time `t`, and how: `None`
    /// before it goes down and after it lifted.
    pub fn contact(
        &mut self,
        ch: &Character,
        ctl: &Controller,
        camera: &Camera,
        t: f64,
    ) -> Option<(Phase, ScreenPoint)> {
        if self.lifted {
            return None;
        }
        let pelvis = camera.project(ctl.world().positions[ch.roles.get(Role::Pelvis)])?;
        let Some(d) = &self.drag else {
            if matches!(ctl.mode(), Mode::Walk(_)) {
                self.walk_from.get_or_insert(t);
            }
            if self.walk_from.is_none_or(|w| t - w < AFTER_WALK_S) {
                return None;
            }
            let a = &ch.actions[self.action];
            let part = ctl.world().positions[ch.roles.get(a.def.primary)];
            let down = camera.project(part)?;
            let Some(template) = a.templates.first() else {
                self.lifted = true;
                return None;
            };
            let path = template.projected(camera, &ctl.placement_now());
            if path.len() < 2 {
                self.lifted = true;
                return None;
            }
            self.drag = Some(Drag {
                from: t,
                down,
                pelvis,
                path,
            });
            return Some((Phase::Down, down));
        };
        let u = t - d.from;
        let (first, last) = (d.path[0], d.path[d.path.len() - 1]);
        let at = d.path.iter().find(|p| p.t >= u).copied().unwrap_or(last);
        let p = ScreenPoint::new(
            d.down.x + at.at.x - first.at.x + pelvis.x - d.pelvis.x,
            d.down.y + at.at.y - first.at.y + pelvis.y - d.pelvis.y,
        );
        if u > last.t + REST_S {
            self.lifted = true;
            return Some((Phase::Up, p));
        }
        Some((Phase::Move, p))
    }

    /// Measure the frame just stepped.
    pub(super) fn measure(&mut self, ch: &Character, ctl: &Controller) {
        let Some(l) = ctl.layered() else {
            return;
        };
        if l.weight < 1.0 || l.action != ch.actions[self.action].def.name {
            return;
        }
        self.row.started = true;
        let j = ch.roles.get(ch.actions[self.action].def.primary);
        let local = |pose: &Pose| -> DVec3 {
            let at = Placement::of(&ch.lib.skeleton, &ch.roles, pose);
            let w = forward_kinematics(&ch.lib.skeleton, pose);
            DQuat::from_rotation_y(at.yaw).inverse() * (w.positions[j] - at.position)
        };
        let alone = local(l.alone);
        let d = (local(ctl.target()) - alone).length() * 100.0;
        self.sum += d;
        self.shown += (local(ctl.pose()) - alone).length() * 100.0;
        self.n += 1;
        self.row.part_max_cm = self.row.part_max_cm.max(d);
    }

    pub(super) fn finish(mut self) -> LayerRow {
        let n = self.n.max(1) as f64;
        self.row.part_cm = self.sum / n;
        self.row.shown_cm = self.shown / n;
        self.row
    }
}

/// The paths' layered figures together.
#[must_use]
pub fn summarise(action: &str, rows: &[&LayerRow]) -> LayerReport {
    let n = rows.len().max(1) as f64;
    let played: Vec<&&LayerRow> = rows.iter().filter(|r| r.started).collect();
    let m = played.len().max(1) as f64;
    let r3 = |v: f64| (v * 1000.0).round() / 1000.0;
    LayerReport {
        action: action.to_owned(),
        started: r3(played.len() as f64 / n),
        part_cm: r3(played.iter().map(|r| r.part_cm).sum::<f64>() / m),
        part_max_cm: r3(played.iter().map(|r| r.part_max_cm).fold(0.0, f64::max)),
        shown_cm: r3(played.iter().map(|r| r.shown_cm).sum::<f64>() / m),
    }
}
