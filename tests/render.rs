//! Golden-image tests: fixed scenes rendered for real with lavapipe (the
//! CPU Vulkan driver, so that images do not depend on the machine's GPU)
//! and compared with stored PNGs in tests/golden. A failure writes the
//! actual frame and a difference image to target/golden-failures.
//! `MARIONETTE_UPDATE_GOLDEN=1 cargo test --test render` rewrites them.

mod common;

use std::path::PathBuf;

use glam::{DQuat, DVec3};
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::character::skeleton::forward_kinematics;
use marionette::control::marks::{FingerMark, FingerUse, Marks, ServiceMarks, TrajectoryMark};
use marionette::render::gpu::{AdapterChoice, Gpu};
use marionette::render::headless::{Headless, Image};
use marionette::render::scene::{self, View};
use marionette::screen::{Rotation, ScreenPoint};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn library() -> Library {
    Library::load(&root().join("assets/library")).expect("default library")
}

fn camera(w: f64, h: f64) -> Camera {
    let target = DVec3::new(0.0, 0.95, 0.0);
    let dir = DQuat::from_rotation_y(0.45) * DVec3::new(0.0, 0.22, 1.0).normalize();
    Camera {
        eye: target + dir * 3.6,
        target,
        fov_y_deg: 40.0,
        width: w,
        height: h,
    }
}

fn headless(w: u32, h: u32) -> Headless {
    let gpu = Gpu::new(AdapterChoice::Cpu)
        .expect("a CPU Vulkan adapter (lavapipe): apt-get install mesa-vulkan-drivers");
    Headless::new(gpu, w, h, 4).unwrap()
}

/// Per-pixel comparison: a pixel differs when a channel is off by more than
/// 24 of 255; at most 0.3% of the pixels may differ, and the mean absolute
/// difference must stay under 1.0.
fn compare(name: &str, actual: &Image) {
    let golden = root().join("tests/golden").join(format!("{name}.png"));
    if std::env::var_os("MARIONETTE_UPDATE_GOLDEN").is_some() || !golden.exists() {
        assert!(
            std::env::var_os("MARIONETTE_UPDATE_GOLDEN").is_some(),
            "{} is missing: run MARIONETTE_UPDATE_GOLDEN=1 cargo test --test render",
            golden.display()
        );
        actual.write_png(&golden).unwrap();
        return;
    }
    let expected = Image::read_png(&golden).unwrap();
    assert_eq!(
        (expected.width, expected.height),
        (actual.width, actual.height),
        "{name}: size"
    );
    let mut diff = Image::filled(actual.width, actual.height, [0, 0, 0, 255]);
    let (mut differing, mut total) = (0usize, 0u64);
    for (i, (a, e)) in actual
        .rgba
        .chunks(4)
        .zip(expected.rgba.chunks(4))
        .enumerate()
    {
        let d = (0..3).map(|c| a[c].abs_diff(e[c])).max().unwrap();
        total += u64::from(d);
        if d > 24 {
            differing += 1;
        }
        let v = (u16::from(d) * 4).min(255) as u8;
        diff.rgba[i * 4..i * 4 + 3].copy_from_slice(&[v, v, v]);
    }
    let n = (actual.width * actual.height) as usize;
    let mean = total as f64 / n as f64;
    let frac = differing as f64 / n as f64;
    if frac > 0.003 || mean > 1.0 {
        let out = root().join("target/golden-failures");
        std::fs::create_dir_all(&out).unwrap();
        actual.write_png(&out.join(format!("{name}.png"))).unwrap();
        diff.write_png(&out.join(format!("{name}-difference.png")))
            .unwrap();
        panic!(
            "{name}: {:.2}% of pixels differ, mean difference {mean:.2}; see {}",
            frac * 100.0,
            out.display()
        );
    }
}

#[test]
fn rest_pose() {
    // The character at rest: standing, arms down (the first frame of the
    // stance clip).
    let lib = library();
    let clip = &lib.clips["pose_stance.bvh"];
    let world = forward_kinematics(&clip.skeleton, &clip.frames[0]);
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let list = scene::compose(
        &view,
        &clip.skeleton,
        &clip.roles,
        &world,
        &[],
        &Marks::default(),
    );
    let mut h = headless(640, 360);
    let img = h.render(&list).unwrap();
    compare("rest_pose", &img);
}

/// A posture from the library with two held parts, finger marks, both
/// kinds of trajectories and a status line.
fn held_scene(view: &View) -> marionette::render::mesh::DrawList {
    let lib = library();
    let clip = &lib.clips["pose_reach_front_right.bvh"];
    let pose = &clip.frames[clip.frames.len() / 2];
    let world = forward_kinematics(&clip.skeleton, pose);
    let cam = &view.camera;
    let at = |r: Role| cam.project(world.positions[clip.roles.get(r)]).unwrap();
    let hand = at(Role::RightHand);
    let foot = at(Role::LeftFoot);
    let arc = |from: ScreenPoint, dx: f64, dy: f64| -> Vec<ScreenPoint> {
        (0..24)
            .map(|k| {
                let s = f64::from(k) / 23.0;
                ScreenPoint::new(
                    from.x + dx * s,
                    from.y + dy * s - (s * std::f64::consts::PI).sin() * 40.0,
                )
            })
            .collect()
    };
    let marks = Marks {
        fingers: vec![
            FingerMark {
                at: hand,
                usage: FingerUse::Part(Role::RightHand),
                tint: None,
            },
            FingerMark {
                at: foot,
                usage: FingerUse::Part(Role::LeftFoot),
                tint: None,
            },
            FingerMark {
                at: ScreenPoint::new(cam.width * 0.85, cam.height * 0.8),
                usage: FingerUse::Camera,
                tint: None,
            },
        ],
        trajectories: vec![
            TrajectoryMark {
                points: arc(hand, 160.0, -20.0),
                executable: true,
                tint: None,
            },
            TrajectoryMark {
                points: arc(hand, -20.0, 120.0),
                executable: false,
                tint: None,
            },
        ],
        status: Some("posing | right_hand, left_foot held | 12.3 ms".into()),
        service: None,
    };
    scene::compose(
        view,
        &clip.skeleton,
        &clip.roles,
        &world,
        &[Role::RightHand, Role::LeftFoot],
        &marks,
    )
}

#[test]
fn the_service_view_draws_its_panel_and_the_fingers_trails() {
    let lib = library();
    let clip = &lib.clips["pose_stance.bvh"];
    let world = forward_kinematics(&clip.skeleton, &clip.frames[0]);
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let render = |marks: &Marks| {
        let list = scene::compose(&view, &clip.skeleton, &clip.roles, &world, &[], marks);
        headless(640, 360).render(&list).unwrap()
    };
    let trail: Vec<ScreenPoint> = (0..20)
        .map(|k| ScreenPoint::new(420.0 + 8.0 * f64::from(k), 250.0 - 3.0 * f64::from(k)))
        .collect();
    let on = Marks {
        service: Some(ServiceMarks {
            lines: vec![
                "SERVICE VIEW   Virtual-1 640x360".into(),
                "touchscreen: /dev/input/event5 \"demo panel\"".into(),
                "59.9 fps   frame 2.5 / 7.0 ms   touch to flip 22 / 41 ms".into(),
            ],
            trails: vec![trail],
        }),
        ..Marks::default()
    };
    let cyan = |img: &Image, x0: u32, y0: u32, x1: u32, y1: u32| {
        let mut n = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                let [r, g, b, _] = img.pixel(x, y);
                n += usize::from(g > 200 && b > 200 && g > r.saturating_add(60));
            }
        }
        n
    };
    let (with, without) = (render(&on), render(&Marks::default()));
    // The text panel at the top left, the trail and crosshair at the right.
    assert!(
        cyan(&with, 0, 0, 640, 80) > 500,
        "{}",
        cyan(&with, 0, 0, 640, 80)
    );
    assert!(cyan(&with, 400, 180, 640, 270) > 100);
    assert_eq!(cyan(&without, 0, 0, 640, 360), 0);
}

#[test]
fn two_held_parts_with_overlays() {
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let mut h = headless(640, 360);
    compare("two_held_parts", &h.render(&held_scene(&view)).unwrap());
}

#[test]
fn rotated_output() {
    // A portrait picture on a landscape panel turned 90° clockwise.
    let view = View {
        camera: camera(360.0, 640.0),
        rotation: Rotation::R90,
    };
    let mut h = headless(640, 360);
    let img = h.render(&held_scene(&view)).unwrap();
    compare("rotated_90", &img);
    // The status text (top left of the picture) lands along the right edge
    // of the output, from its top.
    let text = |x0: u32, x1: u32, y0: u32, y1: u32| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| img.pixel(x, y)[..3].iter().all(|&c| c > 200))
            .count()
    };
    assert!(text(612, 636, 0, 200) > 100, "no text along the right edge");
    assert_eq!(text(0, 40, 0, 200), 0, "text on the left edge");
}

#[test]
fn single_sampled_frames_match_golden_and_leave_no_trails() {
    // One sample per pixel (lavapipe's default) reuses the floor between
    // frames and redraws only where the character and overlays are and
    // were: a frame drawn after another must equal the same frame drawn
    // afresh.
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let lib = library();
    let clip = &lib.clips["pose_stance.bvh"];
    let world = forward_kinematics(&clip.skeleton, &clip.frames[0]);
    let before = scene::compose(
        &view,
        &clip.skeleton,
        &clip.roles,
        &world,
        &[],
        &Marks::default(),
    );
    let after = held_scene(&view);
    let mut h = headless(640, 360);
    let mut one = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
    let _ = one.render(&before).unwrap();
    let second = one.render(&after).unwrap();
    let mut fresh = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
    let alone = fresh.render(&after).unwrap();
    assert!(second == alone, "the earlier frame left traces");
    compare("two_held_parts_x1", &alone);
    let _ = h.render(&after).unwrap();
}

#[test]
fn two_characters_apart_redraw_only_where_they_are_and_were() {
    // The floor between two characters and around a finger mark stays as
    // drawn; each frame redraws the tiles its bodies, shadows and marks
    // touch now and touched last frame. A sequence of frames must equal
    // each frame drawn afresh, and the frame must hold both tints.
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let lib = library();
    let clip = &lib.clips["pose_reach_front_right.bvh"];
    let world = forward_kinematics(&clip.skeleton, &clip.frames[clip.frames.len() / 2]);
    let (red, blue) = ([0.62, 0.1, 0.07], [0.09, 0.26, 0.55]);
    let frame = |apart: f64, hand: f64| {
        let mut left = world.clone();
        let mut right = world.clone();
        for p in &mut left.positions {
            *p += DVec3::new(-apart, 0.0, 0.0);
        }
        for p in &mut right.positions {
            *p += DVec3::new(apart, 0.0, -0.2);
        }
        let at = view
            .camera
            .project(left.positions[clip.roles.get(Role::RightHand)])
            .unwrap();
        let marks = Marks {
            fingers: vec![FingerMark {
                at: ScreenPoint::new(at.x + hand, at.y),
                usage: FingerUse::Part(Role::RightHand),
                tint: Some(red),
            }],
            status: Some("two visitors".into()),
            ..Marks::default()
        };
        let held = [Role::RightHand];
        let body = |w, held, tint| scene::Body {
            figure: None,
            figure_joints: None,
            skeleton: &clip.skeleton,
            roles: &clip.roles,
            world: w,
            held,
            tint: Some(tint),
        };
        scene::compose_bodies(
            &view,
            &[body(&left, &held, red), body(&right, &[], blue)],
            &marks,
        )
    };
    let frames = [frame(0.8, 0.0), frame(1.1, 30.0), frame(0.6, -20.0)];
    let mut kept = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
    for (k, f) in frames.iter().enumerate() {
        let drawn = kept.render(f).unwrap();
        let mut fresh = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
        assert!(
            drawn == fresh.render(f).unwrap(),
            "frame {k} kept traces of the one before"
        );
        let tinted = |c: [f32; 3]| {
            drawn.rgba.chunks(4).any(|p| {
                let q = |v: u8| f32::from(v) / 255.0;
                // sRGB of the tint, lit: the hue's order is what counts.
                (c[0] > c[2]) == (q(p[0]) > q(p[2]) + 0.2)
                    && (c[2] > c[0]) == (q(p[2]) > q(p[0]) + 0.2)
            })
        };
        assert!(tinted(red) && tinted(blue), "frame {k}: both tints show");
    }
}

/// The project's own skinned body (the default look), at rest and with a
/// hand and a foot held (those parts glow whole), tinted as a second
/// character is.
#[test]
fn the_own_skinned_body_at_rest_and_held() {
    let lib = library();
    let rest = &lib.clips["pose_stance.bvh"];
    let skin = marionette::render::body::own_body(&lib, &rest.roles);
    let view = View {
        camera: camera(640.0, 360.0),
        rotation: Rotation::R0,
    };
    let mut h = headless(640, 360);
    for (name, clip, held, tint) in [
        ("own_body_rest", "pose_stance.bvh", vec![], None),
        (
            "own_body_held",
            "pose_reach_front_right.bvh",
            vec![Role::RightHand, Role::LeftFoot],
            Some([0.55, 0.12, 0.1]),
        ),
    ] {
        let clip = &lib.clips[clip];
        let world = forward_kinematics(&clip.skeleton, &clip.frames[clip.frames.len() / 2]);
        let list = scene::compose_bodies(
            &view,
            &[scene::Body {
                skeleton: &clip.skeleton,
                roles: &clip.roles,
                world: &world,
                held: &held,
                tint,
                figure: Some(&skin),
                figure_joints: None,
            }],
            &Marks::default(),
        );
        // Skinned on the CPU (lavapipe's default) and in the vertex
        // shader (a GPU's): the same picture.
        assert!(!h.renderer.gpu_skinning(), "lavapipe skins on the CPU");
        let img = h.render(&list).unwrap();
        compare(name, &img);
        h.renderer.set_gpu_skinning(true);
        let on_gpu = h.render(&list).unwrap();
        h.renderer.set_gpu_skinning(false);
        compare(name, &on_gpu);
        let differing = common::pixels_apart(&img.rgba, &on_gpu.rgba, 8);
        assert!(
            differing <= 20,
            "{name}: {differing} pixels differ between skinning on the CPU and on the GPU"
        );
    }
    // One sample per pixel reuses the floor: the figure redrawn where it
    // is and was (the balls around its joints) leaves no trace of the
    // frame before, skinned either way.
    let posed = |clip: &str| {
        let clip = &lib.clips[clip];
        forward_kinematics(&clip.skeleton, &clip.frames[clip.frames.len() / 2])
    };
    let (a, b) = (
        posed("pose_stance.bvh"),
        posed("pose_reach_front_right.bvh"),
    );
    let list = |world: &marionette::character::skeleton::WorldPose| {
        scene::compose_bodies(
            &view,
            &[scene::Body {
                skeleton: &rest.skeleton,
                roles: &rest.roles,
                world,
                held: &[],
                tint: None,
                figure: Some(&skin),
                figure_joints: None,
            }],
            &Marks::default(),
        )
    };
    for on_gpu in [false, true] {
        let mut one = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
        one.renderer.set_gpu_skinning(on_gpu);
        let _ = one.render(&list(&a)).unwrap();
        let second = one.render(&list(&b)).unwrap();
        let mut fresh = Headless::new(Gpu::new(AdapterChoice::Cpu).unwrap(), 640, 360, 1).unwrap();
        fresh.renderer.set_gpu_skinning(on_gpu);
        assert!(
            second == fresh.render(&list(&b)).unwrap(),
            "skinned on the GPU: {on_gpu}: the earlier frame left traces"
        );
    }
}
