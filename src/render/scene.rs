//! Composing a frame: the character's posture as a smooth body of capsules
//! (limbs that join without gaps, a head, hands and shoes), the camera and
//! output rotation as matrices, and the overlays (a mark under every
//! finger, the held parts highlighted, action trajectories, a status line).
//! Pure: it builds a [`DrawList`] for the renderer.

use glam::{DVec3, Mat4, Vec3, Vec4};

use super::mesh::{AROUND, Mesh, Overlay, RINGS, text_width};
use super::solid::CapsulePart;
use crate::character::camera::Camera;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose};
use crate::control::marks::{FingerUse, Marks, ServiceMarks};
use crate::render::mesh::DrawList;
use crate::screen::Rotation;

/// Linear RGB of the background the floor fades into.
pub const BACKGROUND: [f32; 3] = [0.035, 0.045, 0.07];
/// Direction towards the key light (normalised when used).
pub const LIGHT: Vec3 = Vec3::new(0.45, 1.0, 0.6);

const SHIRT: [f32; 3] = [0.09, 0.26, 0.55];
const SKIN: [f32; 3] = [0.78, 0.52, 0.36];
const TROUSERS: [f32; 3] = [0.16, 0.16, 0.19];
const SHOES: [f32; 3] = [0.06, 0.05, 0.05];
const HELD: [f32; 3] = [1.0, 0.45, 0.08];
/// The shadow's coarse capsules: segments around, rings per end.
const SHADOW_AROUND: usize = 10;
const SHADOW_RINGS: usize = 2;

/// Where the picture goes: the camera (in picture pixels) and how the
/// picture is turned on the output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub camera: Camera,
    pub rotation: Rotation,
}

impl View {
    /// Clip-space turn of the picture on the output (clockwise).
    #[must_use]
    pub fn rotation_matrix(&self) -> Mat4 {
        let (c0, c1) = match self.rotation {
            Rotation::R0 => (Vec4::X, Vec4::Y),
            Rotation::R90 => (-Vec4::Y, Vec4::X),
            Rotation::R180 => (-Vec4::X, -Vec4::Y),
            Rotation::R270 => (Vec4::Y, -Vec4::X),
        };
        Mat4::from_cols(c0, c1, Vec4::Z, Vec4::W)
    }

    /// World → clip.
    #[must_use]
    pub fn view_proj(&self) -> Mat4 {
        let c = &self.camera;
        let proj = glam::camera::rh::proj::directx::perspective(
            (c.fov_y_deg as f32).to_radians(),
            (c.width / c.height) as f32,
            0.05,
            200.0,
        );
        let view =
            glam::camera::rh::view::look_at_mat4(c.eye.as_vec3(), c.target.as_vec3(), Vec3::Y);
        self.rotation_matrix() * proj * view
    }

    /// Picture pixels → clip.
    #[must_use]
    pub fn screen(&self) -> Mat4 {
        let (w, h) = (self.camera.width as f32, self.camera.height as f32);
        let ortho = Mat4::from_cols(
            Vec4::new(2.0 / w, 0.0, 0.0, 0.0),
            Vec4::new(0.0, -2.0 / h, 0.0, 0.0),
            Vec4::Z,
            Vec4::new(-1.0, 1.0, 0.0, 1.0),
        );
        self.rotation_matrix() * ortho
    }

    /// A draw list with nothing in it yet.
    #[must_use]
    pub fn empty(&self, floor: bool) -> DrawList {
        DrawList {
            view_proj: self.view_proj(),
            screen: self.screen(),
            eye: self.camera.eye.as_vec3(),
            light: LIGHT.normalize(),
            background: BACKGROUND,
            fog_start: 8.0,
            floor,
            ..DrawList::default()
        }
    }
}

/// A body segment: which part it belongs to, for highlighting.
pub(super) struct Segment {
    pub(super) part: Role,
    pub(super) a: DVec3,
    pub(super) b: DVec3,
    pub(super) r: f64,
    pub(super) color: [f32; 3],
}

impl Segment {
    fn part(&self, color: [f32; 4]) -> CapsulePart {
        CapsulePart {
            a: self.a.as_vec3(),
            b: self.b.as_vec3(),
            r: self.r as f32,
            color,
        }
    }
}

/// Positions along the joint chain from ancestor `from` down to `to`.
fn chain(skeleton: &Skeleton, world: &WorldPose, from: usize, to: usize) -> Vec<DVec3> {
    let mut joints = vec![to];
    let mut j = to;
    while j != from {
        match skeleton.joints[j].parent {
            Some(p) => {
                joints.push(p);
                j = p;
            }
            None => return vec![world.positions[from], world.positions[to]],
        }
    }
    joints.reverse();
    joints.into_iter().map(|j| world.positions[j]).collect()
}

/// The point past a joint: its first child, else its End Site, else
/// `fallback` from it.
fn tip(skeleton: &Skeleton, world: &WorldPose, joint: usize, fallback: DVec3) -> DVec3 {
    skeleton
        .children(joint)
        .next()
        .map(|c| world.positions[c])
        .or_else(|| world.end_site(skeleton, joint))
        .filter(|p| (*p - world.positions[joint]).length() > 0.02)
        .unwrap_or(world.positions[joint] + fallback)
}

pub(super) fn segments(skeleton: &Skeleton, roles: &RoleMap, world: &WorldPose) -> Vec<Segment> {
    let mut out = Vec::new();
    let push_chain =
        |out: &mut Vec<Segment>, part: Role, from: Role, to: Role, r: f64, color: [f32; 3]| {
            let pts = chain(skeleton, world, roles.get(from), roles.get(to));
            for w in pts.windows(2) {
                out.push(Segment {
                    part,
                    a: w[0],
                    b: w[1],
                    r,
                    color,
                });
            }
        };
    // Trunk: spine, a wide chest and hips.
    push_chain(
        &mut out,
        Role::Chest,
        Role::Pelvis,
        Role::Chest,
        0.115,
        SHIRT,
    );
    push_chain(&mut out, Role::Head, Role::Chest, Role::Neck, 0.06, SHIRT);
    push_chain(&mut out, Role::Head, Role::Neck, Role::Head, 0.05, SKIN);
    for (shoulder, elbow, hand, hip, knee, foot) in [
        (
            Role::LeftShoulder,
            Role::LeftElbow,
            Role::LeftHand,
            Role::LeftHip,
            Role::LeftKnee,
            Role::LeftFoot,
        ),
        (
            Role::RightShoulder,
            Role::RightElbow,
            Role::RightHand,
            Role::RightHip,
            Role::RightKnee,
            Role::RightFoot,
        ),
    ] {
        push_chain(&mut out, Role::Chest, Role::Chest, shoulder, 0.075, SHIRT);
        push_chain(&mut out, elbow, shoulder, elbow, 0.056, SHIRT);
        push_chain(&mut out, hand, elbow, hand, 0.045, SKIN);
        push_chain(&mut out, Role::Pelvis, Role::Pelvis, hip, 0.095, TROUSERS);
        push_chain(&mut out, knee, hip, knee, 0.078, TROUSERS);
        push_chain(&mut out, foot, knee, foot, 0.058, TROUSERS);
        out.extend(mitten_and_shoe(
            skeleton,
            roles,
            world,
            [elbow, hand],
            [hip, knee, foot],
        ));
    }
    out.extend(volumes(skeleton, roles, world));
    out
}

/// The trunk's volumes, so that it reads as a body and not a stick: the
/// chest across the shoulders and as a mass, the hips across the hip
/// joints, and the head as a sphere above the head joint, along the neck.
fn volumes(skeleton: &Skeleton, roles: &RoleMap, world: &WorldPose) -> [Segment; 4] {
    let p = |r: Role| world.positions[roles.get(r)];
    let up = (p(Role::Head) - p(Role::Neck)).normalize_or(DVec3::Y);
    let head_tip = tip(skeleton, world, roles.get(Role::Head), up * 0.2);
    let centre = p(Role::Head) + (head_tip - p(Role::Head)) * 0.45;
    [
        Segment {
            part: Role::Chest,
            a: p(Role::LeftShoulder),
            b: p(Role::RightShoulder),
            r: 0.075,
            color: SHIRT,
        },
        Segment {
            part: Role::Chest,
            a: (p(Role::Chest) * 0.7 + p(Role::Pelvis) * 0.3),
            b: (p(Role::Chest) * 0.7 + p(Role::Pelvis) * 0.3),
            r: 0.14,
            color: SHIRT,
        },
        Segment {
            part: Role::Pelvis,
            a: p(Role::LeftHip),
            b: p(Role::RightHip),
            r: 0.1,
            color: TROUSERS,
        },
        Segment {
            part: Role::Head,
            a: centre,
            b: centre,
            r: 0.105,
            color: SKIN,
        },
    ]
}

/// A mitten past the wrist (along the forearm or the hand's bones) and a
/// shoe from the ankle to the toes, resting on its sole, for one side.
fn mitten_and_shoe(
    skeleton: &Skeleton,
    roles: &RoleMap,
    world: &WorldPose,
    [elbow, hand]: [Role; 2],
    [hip, knee, foot]: [Role; 3],
) -> [Segment; 2] {
    let p = |r: Role| world.positions[roles.get(r)];
    // A mitten past the wrist, along the forearm or the hand's bones.
    let forearm = (p(hand) - p(elbow)).normalize_or_zero();
    let h = p(hand);
    let end = tip(skeleton, world, roles.get(hand), forearm * 0.08);
    let along = (end - h).normalize_or(forearm);
    let mitten = Segment {
        part: hand,
        a: h,
        b: h + along * 0.07,
        r: 0.047,
        color: SKIN,
    };
    // A shoe from the ankle to the toes, resting on its sole.
    let f = p(foot);
    let facing = (p(knee) - p(hip)).cross(p(Role::LeftHip) - p(Role::RightHip));
    let fallback = DVec3::new(facing.x, 0.0, facing.z).normalize_or(DVec3::Z) * 0.14;
    let toe = tip(skeleton, world, roles.get(foot), fallback);
    let r = 0.045;
    let shoe = Segment {
        part: foot,
        a: f,
        b: toe.with_y(toe.y.max(r)),
        r,
        color: SHOES,
    };
    [mitten, shoe]
}

/// Which segments glow when a finger holds `role`.
fn highlights(part: Role, held: &[Role]) -> bool {
    held.contains(&part)
}

/// The character's body as a mesh; parts in `held` are highlighted.
#[must_use]
pub fn body_mesh(skeleton: &Skeleton, roles: &RoleMap, world: &WorldPose, held: &[Role]) -> Mesh {
    let mut mesh = Mesh::default();
    body_into(&mut mesh, &segments(skeleton, roles, world), held);
    mesh
}

/// A coarse body for the shadow: its outline is all that shows.
#[must_use]
pub fn shadow_mesh(skeleton: &Skeleton, roles: &RoleMap, world: &WorldPose) -> Mesh {
    let mut mesh = Mesh::default();
    shadow_into(&mut mesh, &segments(skeleton, roles, world));
    mesh
}

/// The coarse capsules that cast a body's shadow.
///
/// The stencil darkens each shadow pixel once, so the capsules are laid
/// whole, overlapping, rather than as their union (what lies inside one
/// capsule falls inside its shadow: the same pixels, for half the time
/// of composing a skinned figure's frame); of each, only the half facing
/// the light (the other half falls on the same pixels).
fn shadow_into(mesh: &mut Mesh, segments: &[Segment]) {
    let from = mesh.indices.len() / 3;
    for s in segments {
        let c = s.part([0.0; 4]);
        mesh.capsule_with(c.a, c.b, c.r, c.color, SHADOW_AROUND, SHADOW_RINGS);
    }
    mesh.keep_facing(LIGHT, from);
}

pub(super) fn body_into(mesh: &mut Mesh, segments: &[Segment], held: &[Role]) {
    let parts: Vec<CapsulePart> = segments
        .iter()
        .map(|s| {
            let glow = highlights(s.part, held);
            let c = if glow { HELD } else { s.color };
            s.part([c[0], c[1], c[2], if glow { 1.0 } else { 0.0 }])
        })
        .collect();
    mesh.capsule_union(&parts, AROUND, RINGS);
}

/// A tint brightened for a mark over the picture (the clothes' colours
/// are dark), with alpha `a`.
fn bright(c: [f32; 3], a: f32) -> [f32; 4] {
    let top = c[0].max(c[1]).max(c[2]).max(1e-3);
    let k = 1.0 / top;
    [c[0] * k, c[1] * k, c[2] * k, a]
}

/// The overlays of one frame.
#[must_use]
pub fn overlay(marks: &Marks, width: f64) -> Overlay {
    let mut o = Overlay::default();
    for t in &marks.trajectories {
        let pts: Vec<[f32; 2]> = t.points.iter().map(|p| [p.x as f32, p.y as f32]).collect();
        let color = match (t.tint, t.executable) {
            (None, true) => [0.85, 0.03, 0.02, 0.9],
            (None, false) => [1.0, 0.42, 0.62, 0.75],
            (Some(c), true) => bright(c, 0.9),
            (Some(c), false) => bright(c.map(|v| 0.5 + 0.5 * v), 0.6),
        };
        o.polyline(&pts, 5.0, color);
        if pts.len() >= 2 {
            let n = pts.len();
            o.arrow_head(pts[n.saturating_sub(4)], pts[n - 1], 18.0, color);
        }
    }
    for f in &marks.fingers {
        let c = [f.at.x as f32, f.at.y as f32];
        let ring = match (f.usage, f.tint) {
            (FingerUse::Part(_), None) => [1.0, 0.45, 0.08, 0.95],
            (FingerUse::Part(_), Some(c)) => bright(c, 0.95),
            (FingerUse::Camera, _) => [0.55, 0.75, 1.0, 0.9],
        };
        o.disc(c, 34.0, [0.0, 0.0, 0.0, 0.22]);
        o.ring(c, 34.0, 5.0, ring);
        o.disc(c, 5.0, ring);
    }
    let mut top = 0.0;
    if let Some(text) = &marks.status {
        let scale = 2.0;
        let w = text_width(text, scale).min(width as f32) + 24.0;
        o.rect(0.0, 0.0, w, 8.0 * scale + 16.0, [0.0, 0.0, 0.0, 0.55]);
        o.text(12.0, 8.0, scale, text, [0.95, 0.95, 0.95, 1.0]);
        top = 8.0 * scale + 16.0;
    }
    if let Some(service) = &marks.service {
        service_overlay(&mut o, service, width, top);
    }
    o
}

/// The service view: every finger's trail and calibrated point (a
/// crosshair), and a panel of text lines under the status line.
fn service_overlay(o: &mut Overlay, service: &ServiceMarks, width: f64, top: f32) {
    let cyan = [0.2, 0.95, 0.95, 0.95];
    for trail in &service.trails {
        let pts: Vec<[f32; 2]> = trail.iter().map(|p| [p.x as f32, p.y as f32]).collect();
        o.polyline(&pts, 3.0, cyan);
        if let Some(&[x, y]) = pts.last() {
            o.rect(x - 14.0, y - 1.0, 28.0, 2.0, cyan);
            o.rect(x - 1.0, y - 14.0, 2.0, 28.0, cyan);
        }
    }
    let widest = |scale: f32| {
        service
            .lines
            .iter()
            .map(|l| text_width(l, scale))
            .fold(0.0, f32::max)
    };
    // Twice the font's size where the longest line fits.
    let scale = if widest(2.0) + 24.0 <= width as f32 {
        2.0
    } else {
        1.0
    };
    let line_h = 8.0 * scale + 6.0;
    let w = widest(scale).min(width as f32) + 24.0;
    let h = service.lines.len() as f32 * line_h + 12.0;
    o.rect(0.0, top, w, h, [0.0, 0.05, 0.1, 0.7]);
    for (k, line) in service.lines.iter().enumerate() {
        o.text(12.0, top + 8.0 + k as f32 * line_h, scale, line, cyan);
    }
}

/// The character with its overlays.
#[must_use]
pub fn compose(
    view: &View,
    skeleton: &Skeleton,
    roles: &RoleMap,
    world: &WorldPose,
    held: &[Role],
    marks: &Marks,
) -> DrawList {
    compose_bodies(
        view,
        &[Body {
            skeleton,
            roles,
            world,
            held,
            tint: None,
            figure: None,
            figure_joints: None,
        }],
        marks,
    )
}

/// One character to draw: its posture, the parts fingers hold, and the
/// tint of its clothes (`None`: the default blue shirt).
#[derive(Clone, Copy, Debug)]
pub struct Body<'a> {
    pub skeleton: &'a Skeleton,
    pub roles: &'a RoleMap,
    pub world: &'a WorldPose,
    pub held: &'a [Role],
    pub tint: Option<[f32; 3]>,
    /// A skinned figure shown instead of the capsules, with its joints
    /// as posed in the postures before this one (see
    /// `Actor::figure_joints`; `None`: posed for this posture alone).
    pub figure: Option<&'a crate::character::gltf::Skin>,
    pub figure_joints: Option<&'a [glam::DMat4]>,
}

/// The draw list of several characters, each with its shadow, and the
/// overlays of every visitor.
#[must_use]
pub fn compose_bodies(view: &View, bodies: &[Body<'_>], marks: &Marks) -> DrawList {
    let mut list = view.empty(true);
    for b in bodies {
        let mut segs = segments(b.skeleton, b.roles, b.world);
        if let Some(skin) = b.figure {
            // Shown as large as the library's character, the figure casts
            // about the capsules' shadow: the coarse one, at a fraction of
            // drawing its every triangle twice.
            let alone;
            let joints = match b.figure_joints {
                Some(j) => j,
                None => {
                    alone = skin.joints(b.world);
                    &alone
                }
            };
            super::figure::draw(&mut list, skin, joints, b.held, b.tint);
            shadow_into(&mut list.shadow, &segs);
            continue;
        }
        if let Some(tint) = b.tint {
            for s in &mut segs {
                s.color = tinted(s.color, tint);
            }
        }
        body_into(&mut list.body, &segs, b.held);
        shadow_into(&mut list.shadow, &segs);
    }
    list.overlay = overlay(marks, view.camera.width);
    list
}

/// Clothes take the tint (the shirt, the tint itself; trousers, a dark
/// shade of it); skin and shoes stay as they are.
pub(super) fn tinted(color: [f32; 3], tint: [f32; 3]) -> [f32; 3] {
    if color == SHIRT {
        tint
    } else if color == TROUSERS {
        [
            0.5 * TROUSERS[0] + 0.25 * tint[0],
            0.5 * TROUSERS[1] + 0.25 * tint[1],
            0.5 * TROUSERS[2] + 0.25 * tint[2],
        ]
    } else {
        color
    }
}

/// The bare scene benchmarks compare with: `n` lit boxes, no floor, no
/// shadow, no overlays.
#[must_use]
pub fn boxes(view: &View, n: usize) -> DrawList {
    let mut list = view.empty(false);
    let cols = (n as f64).sqrt().ceil() as usize;
    for i in 0..n {
        let (cx, cz) = ((i % cols) as f32, (i / cols) as f32);
        let c = Vec3::new(
            (cx - cols as f32 / 2.0) * 0.5,
            0.8,
            (cz - cols as f32 / 2.0) * 0.5,
        );
        list.body.cuboid(c, Vec3::splat(0.15), [0.5, 0.6, 0.7, 0.0]);
    }
    list
}
