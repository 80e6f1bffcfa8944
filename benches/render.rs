//! Frame time, render plus readback, on the adapter the machine offers
//! (lavapipe here): the character scene (body, shadow, floor, overlays)
//! next to a bare scene of 21 lit boxes measured in the same run, at
//! 1280x720 and 1920x1080, with the shipped automatic anti-aliasing (one
//! sample per pixel on a CPU renderer, four on a GPU;
//! `MARIONETTE_BENCH_SAMPLES=4` to force); and two tinted characters with
//! both visitors' marks. After criterion's runs, the bare scene, one
//! character and two are drawn in turn, 12 frames each, 30 rounds, and the
//! medians and ratios printed: on a shared machine whose speed drifts,
//! scenes measured minutes apart compare badly. Where the shared test
//! characters are beside the checkout, CesiumMan skinned (one, and two
//! tinted) joins the interleaved scenes and its composing is timed; so
//! does the project's own skinned body (the default look), always. Two
//! figures are also drawn skinned the other way (in the vertex shader on a
//! CPU adapter, which skins on the CPU by default; on the CPU on a GPU).
//! `cargo bench --bench render`.

#![allow(
    clippy::print_stderr,
    clippy::disallowed_methods,
    reason = "the interleaved medians are timed with the wall clock and printed"
)]

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use marionette::character::camera::Camera;
use marionette::character::library::Library;
use marionette::character::roles::Role;
use marionette::character::skeleton::forward_kinematics;
use marionette::control::marks::{FingerMark, FingerUse, Marks, TrajectoryMark};
use marionette::render::gpu::{AdapterChoice, Gpu};
use marionette::render::headless::Headless;
use marionette::render::scene::{self, View};
use marionette::screen::Rotation;

fn view(w: u32, h: u32) -> View {
    let target = DVec3::new(0.0, 0.95, 0.0);
    let dir = DQuat::from_rotation_y(1.0) * DVec3::new(0.0, 0.22, 1.0).normalize();
    View {
        camera: Camera {
            eye: target + dir * 3.6,
            target,
            fov_y_deg: 40.0,
            width: f64::from(w),
            height: f64::from(h),
        },
        rotation: Rotation::R0,
    }
}

fn bench(c: &mut Criterion) {
    let lib =
        Library::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/library"))
            .unwrap();
    let clip = &lib.clips["pose_reach_front_right.bvh"];
    let world = forward_kinematics(&clip.skeleton, &clip.frames[clip.frames.len() / 2]);
    let samples: u32 = std::env::var("MARIONETTE_BENCH_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let mut g = c.benchmark_group("frame");
    g.sample_size(20);
    for (w, h) in [(1280u32, 720u32), (1920, 1080)] {
        let v = view(w, h);
        let cam = &v.camera;
        let at = |r: Role| cam.project(world.positions[clip.roles.get(r)]).unwrap();
        let marks = Marks {
            fingers: vec![
                FingerMark {
                    at: at(Role::RightHand),
                    usage: FingerUse::Part(Role::RightHand),
                    tint: None,
                },
                FingerMark {
                    at: at(Role::LeftFoot),
                    usage: FingerUse::Part(Role::LeftFoot),
                    tint: None,
                },
            ],
            trajectories: vec![TrajectoryMark {
                points: (0..32)
                    .map(|k| {
                        let s = f64::from(k) / 31.0;
                        let p = at(Role::RightHand);
                        marionette::screen::ScreenPoint::new(
                            p.x + 200.0 * s,
                            p.y - 80.0 * (s * 3.0).sin(),
                        )
                    })
                    .collect(),
                executable: true,
                tint: None,
            }],
            status: Some("posing | holding right_hand, left_foot | 12.3 ms".into()),
            service: None,
        };
        let character = scene::compose(
            &v,
            &clip.skeleton,
            &clip.roles,
            &world,
            &[Role::RightHand, Role::LeftFoot],
            &marks,
        );
        let boxes = scene::boxes(&v, 21);
        let gpu = Gpu::new(AdapterChoice::Auto).expect("a Vulkan adapter");
        let name = gpu.info.name.clone();
        let mut bare = Headless::new(gpu, w, h, 1).unwrap();
        g.bench_function(format!("{name} {w}x{h} bare 21 boxes"), |b| {
            b.iter(|| bare.render(&boxes).unwrap())
        });
        let gpu = Gpu::new(AdapterChoice::Auto).unwrap();
        let mut full = Headless::new(gpu, w, h, samples).unwrap();
        let n = full.renderer.samples();
        g.bench_function(format!("{name} {w}x{h} character x{n}"), |b| {
            b.iter(|| full.render(&character).unwrap())
        });
        // Two characters, tinted, each with its visitor's marks.
        let mut other = world.clone();
        for p in &mut other.positions {
            *p += DVec3::new(0.9, 0.0, -0.3);
        }
        let mut both_marks = marks.clone();
        for f in &mut both_marks.fingers {
            f.tint = Some([0.62, 0.1, 0.07]);
        }
        for t in &mut both_marks.trajectories {
            t.tint = Some([0.62, 0.1, 0.07]);
        }
        let extra: Vec<FingerMark> = [Role::RightHand, Role::LeftFoot]
            .into_iter()
            .map(|r| FingerMark {
                at: cam.project(other.positions[clip.roles.get(r)]).unwrap(),
                usage: FingerUse::Part(r),
                tint: Some([0.09, 0.26, 0.55]),
            })
            .collect();
        both_marks.fingers.extend(extra);
        let held = [Role::RightHand, Role::LeftFoot];
        let two = scene::compose_bodies(
            &v,
            &[
                scene::Body {
                    skeleton: &clip.skeleton,
                    roles: &clip.roles,
                    world: &world,
                    held: &held,
                    tint: Some([0.62, 0.1, 0.07]),
                    figure: None,
                    figure_joints: None,
                },
                scene::Body {
                    skeleton: &clip.skeleton,
                    roles: &clip.roles,
                    world: &other,
                    held: &held,
                    tint: Some([0.09, 0.26, 0.55]),
                    figure: None,
                    figure_joints: None,
                },
            ],
            &both_marks,
        );
        g.bench_function(format!("{name} {w}x{h} two characters x{n}"), |b| {
            b.iter(|| full.render(&two).unwrap())
        });
        let mut two_bare = two.clone();
        two_bare.overlay = Default::default();
        g.bench_function(
            format!("{name} {w}x{h} two characters x{n} no overlays"),
            |b| b.iter(|| full.render(&two_bare).unwrap()),
        );
        // The camera moving: the floor is drawn again every frame.
        let mut turned = character.clone();
        turned.view_proj *= glam::Mat4::from_rotation_y(0.01);
        let mut flip = false;
        g.bench_function(
            format!("{name} {w}x{h} character x{n} camera moving"),
            |b| {
                b.iter(|| {
                    flip = !flip;
                    full.render(if flip { &turned } else { &character })
                        .unwrap()
                })
            },
        );
        // What the parts cost: without overlays, without floor and shadow.
        let mut no_overlay = character.clone();
        no_overlay.overlay = Default::default();
        g.bench_function(format!("{name} {w}x{h} character x{n} no overlays"), |b| {
            b.iter(|| full.render(&no_overlay).unwrap())
        });
        let mut no_floor = no_overlay.clone();
        no_floor.floor = false;
        g.bench_function(format!("{name} {w}x{h} character x{n} body only"), |b| {
            b.iter(|| full.render(&no_floor).unwrap())
        });
        // Composing the scene on the CPU (body mesh, overlays) per frame.
        g.bench_function(format!("{w}x{h} compose"), |b| {
            b.iter(|| {
                scene::compose(
                    &v,
                    &clip.skeleton,
                    &clip.roles,
                    &world,
                    &[Role::RightHand],
                    &marks,
                )
            })
        });
        // A skinned figure (the shared CesiumMan, tests only, where it is
        // beside the checkout): composing it skins every vertex on the CPU.
        let cesium = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/characters/CesiumMan.glb");
        let skin = marionette::character::gltf::load(&cesium, &Default::default())
            .ok()
            .map(|f| marionette::character::gltf::Skin::life_size(f, &lib, &clip.roles));
        fn figured<'a>(
            clip: &'a marionette::character::motion::Clip,
            w: &'a marionette::character::skeleton::WorldPose,
            held: &'a [Role],
            tint: Option<[f32; 3]>,
            skin: Option<&'a marionette::character::gltf::Skin>,
        ) -> scene::Body<'a> {
            scene::Body {
                skeleton: &clip.skeleton,
                roles: &clip.roles,
                world: w,
                held,
                tint,
                figure: skin,
                figure_joints: None,
            }
        }
        let one = [figured(clip, &world, &held, None, skin.as_ref())];
        let skinned = scene::compose_bodies(&v, &one, &marks);
        let two_skinned = scene::compose_bodies(
            &v,
            &[
                figured(clip, &world, &held, Some([0.62, 0.1, 0.07]), skin.as_ref()),
                figured(clip, &other, &held, Some([0.09, 0.26, 0.55]), skin.as_ref()),
            ],
            &both_marks,
        );
        // The project's own skinned body (the default look).
        let own = marionette::render::body::own_body(&lib, &clip.roles);
        let own_one = [figured(clip, &world, &held, None, Some(&own))];
        let own_skinned = scene::compose_bodies(&v, &own_one, &marks);
        let two_own = scene::compose_bodies(
            &v,
            &[
                figured(clip, &world, &held, Some([0.62, 0.1, 0.07]), Some(&own)),
                figured(clip, &other, &held, Some([0.09, 0.26, 0.55]), Some(&own)),
            ],
            &both_marks,
        );
        g.bench_function(format!("{w}x{h} compose own skinned body"), |b| {
            b.iter(|| scene::compose_bodies(&v, &own_one, &marks))
        });
        if skin.is_some() {
            g.bench_function(format!("{w}x{h} compose CesiumMan"), |b| {
                b.iter(|| scene::compose_bodies(&v, &one, &marks))
            });
        }
        // Every shared character (a file added there is timed too).
        let shared = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/characters");
        let mut files: Vec<std::path::PathBuf> = std::fs::read_dir(&shared)
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        files.sort();
        for file in files {
            let Ok(fig) = marionette::character::gltf::load(&file, &Default::default()) else {
                continue;
            };
            let each = marionette::character::gltf::Skin::life_size(fig, &lib, &clip.roles);
            let body = [figured(clip, &world, &held, None, Some(&each))];
            let name = file
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            g.bench_function(format!("{w}x{h} compose shared {name}"), |b| {
                b.iter(|| scene::compose_bodies(&v, &body, &marks))
            });
        }
        // Bare, one, two in turn (same renderer settings as above), unless
        // a filter given to the bench leaves them out.
        let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
        let label = format!("interleaved {w}x{h}");
        if filter.is_some_and(|f| !label.contains(&f)) {
            continue;
        }
        // The figures skinned the other way too (in the vertex shader
        // where the adapter is a CPU, which skins them on the CPU by
        // default; on the CPU where it is a GPU).
        let mut other =
            Headless::new(Gpu::new(AdapterChoice::Auto).unwrap(), w, h, samples).unwrap();
        let default_on_gpu = other.renderer.gpu_skinning();
        other.renderer.set_gpu_skinning(!default_on_gpu);
        let other_way = if default_on_gpu {
            "skinned on the CPU"
        } else {
            "skinned in the vertex shader"
        };
        let mut scenes = vec![
            ("bare 21 boxes".to_owned(), &boxes, 0),
            ("character".to_owned(), &character, 1),
            ("two characters".to_owned(), &two, 1),
            ("own skinned body".to_owned(), &own_skinned, 1),
            ("two own skinned bodies".to_owned(), &two_own, 1),
            (format!("two own skinned bodies {other_way}"), &two_own, 2),
        ];
        if skin.is_some() {
            scenes.push(("CesiumMan skinned".to_owned(), &skinned, 1));
            scenes.push(("two CesiumMan skinned".to_owned(), &two_skinned, 1));
            scenes.push((format!("two CesiumMan {other_way}"), &two_skinned, 2));
        }
        let mut times = vec![Vec::new(); scenes.len()];
        // Blocks of 12 frames of one scene, the first 2 not counted (the
        // caches warm up again after the other scenes), 30 rounds.
        for _ in 0..30 {
            for (k, (_, list, which)) in scenes.iter().enumerate() {
                let target = match which {
                    0 => &mut bare,
                    1 => &mut full,
                    _ => &mut other,
                };
                for i in 0..12 {
                    let start = std::time::Instant::now();
                    target.render(list).unwrap();
                    if i >= 2 {
                        times[k].push(start.elapsed().as_secs_f64() * 1e3);
                    }
                }
            }
        }
        let medians: Vec<f64> = times
            .iter_mut()
            .map(|t| {
                t.sort_by(f64::total_cmp);
                t[t.len() / 2]
            })
            .collect();
        for ((name, _, _), m) in scenes.iter().zip(&medians) {
            eprintln!(
                "{label} {name}: median {m:.2} ms, {:.2}x bare",
                m / medians[0]
            );
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
