//! CPU geometry for the renderer: the vertex formats the shaders read, and
//! meshes built from primitives (capsules, spheres, boxes, the floor, 2-D
//! overlay shapes). Pure; the scene builds them each frame and the renderer
//! uploads them.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::character::gltf::Geometry;

/// A lit 3-D vertex. `color.a` is how strongly the surface glows (0 for a
/// plain surface, 1 for a highlighted body part).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex3 {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    pub color: [f32; 4],
}

/// A 2-D overlay vertex in picture pixels (origin top left, y down).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex2 {
    pub pos: [f32; 2],
    pub color: [f32; 4],
}

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<Vertex3>,
    pub indices: Vec<u32>,
}

/// Segments around a capsule.
pub const AROUND: usize = 16;
/// Rings per hemisphere of a capsule.
pub const RINGS: usize = 5;

/// Any unit vector perpendicular to `axis`.
fn perpendicular(axis: Vec3) -> Vec3 {
    let other = if axis.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    axis.cross(other).normalize()
}

impl Mesh {
    pub(crate) fn base(&self) -> u32 {
        u32::try_from(self.vertices.len()).expect("mesh under 4 G vertices")
    }

    /// A capsule: the points within `r` of the segment `a`–`b` (a sphere
    /// when they coincide). Capsules that share an end point and radius join
    /// without a gap.
    pub fn capsule(&mut self, a: Vec3, b: Vec3, r: f32, color: [f32; 4]) {
        self.capsule_with(a, b, r, color, AROUND, RINGS);
    }

    /// A capsule with `around` segments and `rings` rings per end (coarse
    /// ones for shadows).
    pub fn capsule_with(
        &mut self,
        a: Vec3,
        b: Vec3,
        r: f32,
        color: [f32; 4],
        around: usize,
        rings_per_end: usize,
    ) {
        let (around_n, rings_n) = (around.max(3), rings_per_end.max(1));
        let axis = (b - a).try_normalize().unwrap_or(Vec3::Y);
        let u = perpendicular(axis);
        let v = axis.cross(u);
        let base = self.base();
        // Rings from the pole at `a` to the pole at `b`: 0..=rings_n around
        // `a` (latitude -90°..0°), then rings_n+1..=2*rings_n+1 around `b`.
        let rings = 2 * rings_n + 2;
        for ring in 0..rings {
            let (centre, lat) = if ring <= rings_n {
                (
                    a,
                    -std::f32::consts::FRAC_PI_2 * (1.0 - ring as f32 / rings_n as f32),
                )
            } else {
                (
                    b,
                    std::f32::consts::FRAC_PI_2 * ((ring - rings_n - 1) as f32 / rings_n as f32),
                )
            };
            for k in 0..=around_n {
                let theta = std::f32::consts::TAU * k as f32 / around_n as f32;
                let n = (u * theta.cos() + v * theta.sin()) * lat.cos() + axis * lat.sin();
                self.vertices.push(Vertex3 {
                    pos: (centre + n * r).to_array(),
                    normal: n.to_array(),
                    color,
                });
            }
        }
        let row = (around_n + 1) as u32;
        for ring in 0..(rings - 1) as u32 {
            for k in 0..around_n as u32 {
                let i0 = base + ring * row + k;
                let i1 = i0 + row;
                self.indices
                    .extend_from_slice(&[i0, i0 + 1, i1, i1, i0 + 1, i1 + 1]);
            }
        }
    }

    /// A sphere.
    pub fn sphere(&mut self, c: Vec3, r: f32, color: [f32; 4]) {
        self.capsule(c, c, r, color);
    }

    /// An axis-aligned box.
    pub fn cuboid(&mut self, centre: Vec3, half: Vec3, color: [f32; 4]) {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            let u = perpendicular(axis);
            let v = axis.cross(u);
            let base = self.base();
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = centre + (axis + u * su + v * sv) * half;
                self.vertices.push(Vertex3 {
                    pos: p.to_array(),
                    normal: axis.to_array(),
                    color,
                });
            }
            self.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }

    /// A horizontal square of half-size `half` at height `y`, facing up.
    pub fn ground(&mut self, half: f32, y: f32, color: [f32; 4]) {
        let base = self.base();
        for (x, z) in [(-half, -half), (-half, half), (half, half), (half, -half)] {
            self.vertices.push(Vertex3 {
                pos: [x, y, z],
                normal: [0.0, 1.0, 0.0],
                color,
            });
        }
        self.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
}

/// 2-D overlay geometry (triangles) in picture pixels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overlay {
    pub vertices: Vec<Vertex2>,
}

impl Overlay {
    fn tri(&mut self, a: [f32; 2], b: [f32; 2], c: [f32; 2], color: [f32; 4]) {
        for pos in [a, b, c] {
            self.vertices.push(Vertex2 { pos, color });
        }
    }

    /// An axis-aligned rectangle.
    pub fn rect(&mut self, x: f32, y: f32, w: f32, h: f32, color: [f32; 4]) {
        self.tri([x, y], [x + w, y], [x + w, y + h], color);
        self.tri([x, y], [x + w, y + h], [x, y + h], color);
    }

    /// Segments for a circle of radius `r` px (smooth, no more than needed).
    fn segments(r: f32) -> usize {
        ((r * 0.8) as usize).clamp(8, 48)
    }

    /// A ring of outer radius `r` and width `w`.
    pub fn ring(&mut self, c: [f32; 2], r: f32, w: f32, color: [f32; 4]) {
        let n = Self::segments(r);
        let inner = (r - w).max(0.0);
        let p = |k: usize, rr: f32| {
            let a = std::f32::consts::TAU * k as f32 / n as f32;
            [c[0] + a.cos() * rr, c[1] + a.sin() * rr]
        };
        for k in 0..n {
            self.tri(p(k, inner), p(k, r), p(k + 1, r), color);
            self.tri(p(k, inner), p(k + 1, r), p(k + 1, inner), color);
        }
    }

    /// A filled disc.
    pub fn disc(&mut self, c: [f32; 2], r: f32, color: [f32; 4]) {
        let n = Self::segments(r);
        let p = |k: usize| {
            let a = std::f32::consts::TAU * k as f32 / n as f32;
            [c[0] + a.cos() * r, c[1] + a.sin() * r]
        };
        for k in 0..n {
            self.tri(c, p(k), p(k + 1), color);
        }
    }

    /// A polyline of width `w`.
    pub fn polyline(&mut self, points: &[[f32; 2]], w: f32, color: [f32; 4]) {
        for p in points.windows(2) {
            let (a, b) = (glam::Vec2::from(p[0]), glam::Vec2::from(p[1]));
            let Some(d) = (b - a).try_normalize() else {
                continue;
            };
            let n = glam::Vec2::new(-d.y, d.x) * (w / 2.0);
            self.tri(
                (a + n).to_array(),
                (b + n).to_array(),
                (b - n).to_array(),
                color,
            );
            self.tri(
                (a + n).to_array(),
                (b - n).to_array(),
                (a - n).to_array(),
                color,
            );
        }
        // Round joints where a thick line would show notches.
        if w > 8.0 {
            for p in points.iter().skip(1).take(points.len().saturating_sub(2)) {
                self.disc(*p, w / 2.0, color);
            }
        }
    }

    /// An arrow head at `tip` pointing along `from` → `tip`.
    pub fn arrow_head(&mut self, from: [f32; 2], tip: [f32; 2], size: f32, color: [f32; 4]) {
        let (a, b) = (glam::Vec2::from(from), glam::Vec2::from(tip));
        let Some(d) = (b - a).try_normalize() else {
            return;
        };
        let n = glam::Vec2::new(-d.y, d.x);
        let back = b - d * size;
        self.tri(
            b.to_array(),
            (back + n * size * 0.5).to_array(),
            (back - n * size * 0.5).to_array(),
            color,
        );
    }

    /// Text in an 8x8 bitmap font, `scale` pixels per font pixel, top left
    /// at (`x`, `y`). Characters outside Basic Latin show as `?`.
    pub fn text(&mut self, x: f32, y: f32, scale: f32, text: &str, color: [f32; 4]) {
        for (i, ch) in text.chars().enumerate() {
            let gx = x + i as f32 * 8.0 * scale;
            // Runs of set bits in a row, extended down while the rows below
            // have the same run: one rectangle each.
            let mut open: Vec<(u32, u32, usize, usize)> = Vec::new();
            let mut done = Vec::new();
            for (row, bits) in glyph(ch).iter().enumerate() {
                let runs = runs(*bits);
                let mut next = Vec::new();
                for r in runs {
                    match open.iter().position(|o| (o.0, o.1) == r) {
                        Some(k) => {
                            let mut o = open.remove(k);
                            o.3 = row + 1;
                            next.push(o);
                        }
                        None => next.push((r.0, r.1, row, row + 1)),
                    }
                }
                done.append(&mut open);
                open = next;
            }
            done.append(&mut open);
            for (c0, c1, r0, r1) in done {
                self.rect(
                    gx + c0 as f32 * scale,
                    y + r0 as f32 * scale,
                    (c1 - c0) as f32 * scale,
                    (r1 - r0) as f32 * scale,
                    color,
                );
            }
        }
    }
}

/// Runs of set bits (first, past-last column), leftmost bit first.
fn runs(bits: u8) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let mut col = 0;
    while col < 8 {
        if bits & (1 << col) == 0 {
            col += 1;
            continue;
        }
        let start = col;
        while col < 8 && bits & (1 << col) != 0 {
            col += 1;
        }
        out.push((start, col));
    }
    out
}

/// Width in pixels of `text` drawn at `scale`.
#[must_use]
pub fn text_width(text: &str, scale: f32) -> f32 {
    text.chars().count() as f32 * 8.0 * scale
}

fn glyph(ch: char) -> [u8; 8] {
    let code = if (ch as u32) < 128 {
        ch as usize
    } else {
        '?' as usize
    };
    font8x8::legacy::BASIC_LEGACY[code]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capsule_surface_lies_at_its_radius_from_the_segment() {
        let mut m = Mesh::default();
        let (a, b, r) = (Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.4, 1.0, -0.2), 0.07);
        m.capsule(a, b, r, [1.0; 4]);
        for v in &m.vertices {
            let p = Vec3::from(v.pos);
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            let d = (p - (a + (b - a) * t)).length();
            assert!((d - r).abs() < 1e-5, "{d}");
            assert!((Vec3::from(v.normal).length() - 1.0).abs() < 1e-5);
        }
        assert!(m.indices.iter().all(|&i| (i as usize) < m.vertices.len()));
    }

    #[test]
    fn text_draws_the_glyph_bits() {
        let mut o = Overlay::default();
        o.text(0.0, 0.0, 1.0, "I", [1.0; 4]);
        let lit: u32 = glyph('I').iter().map(|b| b.count_ones()).sum();
        let area: f32 = o
            .vertices
            .chunks(3)
            .map(|t| {
                let (a, b, c) = (t[0].pos, t[1].pos, t[2].pos);
                ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs() / 2.0
            })
            .sum();
        assert!((area - lit as f32).abs() < 1e-4);
    }
}

/// Everything one frame draws, in world and picture coordinates.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    /// World → clip, the output rotation folded in.
    pub view_proj: Mat4,
    /// Picture pixels → clip, the output rotation folded in.
    pub screen: Mat4,
    pub eye: Vec3,
    /// Unit vector towards the light.
    pub light: Vec3,
    /// Linear RGB of the background.
    pub background: [f32; 3],
    /// Distance (m) from the eye at which the floor starts fading.
    pub fog_start: f32,
    /// Draw the tiled floor and the character's shadow on it.
    pub floor: bool,
    /// Lit meshes: the character, or boxes.
    pub body: Mesh,
    /// Skinned figures, skinned as they are drawn.
    pub figures: Vec<SkinnedDraw>,
    /// What casts the shadow on the floor (a coarse body).
    pub shadow: Mesh,
    /// Marks, trajectories and text over the picture.
    pub overlay: Overlay,
}

/// A skinned vertex as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SkinVertex {
    /// Rest pose (m).
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    /// Linear RGB untinted...
    pub plain: [f32; 3],
    /// ...and tinted: `rgb + a * tint`.
    pub tinted: [f32; 4],
    pub joints: [u32; 4],
    pub weights: [f32; 4],
    /// The joint whose glow it shows.
    pub glow: u32,
}

/// One joint of a figure as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct JointGpu {
    /// Rest pose to posed (columns).
    pub skin: [[f32; 4]; 4],
    /// x: 1 where the joint glows; yzw: the figure's tint (its first
    /// joint's; y < 0: none).
    pub extra: [f32; 4],
}

/// A figure to draw this frame.
#[derive(Clone, Debug)]
pub struct SkinnedDraw {
    /// The triangles, shared with the figure (the renderer keeps them on
    /// the GPU while the figure is drawn).
    pub geometry: Arc<Geometry>,
    /// The own body (its clothes tinted as the capsule figure's are).
    pub own: bool,
    pub joints: Vec<JointGpu>,
    /// Balls (centre, radius; m) holding every posed vertex: the damage a
    /// frame can do.
    pub spheres: Vec<[f32; 4]>,
}
