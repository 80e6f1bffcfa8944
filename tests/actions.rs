//! Action control on the default library: recognising an action from a
//! drag of its primary part.

use glam::{DQuat, DVec3};
use marionette::character::action::model::{ActionModel, recognize};
use marionette::character::action::trail::{StartRule, TrailPoint};
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::character::posing::sample::{Anchor, Placement};
use marionette::character::roles::Role;

fn setup() -> (Library, Vec<ActionModel>) {
    let lib =
        Library::load(&std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/library"))
            .unwrap();
    let actions = lib
        .actions
        .iter()
        .map(|a| ActionModel::build(&lib, a))
        .collect();
    (lib, actions)
}

fn camera_at(angle_deg: f64) -> Camera {
    let dir = DQuat::from_rotation_y(angle_deg.to_radians()) * DVec3::Z;
    let target = DVec3::new(0.0, 1.1, 0.0);
    Camera {
        eye: target + dir * 3.0,
        target,
        fov_y_deg: 45.0,
        width: 1280.0,
        height: 720.0,
    }
}

/// The first `part` of an action's trajectory as a finger drag at `speed`
/// times natural speed.
fn drag(a: &ActionModel, cam: &Camera, at: &Placement, part: f64, speed: f64) -> Vec<TrailPoint> {
    let path = a.projected(cam, at);
    let n = ((path.len() - 1) as f64 * part).round() as usize + 1;
    path[..n]
        .iter()
        .map(|p| TrailPoint {
            at: p.at,
            t: p.t / speed,
        })
        .collect()
}

#[test]
fn actions_have_trajectories_and_directions() {
    let (_, actions) = setup();
    let punch = actions
        .iter()
        .find(|a| a.def.name == "punch_right")
        .unwrap();
    assert!(
        punch.direction.z > 0.7,
        "a punch goes forward: {:?}",
        punch.direction
    );
    let jump = actions.iter().find(|a| a.def.name == "jump").unwrap();
    assert!(
        jump.direction.y > 0.5,
        "a jump goes up: {:?}",
        jump.direction
    );
    assert!(
        actions
            .iter()
            .all(|a| a.duration > 0.5 && a.model.samples.len() > 20)
    );
}

#[test]
fn a_quick_drag_along_a_punch_starts_the_punch() {
    let (_, actions) = setup();
    let at = Placement {
        position: DVec3::ZERO,
        yaw: 0.0,
        anchor: Anchor::ClipStart,
    };
    let rule = StartRule::default();
    let side = camera_at(90.0);
    let punch = actions
        .iter()
        .position(|a| a.def.name == "punch_right")
        .unwrap();
    let trail = drag(&actions[punch], &side, &at, 0.6, 1.0);
    let r = recognize(&actions, Role::RightHand, &trail, &side, &at, &rule).expect("recognised");
    assert_eq!(actions[r.action].def.name, "punch_right");
    assert!(
        r.matched.coverage > 0.5 && r.matched.coverage < 0.75,
        "{r:?}"
    );
    // The same path dragged at a third of the speed is posing, not a punch.
    let slow = drag(&actions[punch], &side, &at, 0.6, 0.33);
    assert!(recognize(&actions, Role::RightHand, &slow, &side, &at, &rule).is_none());
    // Seen from the front the punch comes at the viewer: excluded.
    let front = camera_at(0.0);
    let trail = drag(&actions[punch], &front, &at, 0.6, 1.0);
    let r = recognize(&actions, Role::RightHand, &trail, &front, &at, &rule);
    assert!(
        r.is_none_or(|r| actions[r.action].def.name != "punch_right"),
        "{r:?}"
    );
}

#[test]
fn held_out_variants_are_recognised_and_slow_drags_are_not() {
    use marionette::character::action::eval::eval_actions;
    use marionette::character::author::compile::{FPS, frames};
    use marionette::character::author::rig;
    use marionette::character::author::score::{Kind, Score, Variant};
    use marionette::character::motion::{Clip, ImportSettings};
    let (_, actions) = setup();
    // Variants the library does not have: a little slower, wider, higher,
    // and each mirrored action a little faster.
    let src = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/library-src");
    let mut clips: Vec<(String, Clip)> = Vec::new();
    let skeleton = rig::skeleton();
    let translates: Vec<bool> = (0..skeleton.len()).map(|i| i == 0).collect();
    for entry in std::fs::read_dir(&src).unwrap() {
        let score = Score::load(&entry.unwrap().path()).unwrap();
        let Kind::Action { name, .. } = &score.kind else {
            continue;
        };
        let mut variants = vec![(
            name.clone(),
            Variant {
                file: String::new(),
                speed: 0.9,
                reach: 1.05,
                lift: 0.03,
                mirror: false,
                action: None,
                primary: None,
            },
        )];
        for v in score
            .variants
            .iter()
            .filter(|v| v.mirror && v.action.is_some())
        {
            let other = v.action.clone().unwrap();
            if variants.iter().all(|(n, _)| *n != other) {
                variants.push((
                    other,
                    Variant {
                        speed: 1.1,
                        reach: 0.95,
                        lift: 0.0,
                        ..v.clone()
                    },
                ));
            }
        }
        for (action, v) in variants {
            let text = marionette::character::bvh::write(
                &skeleton,
                &translates,
                &frames(&score, &v),
                1.0 / FPS,
            );
            let file =
                marionette::character::bvh::parse(&text, std::path::Path::new("held-out.bvh"))
                    .unwrap();
            clips.push((
                action,
                Clip::from_bvh(file, &ImportSettings::default()).unwrap(),
            ));
        }
    }
    assert!(clips.len() >= 12);
    let tests: Vec<(String, &Clip)> = clips.iter().map(|(a, c)| (a.clone(), c)).collect();
    let r = eval_actions(&actions, &tests, &Default::default(), 1);
    eprintln!("{r:?}");
    assert_eq!(r.trials, clips.len() * 6);
    assert!(r.correct >= 0.85, "{r:?}");
    assert!(r.wrong_action <= 0.05, "{r:?}");
    assert!(r.false_trigger_slow <= 0.05, "{r:?}");
}
