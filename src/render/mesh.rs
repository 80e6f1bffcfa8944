//! CPU geometry for the renderer: the vertex formats the shaders read, and
//! meshes built from primitives (capsules, spheres, boxes, the floor, 2-D
//! overlay shapes). Pure; the scene builds them each frame and the renderer
//! uploads them.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

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

/// One capsule of a [`Mesh::capsule_union`]: the points within `r` of the
/// segment `a`–`b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapsulePart {
    pub a: Vec3,
    pub b: Vec3,
    pub r: f32,
    pub color: [f32; 4],
}

/// A capsule as [`Mesh::capsule_union`] tests points against it: the
/// sphere it lies in, its segment (`inv`: one over the squared length, 0
/// for a point), and the square of the radius its mesh surely holds.
struct Holder {
    centre: Vec3,
    reach: f32,
    reach2: f32,
    a: Vec3,
    ab: Vec3,
    inv: f32,
    holds2: f32,
}

impl Holder {
    /// Squared distance from `p` to the segment.
    fn to_segment2(&self, p: Vec3) -> f32 {
        let t = ((p - self.a).dot(self.ab) * self.inv).clamp(0.0, 1.0);
        p.distance_squared(self.a + self.ab * t)
    }
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
    fn base(&self) -> u32 {
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

    /// The surface of a solid made of capsules: each capsule tessellated
    /// like [`Mesh::capsule_with`], less the triangles that cannot show
    /// (those inside another of the capsules, and the slivers at the
    /// poles). Every ray from outside the solid meets the same first
    /// triangle as with all the capsules drawn, so the picture and the
    /// shadow are the same; a body loses about half its triangles.
    pub fn capsule_union(&mut self, parts: &[CapsulePart], around: usize, rings_per_end: usize) {
        let (around_n, rings_n) = (around.max(3), rings_per_end.max(1));
        // The tessellated capsule holds the true one shrunk by this much
        // (its faces are chords: around the axis and along each end).
        let holds = (std::f32::consts::PI / around_n as f32).cos()
            * (std::f32::consts::FRAC_PI_4 / rings_n as f32).cos()
            * 0.995;
        let holders: Vec<Holder> = parts
            .iter()
            .map(|c| {
                let ab = c.b - c.a;
                let reach = 0.5 * ab.length() + c.r * holds;
                Holder {
                    centre: 0.5 * (c.a + c.b),
                    reach,
                    reach2: reach * reach,
                    a: c.a,
                    ab,
                    inv: if ab.length_squared() > 0.0 {
                        ab.length_squared().recip()
                    } else {
                        0.0
                    },
                    holds2: (c.r * holds).powi(2),
                }
            })
            .collect();
        let mut one = Mesh::default();
        for (i, part) in parts.iter().enumerate() {
            one.vertices.clear();
            one.indices.clear();
            one.capsule_with(part.a, part.b, part.r, part.color, around_n, rings_n);
            // The capsules that may hold some of this one: this one's
            // surface comes within their reach.
            let this = &holders[i];
            let near: Vec<&Holder> = holders
                .iter()
                .enumerate()
                .filter(|&(j, h)| j != i && this.to_segment2(h.centre) < (h.reach + part.r).powi(2))
                .map(|(_, h)| h)
                .take(64)
                .collect();
            // Which of the near capsules hold each vertex (a bit each).
            let held_by: Vec<u64> = one
                .vertices
                .iter()
                .map(|v| {
                    let p = Vec3::from(v.pos);
                    let mut bits = 0;
                    for (k, h) in near.iter().enumerate() {
                        if p.distance_squared(h.centre) >= h.reach2 {
                            continue;
                        }
                        if h.to_segment2(p) < h.holds2 {
                            bits |= 1 << k;
                        }
                    }
                    bits
                })
                .collect();
            let mut remap = vec![u32::MAX; one.vertices.len()];
            for tri in one.indices.chunks_exact(3) {
                let [x, y, z] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                let [px, py, pz] = [x, y, z].map(|k| Vec3::from(one.vertices[k].pos));
                // A sliver at a pole (its corners there differ by rounding).
                let sliver =
                    (py - px).cross(pz - px).length_squared() < (1e-6 * part.r * part.r).powi(2);
                // Inside one capsule (it is convex) the whole triangle is.
                if held_by[x] & held_by[y] & held_by[z] != 0 || sliver {
                    continue;
                }
                for k in [x, y, z] {
                    if remap[k] == u32::MAX {
                        remap[k] = self.base();
                        self.vertices.push(one.vertices[k]);
                    }
                    self.indices.push(remap[k]);
                }
            }
        }
    }

    /// Leave out the triangles (counter-clockwise seen from the front)
    /// that face away from `towards`, from the triangle `from` on. A
    /// shadow flattened along the light keeps only those facing it: the
    /// others would be turned over and culled after the vertex work.
    pub fn keep_facing(&mut self, towards: Vec3, from: usize) {
        let v = &self.vertices;
        let kept: Vec<u32> = self.indices[from * 3..]
            .chunks_exact(3)
            .filter(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(v[t[k] as usize].pos));
                (b - a).cross(c - a).dot(towards) > 0.0
            })
            .flatten()
            .copied()
            .collect();
        self.indices.truncate(from * 3);
        self.indices.extend(kept);
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

    /// The nearest triangle a ray meets (Möller–Trumbore), front faces
    /// only (the renderer culls back faces).
    fn first_hit(m: &Mesh, from: Vec3, dir: Vec3) -> Option<f32> {
        m.indices
            .chunks_exact(3)
            .filter_map(|t| {
                let [p0, p1, p2] = [0, 1, 2].map(|k| Vec3::from(m.vertices[t[k] as usize].pos));
                let (e1, e2) = (p1 - p0, p2 - p0);
                if e1.cross(e2).dot(dir) >= 0.0 {
                    return None;
                }
                let h = dir.cross(e2);
                let det = e1.dot(h);
                let s = (from - p0) / det;
                let u = s.dot(h);
                let q = s.cross(e1);
                let v = dir.dot(q);
                let t = e2.dot(q);
                (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
            })
            .min_by(f32::total_cmp)
    }

    #[test]
    fn a_capsule_union_shows_what_all_its_capsules_show_with_fewer_triangles() {
        // An arm bent at the elbow into a wider shoulder, a mitten wider
        // than the forearm, a sphere half sunk into the upper arm.
        let c = |a: [f32; 3], b: [f32; 3], r: f32| CapsulePart {
            a: Vec3::from(a),
            b: Vec3::from(b),
            r,
            color: [r; 4],
        };
        let parts = [
            c([0.0, 0.0, 0.0], [0.2, 0.0, 0.0], 0.075),
            c([0.2, 0.0, 0.0], [0.45, -0.1, 0.05], 0.056),
            c([0.45, -0.1, 0.05], [0.5, 0.15, 0.1], 0.045),
            c([0.5, 0.15, 0.1], [0.52, 0.22, 0.1], 0.047),
            c([0.3, 0.05, 0.0], [0.3, 0.05, 0.0], 0.05),
        ];
        let mut all = Mesh::default();
        for p in &parts {
            all.capsule(p.a, p.b, p.r, p.color);
        }
        let mut union = Mesh::default();
        union.capsule_union(&parts, AROUND, RINGS);
        assert!(
            union
                .indices
                .iter()
                .all(|&i| (i as usize) < union.vertices.len())
        );
        let (kept, before) = (union.indices.len() / 3, all.indices.len() / 3);
        assert!(kept * 10 < before * 7, "{kept} of {before} triangles kept");
        // Rays from all round, aimed at points near the arm, meet the same
        // surface (a triangle left out would leave a hole, one too many is
        // harmless but costs).
        let mut hits = 0;
        for k in 0..400 {
            let f = k as f32;
            let (theta, phi) = (f * 2.399_963, (f * 0.618_034).fract() * 2.0 - 1.0);
            let from = Vec3::new(
                theta.cos() * phi.acos().sin(),
                phi,
                theta.sin() * phi.acos().sin(),
            ) * 2.0
                + Vec3::new(0.25, 0.0, 0.05);
            let aim = Vec3::new(
                0.55 * (f * 0.377).fract() - 0.02,
                0.4 * (f * 0.731).fract() - 0.15,
                0.2 * (f * 0.513).fract() - 0.05,
            );
            let dir = (aim - from).normalize();
            let (a, b) = (first_hit(&all, from, dir), first_hit(&union, from, dir));
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() < 1e-4, "ray {k}: {a} against {b}");
                    hits += 1;
                }
                (None, None) => {}
                _ => panic!("ray {k}: {a:?} against {b:?}"),
            }
        }
        assert!(hits > 200, "{hits} rays met the arm");
    }

    #[test]
    fn keep_facing_leaves_the_half_that_faces_the_light() {
        let mut m = Mesh::default();
        m.cuboid(Vec3::ZERO, Vec3::splat(1.0), [1.0; 4]);
        let before = m.indices.len();
        m.capsule_union(
            &[CapsulePart {
                a: Vec3::ZERO,
                b: Vec3::X,
                r: 0.5,
                color: [1.0; 4],
            }],
            AROUND,
            RINGS,
        );
        let n = m.indices.len() / 3;
        m.keep_facing(Vec3::new(0.3, 1.0, 0.2), before / 3);
        let kept = m.indices.len() / 3 - before / 3;
        assert!(kept * 5 > (n - before / 3) * 2 && kept * 5 < (n - before / 3) * 3);
        // The box before `from` stays whole; what is left faces up, its
        // outward normals (the vertices') agree.
        assert_eq!(m.indices.len() - kept * 3, before);
        for t in m.indices[before..].chunks_exact(3) {
            let normal: Vec3 = t
                .iter()
                .map(|&i| Vec3::from(m.vertices[i as usize].normal))
                .sum();
            assert!(normal.dot(Vec3::new(0.3, 1.0, 0.2)) > -0.3, "{normal}");
        }
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
    /// What casts the shadow on the floor (a coarse body).
    pub shadow: Mesh,
    /// Marks, trajectories and text over the picture.
    pub overlay: Overlay,
}
