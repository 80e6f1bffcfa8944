//! Judging drags through the controller, as live touches are: each drag
//! becomes touch frames (finger down on the part as the controller shows
//! it, moved along the drag, lifted) fed to a fresh [`Controller`] at the
//! drag's times, and the action it starts is read from its event stream.
//! Everything after the touch pipeline runs as in the kiosk: picking,
//! posing, the trail since the finger last rested, recognition, playing.

use std::sync::Arc;

use crate::control::action::timeline::ActionEvent;
use crate::control::character::Character;
use crate::control::controller::{Controller, Settings};
use crate::control::rig::Orbit;
use crate::control::stage::Stage;
use crate::input::calibration::RawPoint;
use crate::input::touch::{Phase, Tool};
use crate::input::touch::{ScreenContact, ScreenFrame};
use crate::screen::ScreenPoint;
use crate::tools::eval::actions::Drag;

/// Time the character is left to stand before the finger goes down (s).
const SETTLE_S: f64 = 0.3;
/// Controller steps per second between touch frames.
const STEP_HZ: f64 = 60.0;

/// Which action `drag` starts through the controller, and after how many
/// of its points.
#[must_use]
pub fn judge(ch: &Arc<Character>, settings: &Settings, drag: &Drag<'_>) -> Option<(String, usize)> {
    let cam = drag.camera;
    let mut table = Stage::single(
        Controller::new(ch.clone(), *settings, 0.0),
        cam.width,
        cam.height,
    );
    // The same view of the character as the drag's camera has of the
    // clip's: from `angle_deg` around its facing, level, 3 m away.
    let at = table.ctl().placement_now();
    let orbit = Orbit {
        yaw: at.yaw + drag.angle_deg.to_radians(),
        pitch: 0.0,
        distance: cam.eye.distance(cam.target),
    };
    let rig = table.rig_mut();
    rig.orbit = orbit;
    rig.home = orbit;
    rig.fov_y_deg = cam.fov_y_deg;
    let mut t = 0.0;
    while t < SETTLE_S {
        t += 1.0 / STEP_HZ;
        table.advance(t);
    }
    let view = table.rig().camera();
    let start = view.project(table.ctl().world().positions[ch.roles.get(drag.role)])?;
    let first = drag.trail.first()?;
    let t0 = t + 1.0 / STEP_HZ;
    let contact = |phase, at: ScreenPoint| ScreenContact {
        id: 1,
        phase,
        tool: Tool::Finger,
        raw: RawPoint {
            x: at.x as i32,
            y: at.y as i32,
        },
        screen: at,
    };
    let started = |table: &mut Stage| {
        table.take_events().into_iter().find_map(|(_, e)| match e {
            // A walk started by the pelvis finger's reach is no action.
            ActionEvent::Started {
                action, by_reach, ..
            } if !by_reach => Some(action),
            _ => None,
        })
    };
    for (k, p) in drag.trail.iter().enumerate() {
        let at = ScreenPoint::new(
            start.x + (p.at.x - first.at.x),
            start.y + (p.at.y - first.at.y),
        );
        let ft = t0 + (p.t - first.t);
        // Steps between touch frames, as the kiosk's loop runs.
        while t + 1.0 / STEP_HZ < ft {
            t += 1.0 / STEP_HZ;
            table.advance(t);
            if let Some(a) = started(&mut table) {
                return Some((a, k));
            }
        }
        let phase = if k == 0 { Phase::Down } else { Phase::Move };
        table.touch(&ScreenFrame {
            t: ft,
            contacts: vec![contact(phase, at)],
        });
        t = ft;
        table.advance(t);
        if let Some(a) = started(&mut table) {
            return Some((a, k + 1));
        }
    }
    None
}
