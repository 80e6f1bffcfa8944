//! The wgpu renderer: pipelines for the floor, the planar shadow, lit
//! meshes, skinned figures (`skinned`) and 2-D overlays, drawing a [`DrawList`] into any colour target
//! (an offscreen texture for headless output and the KMS copy path, a
//! surface texture for direct display).

mod pipelines;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use self::pipelines::Maker;
use super::damage::{Damage, Rect, damage};
use super::gpu::{Gpu, GrowBuffer};
use super::mesh::{DrawList, Mesh};
use super::skinned::Figures;

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

/// A render pass into `color` (resolved into `color.1` when multisampled;
/// the multisampled image is then not kept), with a cleared depth-stencil
/// that is not kept either.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: (&wgpu::TextureView, Option<&wgpu::TextureView>),
    load: wgpu::LoadOp<wgpu::Color>,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color.0,
            depth_slice: None,
            resolve_target: color.1,
            ops: wgpu::Operations {
                load,
                store: if color.1.is_some() {
                    wgpu::StoreOp::Discard
                } else {
                    wgpu::StoreOp::Store
                },
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
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
    })
}

fn clear(bg: [f32; 3]) -> wgpu::Color {
    wgpu::Color {
        r: f64::from(bg[0]),
        g: f64::from(bg[1]),
        b: f64::from(bg[2]),
        a: 1.0,
    }
}

/// The floor as last drawn, reused while the view does not change (on
/// single-sampled targets the floor is most of a frame's cost on a CPU
/// renderer; the camera is still most of the time).
struct FloorCache {
    key: Vec<u8>,
    texture: wgpu::Texture,
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
    /// Skinning in the vertex shader, where the adapter can.
    skinned: Option<wgpu::RenderPipeline>,
    figures: Figures,
    floor_mesh: (wgpu::Buffer, wgpu::Buffer, u32),
    body_vertices: GrowBuffer,
    body_indices: GrowBuffer,
    shadow_vertices: GrowBuffer,
    shadow_indices: GrowBuffer,
    overlay_vertices: GrowBuffer,
    attachments: Option<Attachments>,
    floor_cache: Option<FloorCache>,
    /// The target last drawn with the floor cache, and what was drawn over
    /// the floor there.
    last: Option<(wgpu::Texture, Damage)>,
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
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/scene.wgsl").into()),
        });
        let (globals, layout, bind_group) = globals(device);
        let maker = Maker {
            device,
            shader: &shader,
            format,
            samples,
        };
        let [lit, floor, shadow, overlay] = maker.scene(&layout);
        // Skinning in the vertex shader needs storage buffers read there
        // (every Vulkan GPU does); the default where the adapter is a GPU.
        let vertex_storage = gpu
            .adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::VERTEX_STORAGE);
        let figures = Figures::new(device, !gpu.is_cpu() && vertex_storage);
        let skinned = vertex_storage.then(|| maker.skinned(&layout, figures.layout()));
        Self {
            format,
            samples,
            globals,
            bind_group,
            lit,
            floor,
            shadow,
            overlay,
            skinned,
            figures,
            floor_mesh: floor_mesh(gpu),
            body_vertices: GrowBuffer::new(device, "body vertices", wgpu::BufferUsages::VERTEX),
            body_indices: GrowBuffer::new(device, "body indices", wgpu::BufferUsages::INDEX),
            shadow_vertices: GrowBuffer::new(device, "shadow vertices", wgpu::BufferUsages::VERTEX),
            shadow_indices: GrowBuffer::new(device, "shadow indices", wgpu::BufferUsages::INDEX),
            overlay_vertices: GrowBuffer::new(
                device,
                "overlay vertices",
                wgpu::BufferUsages::VERTEX,
            ),
            attachments: None,
            floor_cache: None,
            last: None,
        }
    }

    /// Copy the floor for this view into `target`, drawing it first when
    /// the view changed.
    fn floor_into(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::Texture,
        key: Vec<u8>,
        bg: [f32; 3],
        damage: Damage,
    ) -> Rect {
        let size = (target.width(), target.height());
        // Everything is new when the view or the target changed; else only
        // where the characters and overlays are and were.
        let mut region = match &self.last {
            Some((t, last)) if t == target => damage.union(last),
            _ => Damage::all(size),
        };
        if self.floor_cache.as_ref().is_none_or(|c| c.key != key) {
            region = Damage::all(size);
            let texture = match self.floor_cache.take() {
                Some(c) if (c.texture.width(), c.texture.height()) == size => c.texture,
                _ => gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("floor cache"),
                    size: target.size(),
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: self.format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                }),
            };
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let depth = &self.attachments(gpu, size).depth;
            let mut pass = begin_pass(
                encoder,
                "floor",
                (&view, None),
                wgpu::LoadOp::Clear(clear(bg)),
                depth,
            );
            pass.set_bind_group(0, &self.bind_group, &[]);
            self.draw_floor(&mut pass);
            drop(pass);
            self.floor_cache = Some(FloorCache { key, texture });
        }
        let cache = &self.floor_cache.as_ref().expect("just drawn").texture;
        for rect in region.rects() {
            let origin = wgpu::Origin3d {
                x: rect.x0,
                y: rect.y0,
                z: 0,
            };
            encoder.copy_texture_to_texture(
                wgpu::TexelCopyTextureInfo {
                    origin,
                    ..cache.as_image_copy()
                },
                wgpu::TexelCopyTextureInfo {
                    origin,
                    ..target.as_image_copy()
                },
                wgpu::Extent3d {
                    width: rect.x1 - rect.x0,
                    height: rect.y1 - rect.y0,
                    depth_or_array_layers: 1,
                },
            );
        }
        self.last = Some((target.clone(), damage));
        region.bounds()
    }

    fn draw_floor(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.floor);
        pass.set_vertex_buffer(0, self.floor_mesh.0.slice(..));
        pass.set_index_buffer(self.floor_mesh.1.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.floor_mesh.2, 0, 0..1);
    }

    /// Whether figures are skinned in the vertex shader.
    #[must_use]
    pub fn gpu_skinning(&self) -> bool {
        self.figures.on_gpu
    }

    /// Skin figures in the vertex shader (the default on a GPU; where the
    /// adapter can) or on the CPU (the default on a CPU renderer); both
    /// draw the same.
    pub fn set_gpu_skinning(&mut self, on: bool) {
        self.figures.on_gpu = on && self.skinned.is_some();
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

    /// The frame's uniforms and geometry to the GPU.
    fn upload(&mut self, gpu: &Gpu, list: &DrawList, globals: &Globals) {
        gpu.queue
            .write_buffer(&self.globals, 0, bytemuck::bytes_of(globals));
        self.body_vertices
            .write(gpu, bytemuck::cast_slice(&list.body.vertices));
        self.body_indices
            .write(gpu, bytemuck::cast_slice(&list.body.indices));
        self.overlay_vertices
            .write(gpu, bytemuck::cast_slice(&list.overlay.vertices));
        self.shadow_vertices
            .write(gpu, bytemuck::cast_slice(&list.shadow.vertices));
        self.shadow_indices
            .write(gpu, bytemuck::cast_slice(&list.shadow.indices));
        self.figures.upload(gpu, list);
    }

    /// Record the frame into `encoder`, drawing into `target` (which
    /// needs `RENDER_ATTACHMENT`, and `COPY_DST` for the floor cache).
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::Texture,
        list: &DrawList,
    ) {
        let size = (target.width(), target.height());
        let target_view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let target = (target, &target_view);
        let shadow = planar_shadow(list.light, 0.002);
        let globals = Globals::of(list, shadow);
        self.upload(gpu, list, &globals);
        let shadow_count = list.shadow.indices.len() as u32;
        let body_count = list.body.indices.len() as u32;
        let overlay_count = list.overlay.vertices.len() as u32;
        let bg = list.background;
        let cached_floor = list.floor
            && self.samples == 1
            && target.0.usage().contains(wgpu::TextureUsages::COPY_DST);
        let scissor = if cached_floor {
            let mut key = bytemuck::bytes_of(&globals).to_vec();
            key.extend_from_slice(bytemuck::cast_slice(&[size.0, size.1]));
            let damage = damage(list, list.view_proj * shadow, size);
            Some(self.floor_into(gpu, encoder, target.0, key, bg, damage))
        } else {
            self.last = None;
            None
        };
        let att = self.attachments(gpu, size);
        let target = target.1;
        let (view, resolve) = match &att.msaa {
            Some(m) => (m, Some(target)),
            None => (target, None),
        };
        let load = if cached_floor {
            wgpu::LoadOp::Load
        } else {
            wgpu::LoadOp::Clear(clear(bg))
        };
        let mut pass = begin_pass(encoder, "scene", (view, resolve), load, &att.depth);
        pass.set_bind_group(0, &self.bind_group, &[]);
        if let Some(r) = scissor {
            if r.is_empty() {
                return;
            }
            pass.set_scissor_rect(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
        }
        if list.floor && !cached_floor {
            self.draw_floor(&mut pass);
        }
        if list.floor && shadow_count > 0 {
            pass.set_pipeline(&self.shadow);
            pass.set_stencil_reference(0);
            pass.set_vertex_buffer(0, self.shadow_vertices.buffer.slice(..));
            pass.set_index_buffer(
                self.shadow_indices.buffer.slice(..),
                wgpu::IndexFormat::Uint32,
            );
            pass.draw_indexed(0..shadow_count, 0, 0..1);
        }
        if body_count > 0 {
            pass.set_vertex_buffer(0, self.body_vertices.buffer.slice(..));
            pass.set_index_buffer(
                self.body_indices.buffer.slice(..),
                wgpu::IndexFormat::Uint32,
            );
            pass.set_pipeline(&self.lit);
            pass.draw_indexed(0..body_count, 0, 0..1);
        }
        if !list.figures.is_empty() {
            self.figures
                .draw(&mut pass, self.skinned.as_ref(), &self.lit);
        }
        if overlay_count > 0 {
            pass.set_pipeline(&self.overlay);
            pass.set_vertex_buffer(0, self.overlay_vertices.buffer.slice(..));
            pass.draw(0..overlay_count, 0..1);
        }
    }
}
impl Globals {
    /// The uniforms of `list`, its shadows cast by `shadow`.
    fn of(list: &DrawList, shadow: glam::Mat4) -> Self {
        Self {
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
        }
    }
}

/// The scene's uniforms: their buffer, its layout and its bind group.
fn globals(device: &wgpu::Device) -> (wgpu::Buffer, wgpu::BindGroupLayout, wgpu::BindGroup) {
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
    (globals, layout, bind_group)
}

/// The floor's vertices and indices on the GPU, and how many indices.
fn floor_mesh(gpu: &Gpu) -> (wgpu::Buffer, wgpu::Buffer, u32) {
    let mut ground = Mesh::default();
    ground.ground(FLOOR_HALF, 0.0, [0.62, 0.60, 0.56, 0.0]);
    let floor_vb = gpu.filled_buffer(
        "floor vertices",
        wgpu::BufferUsages::VERTEX,
        bytemuck::cast_slice(&ground.vertices),
    );
    let floor_ib = gpu.filled_buffer(
        "floor indices",
        wgpu::BufferUsages::INDEX,
        bytemuck::cast_slice(&ground.indices),
    );
    (floor_vb, floor_ib, ground.indices.len() as u32)
}

/// The depth test (and stencil) of a pipeline.
fn depth(
    write: bool,
    compare: wgpu::CompareFunction,
    stencil: wgpu::StencilState,
) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil,
        bias: wgpu::DepthBiasState::default(),
    }
}
