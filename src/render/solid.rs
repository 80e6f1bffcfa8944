//! Solids made of capsules, drawn as their surface: the body mesh and the
//! shadow leave out what cannot show.

use glam::Vec3;

use super::mesh::Mesh;

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

impl Mesh {
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
        let mut kept = from * 3;
        for i in (from * 3..self.indices.len()).step_by(3) {
            let t = [self.indices[i], self.indices[i + 1], self.indices[i + 2]];
            let [a, b, c] = t.map(|k| Vec3::from(v[k as usize].pos));
            if (b - a).cross(c - a).dot(towards) > 0.0 {
                self.indices[kept..kept + 3].copy_from_slice(&t);
                kept += 3;
            }
        }
        self.indices.truncate(kept);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::mesh::{AROUND, RINGS};

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
}
