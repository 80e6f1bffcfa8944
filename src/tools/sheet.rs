//! Contact sheets: frames of a clip side by side as stick figures, seen
//! from the front and from the side, written as PNG. For looking at motion
//! before the renderer exists, and for reviewing a library.

use std::path::Path;

use glam::DVec3;

use crate::character::roles::{Role, RoleMap};
use crate::character::skeleton::{Pose, Skeleton, forward_kinematics};

const PANEL_W: usize = 150;
const PANEL_H: usize = 230;
const PX_PER_M: f64 = 110.0;

struct Canvas {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Self {
        Self {
            w,
            h,
            rgb: vec![250; w * h * 3],
        }
    }

    fn dot(&mut self, x: f64, y: f64, r: f64, c: [u8; 3]) {
        let (x0, x1) = (
            (x - r).floor().max(0.0) as usize,
            ((x + r).ceil() as usize).min(self.w.saturating_sub(1)),
        );
        let (y0, y1) = (
            (y - r).floor().max(0.0) as usize,
            ((y + r).ceil() as usize).min(self.h.saturating_sub(1)),
        );
        for py in y0..=y1 {
            for px in x0..=x1 {
                if (px as f64 - x).hypot(py as f64 - y) <= r {
                    let i = (py * self.w + px) * 3;
                    self.rgb[i..i + 3].copy_from_slice(&c);
                }
            }
        }
    }

    fn line(&mut self, a: (f64, f64), b: (f64, f64), r: f64, c: [u8; 3]) {
        let n = ((b.0 - a.0).hypot(b.1 - a.1) / 0.7).ceil().max(1.0) as usize;
        for i in 0..=n {
            let s = i as f64 / n as f64;
            self.dot(a.0 + (b.0 - a.0) * s, a.1 + (b.1 - a.1) * s, r, c);
        }
    }
}

/// Draw `frames` (evenly chosen from `poses`) in two rows: from the front
/// and from the character's left side. Left limbs blue, right red.
pub fn write_sheet(
    path: &Path,
    skeleton: &Skeleton,
    roles: &RoleMap,
    poses: &[Pose],
    frames: usize,
) -> std::io::Result<()> {
    let n = frames.clamp(1, poses.len().max(1));
    let mut canvas = Canvas::new(PANEL_W * n, PANEL_H * 2);
    let left: Vec<usize> = [Role::LeftShoulder, Role::LeftHip]
        .iter()
        .map(|r| roles.get(*r))
        .collect();
    let right: Vec<usize> = [Role::RightShoulder, Role::RightHip]
        .iter()
        .map(|r| roles.get(*r))
        .collect();
    let side_of = |i: usize| {
        if left.iter().any(|&l| skeleton.is_ancestor(l, i)) {
            [40, 90, 220]
        } else if right.iter().any(|&r| skeleton.is_ancestor(r, i)) {
            [220, 60, 50]
        } else {
            [60, 60, 60]
        }
    };
    for k in 0..n {
        let idx = if n == 1 {
            0
        } else {
            k * (poses.len() - 1) / (n - 1)
        };
        let w = forward_kinematics(skeleton, &poses[idx]);
        let root = w.positions[0];
        for (row, project) in [
            (
                0usize,
                (|p: DVec3, c: DVec3| (c.x - p.x, p.y)) as fn(DVec3, DVec3) -> (f64, f64),
            ),
            (1usize, |p: DVec3, c: DVec3| (p.z - c.z, p.y)),
        ] {
            let ox = (k * PANEL_W) as f64 + PANEL_W as f64 / 2.0;
            let oy = (row * PANEL_H + PANEL_H) as f64 - 15.0;
            let to_px = |p: DVec3| {
                let (x, y) = project(p, root);
                (ox + x * PX_PER_M, oy - y * PX_PER_M)
            };
            canvas.line((ox - 60.0, oy), (ox + 60.0, oy), 0.6, [150, 150, 150]);
            for (i, jnt) in skeleton.joints.iter().enumerate() {
                if let Some(p) = jnt.parent {
                    canvas.line(
                        to_px(w.positions[p]),
                        to_px(w.positions[i]),
                        1.6,
                        side_of(i),
                    );
                }
                if let Some(e) = w.end_site(skeleton, i) {
                    canvas.line(to_px(w.positions[i]), to_px(e), 1.2, side_of(i));
                }
            }
            let head = to_px(w.positions[roles.get(Role::Head)]);
            canvas.dot(head.0, head.1 - 8.0, 7.0, [60, 60, 60]);
        }
    }
    let mut png_bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut png_bytes, canvas.w as u32, canvas.h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(&canvas.rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)?;
    crate::output::replace_file(path, &png_bytes)
}
