//! The project's own skinned body, shown by default: the capsule figure's
//! shapes (shirt, trousers, skin and shoes) laid over the library's
//! skeleton in its rest pose, each meshed whole and skinned to the joints
//! at its ends with weights that blend across them (an elbow bends as one
//! sleeve, not two capsules meeting). It is a [`Figure`] like an exhibit's
//! glTF character and is drawn and shadowed as one, posed straight from
//! the library's skeleton.

use glam::{DMat4, DVec3};

use super::mesh::Mesh;
use super::scene::segments;
use crate::character::gltf::{Figure, Part, Skin};
use crate::character::library::Library;
use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Skeleton, WorldPose, forward_kinematics};

/// How far from each end of a segment its vertices start to blend with
/// the joint beyond that end (fraction of its length).
const BLEND: f64 = 0.3;

/// Segments around each capsule and rings per end: fewer than the
/// capsule figure's (16, 5), whose union leaves out what lies inside
/// another capsule; the smooth normals round them off.
const OWN_AROUND: usize = 12;
const OWN_RINGS: usize = 3;

/// How high the lowest joint stands at rest (m): a shoe's radius.
const SOLE_M: f64 = 0.045;

/// The joint whose rest position is nearest `p`.
fn joint_at(rest: &WorldPose, p: DVec3) -> usize {
    (0..rest.positions.len())
        .min_by(|&x, &y| {
            rest.positions[x]
                .distance_squared(p)
                .total_cmp(&rest.positions[y].distance_squared(p))
        })
        .unwrap_or(0)
}

/// Which joints carry a segment from the joint at its `a` end to the one
/// at its `b` end: (the joint carrying it, the joint it blends into at
/// `a`, at `b`). A bone (one end below the other) is carried by its upper
/// joint and blends into that joint's parent at the top and into the
/// lower joint at the bottom; a segment across (hip to hip) is carried by
/// the joints' common ancestor; a ball (the head) by its joint.
fn carriers(sk: &Skeleton, ja: usize, jb: usize) -> (usize, usize, usize) {
    if ja == jb {
        return (ja, ja, ja);
    }
    let (top, bottom) = if sk.is_ancestor(jb, ja) {
        (jb, ja)
    } else {
        (ja, jb)
    };
    if sk.is_ancestor(top, bottom) {
        let parent = sk.joints[top].parent.unwrap_or(top);
        return if top == ja {
            (top, parent, bottom)
        } else {
            (top, bottom, parent)
        };
    }
    let c = sk.common_ancestor(ja, jb);
    (c, c, c)
}

/// The body for `lib`'s skeleton (`roles` name its parts), driven by
/// `lib`.
#[must_use]
pub fn own_body(lib: &Library, roles: &RoleMap) -> Skin {
    Skin::new(own_figure(lib, roles), lib, roles)
}

/// The body as a figure in the library's rest pose.
#[must_use]
pub fn own_figure(lib: &Library, roles: &RoleMap) -> Figure {
    let sk = &lib.skeleton;
    let rest = standing_rest(sk);
    // Each segment meshed whole (a bent joint shows what the capsules'
    // union would have left out), its vertices carried by its joints.
    let mut mesh = Mesh::default();
    let mut roles_of = Vec::new();
    let mut joints = Vec::new();
    let mut weights = Vec::new();
    for seg in segments(sk, roles, &rest) {
        let from = mesh.vertices.len();
        let c = seg.color;
        mesh.capsule_with(
            seg.a.as_vec3(),
            seg.b.as_vec3(),
            seg.r as f32,
            [c[0], c[1], c[2], 0.0],
            OWN_AROUND,
            OWN_RINGS,
        );
        let (carrier, at_a, at_b) = carriers(sk, joint_at(&rest, seg.a), joint_at(&rest, seg.b));
        let ab = seg.b - seg.a;
        for v in &mesh.vertices[from..] {
            let p = DVec3::from(v.pos.map(f64::from));
            let t = if ab.length_squared() > 1e-12 {
                (p - seg.a).dot(ab) / ab.length_squared()
            } else {
                0.5
            };
            let (js, ws) = skin_at(t, (carrier, at_a, at_b));
            joints.push(js);
            weights.push(ws);
            roles_of.push(seg.part);
        }
    }
    let parts = parts_by_colour(&mesh, &roles_of, &joints, &weights);
    let height_m = mesh
        .vertices
        .iter()
        .map(|v| f64::from(v.pos[1]))
        .fold(0.0, f64::max);
    Figure {
        skeleton: sk.clone(),
        rest: (0..sk.len())
            .map(|j| DMat4::from_rotation_translation(rest.rotations[j], rest.positions[j]))
            .collect(),
        roles: roles.clone(),
        evidence: roles
            .0
            .keys()
            .map(|r| {
                (
                    *r,
                    crate::character::gltf::humanoid::Evidence::Configuration,
                )
            })
            .collect(),
        roles_by: "the library",
        parts,
        skins: 1,
        height_m,
        scale_to_m: 1.0,
        facing: "+Z".to_owned(),
        up: "+Y".to_owned(),
        warnings: Vec::new(),
        own: true,
        made_up: vec![false; sk.len()],
        credit: None,
    }
}

/// The rest pose standing on the floor: its lowest joint or End Site as
/// high as a shoe's sole puts it (the shoes rest on the floor).
fn standing_rest(sk: &Skeleton) -> WorldPose {
    let mut pose = sk.rest_pose();
    let low = {
        let w = forward_kinematics(sk, &pose);
        (0..sk.len())
            .flat_map(|j| [Some(w.positions[j]), w.end_site(sk, j)])
            .flatten()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min)
    };
    if low.is_finite() {
        pose.translations[0].y += SOLE_M - low;
    }
    forward_kinematics(sk, &pose)
}

/// The joints and weights of a segment's vertex at `t` along it (0 at its
/// start, 1 at its end): its carrier, and up to half the turn of the joint
/// beyond an end, at that end.
fn skin_at(t: f64, (carrier, at_a, at_b): (usize, usize, usize)) -> ([u16; 4], [f32; 4]) {
    let beyond = |s: f64| 0.5 * (1.0 - s / BLEND).clamp(0.0, 1.0).powi(2);
    let mut ws = [0.0; 4];
    let mut js = [0u16; 4];
    let mut add = |j: usize, w: f64| {
        let k = js[..3]
            .iter()
            .zip(&ws)
            .position(|(&x, &wx)| wx == 0.0 || usize::from(x) == j)
            .unwrap_or(3);
        js[k] = u16::try_from(j).unwrap_or(0);
        ws[k] += w as f32;
    };
    let (wa, wb) = (beyond(t), beyond(1.0 - t));
    add(carrier, 1.0 - wa - wb);
    if wa > 0.0 {
        add(at_a, wa);
    }
    if wb > 0.0 {
        add(at_b, wb);
    }
    (js, ws)
}

/// The mesh as one part per colour and body part (the clothes are tinted
/// per character; a held part glows), each vertex with its joints and
/// weights.
fn parts_by_colour(
    mesh: &Mesh,
    roles_of: &[Role],
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
) -> Vec<Part> {
    let mut parts: Vec<Part> = Vec::new();
    let mut index_in: Vec<Option<(usize, u32)>> = vec![None; mesh.vertices.len()];
    for t in mesh.indices.chunks_exact(3) {
        let colour = mesh.vertices[t[0] as usize].color;
        let rgb = [colour[0], colour[1], colour[2], 1.0];
        let role = roles_of[t[0] as usize];
        let k = match parts
            .iter()
            .position(|p| p.base_colour == rgb && p.role == Some(role))
        {
            Some(k) => k,
            None => {
                parts.push(Part {
                    positions: Vec::new(),
                    joints: Vec::new(),
                    weights: Vec::new(),
                    indices: Vec::new(),
                    base_colour: rgb,
                    colours: Vec::new(),
                    role: Some(role),
                });
                parts.len() - 1
            }
        };
        for &i in t {
            let i = i as usize;
            let local = match index_in[i] {
                Some((part, local)) if part == k => local,
                _ => {
                    let part = &mut parts[k];
                    let local = part.positions.len() as u32;
                    part.positions.push(mesh.vertices[i].pos);
                    part.joints.push(joints[i]);
                    part.weights.push(weights[i]);
                    index_in[i] = Some((k, local));
                    local
                }
            };
            parts[k].indices.push(local);
        }
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the skinned body's vertices lie, posed, against the capsule
    /// figure of the same posture: how far each is off the surface of the
    /// nearest capsule of its own part and colour (m), mean and worst over
    /// every `every`th frame of every clip.
    fn off_the_capsules(lib: &Library, roles: &RoleMap, every: usize) -> (f64, f64) {
        let fig = own_figure(lib, roles);
        let sk = &lib.skeleton;
        let (mut worst, mut sum, mut n) = (0.0f64, 0.0, 0usize);
        for clip in lib.clips.values() {
            for pose in clip.frames.iter().step_by(every) {
                let world = forward_kinematics(sk, pose);
                let segs = segments(sk, roles, &world);
                let skin: Vec<DMat4> = (0..sk.len())
                    .map(|j| {
                        DMat4::from_rotation_translation(world.rotations[j], world.positions[j])
                            * fig.rest[j].inverse()
                    })
                    .collect();
                for part in &fig.parts {
                    let mine: Vec<_> = segs
                        .iter()
                        .filter(|s| Some(s.part) == part.role && s.color == part.base_colour[..3])
                        .collect();
                    for (i, p) in part.positions.iter().enumerate() {
                        let p = DVec3::from(p.map(f64::from));
                        let q: DVec3 = (0..4)
                            .map(|k| {
                                f64::from(part.weights[i][k])
                                    * skin[usize::from(part.joints[i][k])].transform_point3(p)
                            })
                            .sum();
                        let off = mine
                            .iter()
                            .map(|s| {
                                let ab = s.b - s.a;
                                let t = if ab.length_squared() > 1e-12 {
                                    ((q - s.a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                                } else {
                                    0.0
                                };
                                (q.distance(s.a + ab * t) - s.r).abs()
                            })
                            .fold(f64::INFINITY, f64::min);
                        worst = worst.max(off);
                        sum += off;
                        n += 1;
                    }
                }
            }
        }
        (sum / n.max(1) as f64, worst)
    }

    use crate::character::library::default_library;

    #[test]
    fn the_skinned_body_follows_the_capsule_figure_of_every_clip() {
        let lib = default_library();
        let roles = lib.clips.values().next().expect("clips").roles.clone();
        let (mean, worst) = off_the_capsules(&lib, &roles, 5);
        // Measured: 2.57 mm, and 61.5 mm at the deepest knee bend (the
        // blended knee rounds off where the capsules meet at an edge).
        assert!(mean < 0.0028, "mean {:.2} mm", mean * 1e3);
        assert!(worst < 0.065, "worst {:.1} mm", worst * 1e3);
    }

    #[test]
    fn every_vertex_is_carried_by_weights_that_sum_to_one() {
        let lib = default_library();
        let roles = lib.clips.values().next().expect("clips").roles.clone();
        let fig = own_figure(&lib, &roles);
        assert!(fig.own && fig.vertices() > 1000, "{}", fig.vertices());
        for part in &fig.parts {
            assert!(part.role.is_some());
            for (j, w) in part.joints.iter().zip(&part.weights) {
                assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
                assert!(j.iter().all(|&j| usize::from(j) < lib.skeleton.len()));
            }
        }
        // Standing on the floor at rest, a body's height tall.
        let low = fig
            .parts
            .iter()
            .flat_map(|p| &p.positions)
            .map(|p| p[1])
            .fold(f32::INFINITY, f32::min);
        assert!(low.abs() < 0.005, "{low}");
        assert!((1.5..2.0).contains(&fig.height_m), "{}", fig.height_m);
    }
}
