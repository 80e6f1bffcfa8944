//! BVH out: metres, `Xposition Yposition Zposition` on the root (and on
//! the joints that translate), `Zrotation Yrotation Xrotation` on every
//! joint, the layout Blender's importer expects.

use std::fmt::Write as _;

use glam::EulerRot;

use crate::character::skeleton::{Pose, Skeleton};

/// Write a skeleton and postures (metres) as BVH. Joints whose
/// `translates[j]` is set get translation channels (the root always does).
#[must_use]
pub fn write(skeleton: &Skeleton, translates: &[bool], frames: &[Pose], frame_time: f64) -> String {
    let mut s = String::from("HIERARCHY\n");
    write_joint(&mut s, skeleton, translates, 0, 0);
    let _ = writeln!(
        s,
        "MOTION\nFrames: {}\nFrame Time: {:.8}",
        frames.len(),
        frame_time
    );
    for pose in frames {
        let mut first = true;
        for (j, _) in skeleton.joints.iter().enumerate() {
            let mut push = |v: f64| {
                if !first {
                    s.push(' ');
                }
                first = false;
                // Avoid "-0.000000".
                let v = if v.abs() < 5e-10 { 0.0 } else { v };
                let _ = write!(s, "{v:.6}");
            };
            if j == 0 || translates.get(j).copied().unwrap_or(false) {
                let p = pose.translations[j];
                push(p.x);
                push(p.y);
                push(p.z);
            }
            let (z, y, x) = pose.rotations[j].to_euler(EulerRot::ZYX);
            push(z.to_degrees());
            push(y.to_degrees());
            push(x.to_degrees());
        }
        s.push('\n');
    }
    s
}

fn write_joint(s: &mut String, skeleton: &Skeleton, translates: &[bool], j: usize, depth: usize) {
    let ind = "\t".repeat(depth);
    let joint = &skeleton.joints[j];
    let kw = if j == 0 { "ROOT" } else { "JOINT" };
    let _ = writeln!(s, "{ind}{kw} {}\n{ind}{{", joint.name);
    let o = joint.offset;
    let _ = writeln!(s, "{ind}\tOFFSET {:.6} {:.6} {:.6}", o.x, o.y, o.z);
    if j == 0 || translates.get(j).copied().unwrap_or(false) {
        let _ = writeln!(
            s,
            "{ind}\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation"
        );
    } else {
        let _ = writeln!(s, "{ind}\tCHANNELS 3 Zrotation Yrotation Xrotation");
    }
    for c in skeleton.children(j).collect::<Vec<_>>() {
        write_joint(s, skeleton, translates, c, depth + 1);
    }
    if let Some(e) = joint.end_site {
        let _ = writeln!(
            s,
            "{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {:.6} {:.6} {:.6}\n{ind}\t}}",
            e.x, e.y, e.z
        );
    }
    let _ = writeln!(s, "{ind}}}");
}
