//! Skinned figures: each figure's triangles uploaded once and kept while
//! it is drawn. On a GPU its vertices are kept too and every frame's joints
//! go into one storage buffer (a figure's first joint passed as its
//! instance index), skinned by the `vs_skinned` pipeline. On a CPU
//! renderer (lavapipe) the vertex stage runs on one thread and skinning
//! there cost more than skinning before it (CesiumMan 0.8 ms a frame at
//! 1280x720), so the vertices are skinned on the CPU and
//! drawn as lit meshes ([`skin_on_cpu`]); either way they come out the same.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::gpu::{Gpu, GrowBuffer};
use super::mesh::{DrawList, JointGpu, SkinVertex, Vertex3};
use crate::character::gltf::Geometry;

/// A figure's buffers on the GPU.
struct Uploaded {
    geometry: Arc<Geometry>,
    /// On the GPU (skinned there), or kept here (skinned here).
    vertices: Result<wgpu::Buffer, Vec<SkinVertex>>,
    indices: wgpu::Buffer,
}

impl Uploaded {
    /// The buffers of `geometry` (the project's own body when `own`), its
    /// vertices on the GPU when skinned there (`on_gpu`), else kept here.
    fn new(gpu: &Gpu, geometry: &Arc<Geometry>, own: bool, on_gpu: bool) -> Self {
        // A buffer past the device's largest is said and left empty (the
        // figure's size is bounded where it is read: this is not reached
        // from a file marionette loads).
        let buffer = |label, usage, bytes: &[u8]| {
            let bytes = if gpu.holds(label, bytes.len() as u64) {
                bytes
            } else {
                &[]
            };
            gpu.filled_buffer(label, usage, bytes)
        };
        let v = vertices(geometry, own);
        Self {
            geometry: Arc::clone(geometry),
            vertices: if on_gpu {
                Ok(buffer(
                    "figure vertices",
                    wgpu::BufferUsages::VERTEX,
                    bytemuck::cast_slice(&v),
                ))
            } else {
                Err(v)
            },
            indices: buffer(
                "figure indices",
                wgpu::BufferUsages::INDEX,
                bytemuck::cast_slice(&geometry.indices),
            ),
        }
    }
}

/// The skinned figures' buffers.
pub(super) struct Figures {
    layout: wgpu::BindGroupLayout,
    /// Skin in the vertex shader (else on the CPU).
    pub(super) on_gpu: bool,
    joints: GrowBuffer,
    /// Vertices skinned on the CPU this frame.
    skinned: GrowBuffer,
    /// The joints' bind group, and the buffer size it was made for.
    bind: Option<(wgpu::BindGroup, u64)>,
    uploaded: Vec<Uploaded>,
    /// This frame's draws: index into `uploaded`, and its first joint (on
    /// the GPU) or first vertex in `skinned` (on the CPU).
    draws: Vec<(usize, u32)>,
}

/// The vertex layout of [`SkinVertex`].
pub(super) const VERTEX: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<SkinVertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x4,
        4 => Uint32x4, 5 => Float32x4, 6 => Uint32
    ],
};

impl Figures {
    pub(super) fn new(device: &wgpu::Device, on_gpu: bool) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("joints"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        Self {
            layout,
            on_gpu,
            joints: GrowBuffer::new(device, "joints", wgpu::BufferUsages::STORAGE),
            skinned: GrowBuffer::new(device, "skinned vertices", wgpu::BufferUsages::VERTEX),
            bind: None,
            uploaded: Vec::new(),
            draws: Vec::new(),
        }
    }

    /// The bind group layout of the joints (group 1 of the pipeline).
    pub(super) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Upload this frame's joints, and the vertices of figures not yet on
    /// the GPU; figures not drawn this frame are let go.
    pub(super) fn upload(&mut self, gpu: &Gpu, list: &DrawList) {
        let device = &gpu.device;
        let on_gpu = self.on_gpu;
        // A figure's geometry is made once (by `Skin::new`): the same one
        // is the same figure, own body or not.
        self.uploaded.retain(|u| {
            u.vertices.is_ok() == on_gpu
                && list
                    .figures
                    .iter()
                    .any(|f| Arc::ptr_eq(&f.geometry, &u.geometry))
        });
        self.draws.clear();
        let mut joints: Vec<JointGpu> = Vec::new();
        let mut skinned = Vec::new();
        for f in &list.figures {
            let k = match self
                .uploaded
                .iter()
                .position(|u| Arc::ptr_eq(&f.geometry, &u.geometry))
            {
                Some(k) => k,
                None => {
                    self.uploaded
                        .push(Uploaded::new(gpu, &f.geometry, f.own, on_gpu));
                    self.uploaded.len() - 1
                }
            };
            match &self.uploaded[k].vertices {
                Ok(_) => {
                    self.draws.push((k, joints.len() as u32));
                    joints.extend_from_slice(&f.joints);
                }
                Err(v) => {
                    self.draws.push((k, skinned.len() as u32));
                    skin_on_cpu(v, &f.joints, &mut skinned);
                }
            }
        }
        if !skinned.is_empty() {
            self.skinned.write(gpu, bytemuck::cast_slice(&skinned));
        }
        if joints.is_empty() {
            return;
        }
        self.joints.write(gpu, bytemuck::cast_slice(&joints));
        let size = self.joints.buffer.size();
        if self.bind.as_ref().is_none_or(|b| b.1 != size) {
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("joints"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.joints.buffer.as_entire_binding(),
                }],
            });
            self.bind = Some((group, size));
        }
    }

    /// Draw this frame's figures with `skinning` (the `vs_skinned`
    /// pipeline) or `lit` (vertices skinned here); group 0 bound.
    pub(super) fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        skinning: Option<&wgpu::RenderPipeline>,
        lit: &wgpu::RenderPipeline,
    ) {
        if self.draws.is_empty() {
            return;
        }
        if self.on_gpu {
            let (Some((group, _)), Some(skinning)) = (&self.bind, skinning) else {
                return;
            };
            pass.set_pipeline(skinning);
            pass.set_bind_group(1, group, &[]);
        } else {
            pass.set_pipeline(lit);
            pass.set_vertex_buffer(0, self.skinned.buffer.slice(..));
        }
        for &(k, base) in &self.draws {
            let u = &self.uploaded[k];
            let count = u.geometry.indices.len() as u32;
            pass.set_index_buffer(u.indices.slice(..), wgpu::IndexFormat::Uint32);
            match &u.vertices {
                Ok(v) => {
                    pass.set_vertex_buffer(0, v.slice(..));
                    pass.draw_indexed(0..count, 0, base..base + 1);
                }
                Err(_) => pass.draw_indexed(0..count, base as i32, 0..1),
            }
        }
    }
}

/// The vertices of `g` as uploaded: the own body's clothes take the tint
/// as the capsule figure's do (`scene::tinted`, linear in the tint), any
/// other figure is blended half and half with it.
#[must_use]
pub fn vertices(g: &Geometry, own: bool) -> Vec<SkinVertex> {
    (0..g.positions.len())
        .map(|i| {
            let rgb = g.colours[i];
            let (c0, k) = if own {
                let c0 = super::scene::tinted(rgb, [0.0; 3]);
                (c0, super::scene::tinted(rgb, [1.0; 3])[0] - c0[0])
            } else {
                (rgb.map(|c| 0.5 * c), 0.5)
            };
            SkinVertex {
                pos: g.positions[i],
                normal: g.normals[i],
                plain: rgb,
                tinted: [c0[0], c0[1], c0[2], k],
                joints: g.joints[i].map(u32::from),
                weights: g.weights[i],
                glow: u32::from(g.glow_joint[i]),
            }
        })
        .collect()
}

/// What `vs_skinned` does, on the CPU: `vertices` skinned by `joints`
/// (their tint and glow) into lit vertices appended to `out`.
pub fn skin_on_cpu(vertices: &[SkinVertex], joints: &[JointGpu], out: &mut Vec<Vertex3>) {
    let Some(first) = joints.first() else {
        return;
    };
    let mats: Vec<Mat4> = joints
        .iter()
        .map(|j| Mat4::from_cols_array_2d(&j.skin))
        .collect();
    let tint = first.extra;
    let joint = |k: u32| mats.get(k as usize).copied().unwrap_or(Mat4::IDENTITY);
    out.extend(vertices.iter().map(|v| {
        let w = v.weights;
        let m = joint(v.joints[0]) * w[0]
            + joint(v.joints[1]) * w[1]
            + joint(v.joints[2]) * w[2]
            + joint(v.joints[3]) * w[3];
        let rgb = if tint[1] >= 0.0 {
            [0, 1, 2].map(|c| v.tinted[c] + v.tinted[3] * tint[c + 1])
        } else {
            v.plain
        };
        let glow = joints.get(v.glow as usize).map_or(0.0, |j| j.extra[0]);
        Vertex3 {
            pos: m.transform_point3(Vec3::from(v.pos)).to_array(),
            normal: m
                .transform_vector3(Vec3::from(v.normal))
                .normalize_or_zero()
                .to_array(),
            color: [rgb[0], rgb[1], rgb[2], glow],
        }
    }));
}
