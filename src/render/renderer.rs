//! The wgpu renderer: pipelines for the floor, the planar shadow, lit
//! meshes and 2-D overlays, drawing a [`DrawList`] into any colour target
//! (an offscreen texture for headless output and the KMS copy path, a
//! surface texture for direct display).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use super::gpu::Gpu;
use super::mesh::{Mesh, Overlay, Vertex2, Vertex3};

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
    /// Marks, trajectories and text over the picture.
    pub overlay: Overlay,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    shadow_view_proj: [[f32; 4]; 4],
    screen: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    fog: [f32; 4],
}

/// Flattens points onto the plane `y = h` along `light` (towards the light).
#[must_use]
pub fn planar_shadow(light: Vec3, h: f32) -> Mat4 {
    let ly = light.y.max(0.05);
    let (kx, kz) = (light.x / ly, light.z / ly);
    // x' = x - kx (y - h), y' = h, z' = z - kz (y - h).
    Mat4::from_cols(
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(-kx, 0.0, -kz, 0.0),
        Vec4::new(0.0, 0.0, 1.0, 0.0),
        Vec4::new(kx * h, h, kz * h, 1.0),
    )
}

/// A vertex or index buffer that grows when a frame needs more.
struct GrowBuffer {
    buffer: wgpu::Buffer,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        Self {
            buffer: Self::make(device, label, usage, 1 << 16),
            usage,
            label,
        }
    }

    fn make(
        device: &wgpu::Device,
        label: &str,
        usage: wgpu::BufferUsages,
        size: u64,
    ) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn write(&mut self, gpu: &Gpu, bytes: &[u8]) {
        let need = (bytes.len() as u64).next_multiple_of(4);
        if need > self.buffer.size() {
            self.buffer = Self::make(
                &gpu.device,
                self.label,
                self.usage,
                need.next_power_of_two(),
            );
        }
        if !bytes.is_empty() {
            let mut padded = bytes.to_vec();
            padded.resize(need as usize, 0);
            gpu.queue.write_buffer(&self.buffer, 0, &padded);
        }
    }
}

/// Depth-stencil and multisample attachments for one target size.
struct Attachments {
    size: (u32, u32),
    depth: wgpu::TextureView,
    msaa: Option<wgpu::TextureView>,
}

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;

/// Pipelines and buffers; one per colour format and sample count.
pub struct Renderer {
    format: wgpu::TextureFormat,
    samples: u32,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    lit: wgpu::RenderPipeline,
    floor: wgpu::RenderPipeline,
    shadow: wgpu::RenderPipeline,
    overlay: wgpu::RenderPipeline,
    floor_mesh: (wgpu::Buffer, wgpu::Buffer, u32),
    body_vertices: GrowBuffer,
    body_indices: GrowBuffer,
    overlay_vertices: GrowBuffer,
    attachments: Option<Attachments>,
}

/// Half-size of the floor square (m).
const FLOOR_HALF: f32 = 40.0;

impl Renderer {
    /// Pipelines drawing into `format` with up to `samples` samples per
    /// pixel (fewer when the adapter cannot).
    #[must_use]
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat, samples: u32) -> Self {
        let device = &gpu.device;
        let samples = gpu.sample_count(format, samples);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/scene.wgsl").into()),
        });
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let v3 = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex3>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4],
        };
        let v2 = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex2>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x4],
        };
        let depth = |write: bool, compare, stencil: wgpu::StencilState| wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil,
            bias: wgpu::DepthBiasState::default(),
        };
        let blend = Some(wgpu::BlendState::ALPHA_BLENDING);
        let make = |label: &str,
                    vs: &str,
                    fs: &str,
                    layout: wgpu::VertexBufferLayout<'_>,
                    cull: Option<wgpu::Face>,
                    ds: wgpu::DepthStencilState,
                    blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers: &[Some(layout)],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: cull,
                    ..wgpu::PrimitiveState::default()
                },
                depth_stencil: Some(ds),
                multisample: wgpu::MultisampleState {
                    count: samples,
                    ..wgpu::MultisampleState::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let once = wgpu::StencilFaceState {
            compare: wgpu::CompareFunction::Equal,
            fail_op: wgpu::StencilOperation::Keep,
            depth_fail_op: wgpu::StencilOperation::Keep,
            pass_op: wgpu::StencilOperation::IncrementClamp,
        };
        let shadow_stencil = wgpu::StencilState {
            front: once,
            back: once,
            read_mask: 0xff,
            write_mask: 0xff,
        };
        let none = wgpu::StencilState::default();
        let lit = make(
            "lit",
            "vs_lit",
            "fs_lit",
            v3.clone(),
            Some(wgpu::Face::Back),
            depth(true, wgpu::CompareFunction::Less, none.clone()),
            None,
        );
        let floor = make(
            "floor",
            "vs_lit",
            "fs_floor",
            v3.clone(),
            None,
            depth(true, wgpu::CompareFunction::Less, none.clone()),
            None,
        );
        let shadow = make(
            "shadow",
            "vs_shadow",
            "fs_shadow",
            v3,
            None,
            depth(false, wgpu::CompareFunction::LessEqual, shadow_stencil),
            blend,
        );
        let overlay = make(
            "overlay",
            "vs_overlay",
            "fs_overlay",
            v2,
            None,
            depth(false, wgpu::CompareFunction::Always, none),
            blend,
        );
        let mut ground = Mesh::default();
        ground.ground(FLOOR_HALF, 0.0, [0.62, 0.60, 0.56, 0.0]);
        let floor_vb = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("floor vertices"),
            size: std::mem::size_of_val(ground.vertices.as_slice()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&floor_vb, 0, bytemuck::cast_slice(&ground.vertices));
        let floor_ib = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("floor indices"),
            size: std::mem::size_of_val(ground.indices.as_slice()) as u64,
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&floor_ib, 0, bytemuck::cast_slice(&ground.indices));
        Self {
            format,
            samples,
            globals,
            bind_group,
            lit,
            floor,
            shadow,
            overlay,
            floor_mesh: (floor_vb, floor_ib, ground.indices.len() as u32),
            body_vertices: GrowBuffer::new(device, "body vertices", wgpu::BufferUsages::VERTEX),
            body_indices: GrowBuffer::new(device, "body indices", wgpu::BufferUsages::INDEX),
            overlay_vertices: GrowBuffer::new(
                device,
                "overlay vertices",
                wgpu::BufferUsages::VERTEX,
            ),
            attachments: None,
        }
    }

    /// Samples per pixel actually used.
    #[must_use]
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The colour format this renderer draws into.
    #[must_use]
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    fn attachments(&mut self, gpu: &Gpu, size: (u32, u32)) -> &Attachments {
        if self.attachments.as_ref().is_none_or(|a| a.size != size) {
            let texture = |label: &str, format| {
                gpu.device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width: size.0,
                            height: size.1,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: self.samples,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                        view_formats: &[],
                    })
                    .create_view(&wgpu::TextureViewDescriptor::default())
            };
            self.attachments = Some(Attachments {
                size,
                depth: texture("depth", DEPTH),
                msaa: (self.samples > 1).then(|| texture("multisample", self.format)),
            });
        }
        self.attachments.as_ref().expect("just made")
    }

    /// Record the frame into `encoder`, drawing into `target` of `size`.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        list: &DrawList,
    ) {
        let shadow = planar_shadow(list.light, 0.002);
        let globals = Globals {
            view_proj: list.view_proj.to_cols_array_2d(),
            shadow_view_proj: (list.view_proj * shadow).to_cols_array_2d(),
            screen: list.screen.to_cols_array_2d(),
            eye: list.eye.extend(1.0).to_array(),
            light: list.light.normalize().extend(0.0).to_array(),
            fog: [
                list.background[0],
                list.background[1],
                list.background[2],
                list.fog_start,
            ],
        };
        gpu.queue
            .write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        self.body_vertices
            .write(gpu, bytemuck::cast_slice(&list.body.vertices));
        self.body_indices
            .write(gpu, bytemuck::cast_slice(&list.body.indices));
        self.overlay_vertices
            .write(gpu, bytemuck::cast_slice(&list.overlay.vertices));
        let body_count = list.body.indices.len() as u32;
        let overlay_count = list.overlay.vertices.len() as u32;
        let bg = list.background;
        let att = self.attachments(gpu, size);
        let (view, resolve) = match &att.msaa {
            Some(m) => (m, Some(target)),
            None => (target, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: f64::from(bg[0]),
                        g: f64::from(bg[1]),
                        b: f64::from(bg[2]),
                        a: 1.0,
                    }),
                    store: if resolve.is_some() {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &att.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Discard,
                }),
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        if list.floor {
            pass.set_pipeline(&self.floor);
            pass.set_vertex_buffer(0, self.floor_mesh.0.slice(..));
            pass.set_index_buffer(self.floor_mesh.1.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.floor_mesh.2, 0, 0..1);
        }
        if body_count > 0 {
            pass.set_vertex_buffer(0, self.body_vertices.buffer.slice(..));
            pass.set_index_buffer(
                self.body_indices.buffer.slice(..),
                wgpu::IndexFormat::Uint32,
            );
            if list.floor {
                pass.set_pipeline(&self.shadow);
                pass.set_stencil_reference(0);
                pass.draw_indexed(0..body_count, 0, 0..1);
            }
            pass.set_pipeline(&self.lit);
            pass.draw_indexed(0..body_count, 0, 0..1);
        }
        if overlay_count > 0 {
            pass.set_pipeline(&self.overlay);
            pass.set_vertex_buffer(0, self.overlay_vertices.buffer.slice(..));
            pass.draw(0..overlay_count, 0..1);
        }
    }
}
