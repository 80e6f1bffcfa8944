//! A figure's triangles as a renderer skins them: every part's rest-pose
//! vertices in one list, with smooth rest normals, colours, joints and
//! weights, the joint whose glow each vertex shows, and how far each
//! joint's vertices lie from it (so that the posed figure's bounds are
//! known without skinning it). Made once per figure; a frame only needs
//! the joints' skinning matrices.

use glam::DVec3;

use super::Figure;

/// The rest-pose mesh of a whole figure, its parts in one list.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub positions: Vec<[f32; 3]>,
    /// Smooth normals in the rest pose: each vertex's triangles, weighted
    /// by their area.
    pub normals: Vec<[f32; 3]>,
    /// Linear RGB: the vertex's texture colour, else its part's base
    /// colour.
    pub colours: Vec<[f32; 3]>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    /// The joint whose glow a vertex shows: its part's joint where the
    /// part shows one body part (the own body), else the joint carrying
    /// it most.
    pub glow_joint: Vec<u16>,
    pub indices: Vec<u32>,
    /// Per joint, the farthest a vertex it carries lies from it at rest
    /// (m; negative where it carries none). Skinning matrices are rigid,
    /// so a posed vertex lies within this of one of its joints' posed
    /// places.
    pub reach: Vec<f32>,
}

impl Geometry {
    #[must_use]
    pub fn new(fig: &Figure) -> Self {
        let mut g = Self {
            reach: vec![-1.0; fig.rest.len()],
            ..Self::default()
        };
        let rest_at: Vec<DVec3> = fig.rest.iter().map(|m| m.w_axis.truncate()).collect();
        for part in &fig.parts {
            let base = g.positions.len() as u32;
            let points: Vec<DVec3> = part
                .positions
                .iter()
                .map(|v| DVec3::new(v[0].into(), v[1].into(), v[2].into()))
                .collect();
            let mut normals = vec![DVec3::ZERO; points.len()];
            for t in part.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
                if a.max(b).max(c) >= points.len() {
                    continue;
                }
                let n = (points[b] - points[a]).cross(points[c] - points[a]);
                for i in [a, b, c] {
                    normals[i] += n;
                }
            }
            let role_joint = part.role.map(|r| fig.roles.get(r) as u16);
            for (i, (p, n)) in points.iter().zip(&normals).enumerate() {
                let j = part.joints.get(i).copied().unwrap_or([0; 4]);
                let w = part.weights.get(i).copied().unwrap_or([1.0, 0.0, 0.0, 0.0]);
                let c = part.colours.get(i).unwrap_or(&part.base_colour);
                let most = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
                for k in 0..4 {
                    let jk = usize::from(j[k]);
                    if w[k] > 0.0 && jk < rest_at.len() {
                        let d = (*p - rest_at[jk]).length() as f32;
                        g.reach[jk] = g.reach[jk].max(d);
                    }
                }
                g.positions.push(part.positions[i]);
                g.normals.push(n.normalize_or_zero().as_vec3().to_array());
                g.colours.push([c[0], c[1], c[2]]);
                g.joints.push(j);
                g.weights.push(w);
                g.glow_joint.push(role_joint.unwrap_or(j[most]));
            }
            g.indices.extend(part.indices.iter().map(|i| base + i));
        }
        g
    }
}
