//! The scene's render pipelines: lit bodies, the floor, the shadows,
//! the overlay and the skinned figures, from one shader and one colour
//! target.

use super::depth;
use crate::render::mesh::{Vertex2, Vertex3};
use crate::render::skinned;

/// Makes the scene's render pipelines: one shader, one colour target.
pub(super) struct Maker<'a> {
    pub(super) device: &'a wgpu::Device,
    pub(super) shader: &'a wgpu::ShaderModule,
    pub(super) format: wgpu::TextureFormat,
    pub(super) samples: u32,
}

impl Maker<'_> {
    /// The scene's pipelines on the globals' `layout`: lit bodies, the
    /// floor, the shadows (each pixel darkened once, by the stencil) and
    /// the overlay.
    pub(super) fn scene(&self, layout: &wgpu::BindGroupLayout) -> [wgpu::RenderPipeline; 4] {
        let pipeline_layout = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("scene"),
                bind_group_layouts: &[Some(layout)],
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
        let blend = Some(wgpu::BlendState::ALPHA_BLENDING);
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
        let lit = self.make(
            "lit",
            &pipeline_layout,
            ("vs_lit", "fs_lit"),
            v3.clone(),
            Some(wgpu::Face::Back),
            depth(true, wgpu::CompareFunction::Less, none.clone()),
            None,
        );
        let floor = self.make(
            "floor",
            &pipeline_layout,
            ("vs_lit", "fs_floor"),
            v3.clone(),
            None,
            depth(true, wgpu::CompareFunction::Less, none.clone()),
            None,
        );
        let shadow = self.make(
            "shadow",
            &pipeline_layout,
            ("vs_shadow", "fs_shadow"),
            v3,
            Some(wgpu::Face::Back),
            depth(false, wgpu::CompareFunction::LessEqual, shadow_stencil),
            blend,
        );
        let overlay = self.make(
            "overlay",
            &pipeline_layout,
            ("vs_overlay", "fs_overlay"),
            v2,
            None,
            depth(false, wgpu::CompareFunction::Always, none),
            blend,
        );
        [lit, floor, shadow, overlay]
    }

    /// The pipeline of skinned figures, skinning in the vertex shader from
    /// the figures' buffers (`figures`).
    pub(super) fn skinned(
        &self,
        layout: &wgpu::BindGroupLayout,
        figures: &wgpu::BindGroupLayout,
    ) -> wgpu::RenderPipeline {
        self.make(
            "skinned",
            &self
                .device
                .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("skinned"),
                    bind_group_layouts: &[Some(layout), Some(figures)],
                    immediate_size: 0,
                }),
            ("vs_skinned", "fs_lit"),
            skinned::VERTEX,
            Some(wgpu::Face::Back),
            depth(
                true,
                wgpu::CompareFunction::Less,
                wgpu::StencilState::default(),
            ),
            None,
        )
    }

    /// A pipeline of the shader's entry points `(vs, fs)`.
    #[allow(clippy::too_many_arguments)]
    fn make(
        &self,
        label: &str,
        pipeline_layout: &wgpu::PipelineLayout,
        (vs, fs): (&str, &str),
        layout: wgpu::VertexBufferLayout<'_>,
        cull: Option<wgpu::Face>,
        ds: wgpu::DepthStencilState,
        blend: Option<wgpu::BlendState>,
    ) -> wgpu::RenderPipeline {
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(pipeline_layout),
                vertex: wgpu::VertexState {
                    module: self.shader,
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
                    count: self.samples,
                    ..wgpu::MultisampleState::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: self.shader,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: self.format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    }
}
