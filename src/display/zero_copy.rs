//! Zero copy: gbm's scanout buffers imported into Vulkan as the renderer's
//! targets (each buffer's dma-buf with its modifier, offset and stride,
//! through VK_EXT_external_memory_dma_buf and
//! VK_EXT_image_drm_format_modifier, wrapped as wgpu textures through
//! wgpu's hal), so frames are drawn straight into the buffer the display
//! engine scans out: no read-back, no copy on the CPU.

use std::path::Path;

use drm::control::crtc;

use ash::vk;
use wgpu::hal::api::Vulkan;

use super::error::PresentError;
use super::gbm::{DmaBuf, GbmBuffers};
use super::modifiers;
use crate::platform::kms::Card;
use crate::render::gpu::{AdapterChoice, Gpu, GpuError};
use crate::render::mesh::DrawList;
use crate::render::renderer::Renderer;

/// XRGB8888 as Vulkan and wgpu see it (little-endian B, G, R, X), with the
/// renderer's sRGB encoding.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Bgra8UnormSrgb;
const VK_FORMAT: vk::Format = vk::Format::B8G8R8A8_SRGB;

/// The device extensions zero copy needs.
const EXTENSIONS: [&std::ffi::CStr; 3] = [
    ash::khr::external_memory_fd::NAME,
    ash::ext::external_memory_dma_buf::NAME,
    ash::ext::image_drm_format_modifier::NAME,
];

/// The single-plane modifiers `gpu` can render XRGB8888 into (as a colour
/// target that is also copied into), or why it cannot import scanout
/// buffers at all (the missing extensions by name).
pub fn renderable_modifiers(gpu: &Gpu) -> Result<Vec<u64>, String> {
    // SAFETY: the hal adapter is only read from, while `gpu` holds it.
    let Some(adapter) = (unsafe { gpu.adapter.as_hal::<Vulkan>() }) else {
        return Err(format!("{} is not a Vulkan adapter", gpu.info.name));
    };
    let caps = adapter.physical_device_capabilities();
    let missing: Vec<&str> = EXTENSIONS
        .iter()
        .filter(|e| !caps.supports_extension(e))
        .map(|e| e.to_str().unwrap_or("?"))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "{} ({} {}) does not offer {}",
            gpu.info.name,
            gpu.info.driver,
            gpu.info.driver_info,
            missing.join(", ")
        ));
    }
    if !gpu
        .device
        .features()
        .contains(wgpu::Features::VULKAN_EXTERNAL_MEMORY_DMA_BUF)
    {
        return Err(format!(
            "the device on {} was opened without dma-buf import",
            gpu.info.name
        ));
    }
    let instance = adapter.shared_instance().raw_instance();
    let physical = adapter.raw_physical_device();
    let mut count = vk::DrmFormatModifierPropertiesListEXT::default();
    let mut props = vk::FormatProperties2::default().push_next(&mut count);
    // SAFETY: `physical` belongs to `instance`; the chain is well formed.
    unsafe { instance.get_physical_device_format_properties2(physical, VK_FORMAT, &mut props) };
    // Bounded: a driver lists a handful of layouts per format.
    let n = count.drm_format_modifier_count.min(256) as usize;
    let mut list = vec![vk::DrmFormatModifierPropertiesEXT::default(); n];
    let mut listed =
        vk::DrmFormatModifierPropertiesListEXT::default().drm_format_modifier_properties(&mut list);
    let mut props = vk::FormatProperties2::default().push_next(&mut listed);
    // SAFETY: as above; `list` has room for the count just read.
    unsafe { instance.get_physical_device_format_properties2(physical, VK_FORMAT, &mut props) };
    let n = (listed.drm_format_modifier_count as usize).min(n);
    let needs = vk::FormatFeatureFlags::COLOR_ATTACHMENT | vk::FormatFeatureFlags::TRANSFER_DST;
    Ok(list[..n]
        .iter()
        .filter(|m| {
            m.drm_format_modifier_plane_count == 1
                && m.drm_format_modifier_tiling_features.contains(needs)
        })
        .map(|m| m.drm_format_modifier)
        .collect())
}

/// gbm buffers the GPU renders into, in a layout the output's primary
/// plane and the Vulkan driver both take, imported into a renderer; where
/// that cannot be, why (the missing extension, the layouts each offers,
/// the driver's refusal).
pub(crate) fn open(
    card: &Card,
    path: &Path,
    crtc: crtc::Handle,
    (w, h): (u16, u16),
    adapter: AdapterChoice,
    samples: u32,
) -> Result<(GbmBuffers, Imported), PresentError> {
    let refused = |why: String| PresentError::ZeroCopy {
        path: path.to_owned(),
        why,
    };
    let gpu = Gpu::new(adapter)?;
    let renderable = renderable_modifiers(&gpu).map_err(refused)?;
    let plane = modifiers::primary_plane_modifiers(card, crtc);
    let chosen = modifiers::choose(plane.as_deref(), &renderable);
    let names = |m: &[u64]| {
        m.iter()
            .map(|m| modifiers::name(*m))
            .collect::<Vec<_>>()
            .join(", ")
    };
    tracing::debug!(
        plane = %plane.as_deref().map_or_else(|| "not listed (linear)".to_owned(), names),
        renderer = %names(&renderable),
        chosen = %names(&chosen),
        "scanout buffer layouts"
    );
    if chosen.is_empty() {
        return Err(refused(format!(
            "no buffer layout both the display plane ({}) and {} ({}) take",
            plane.as_deref().map_or_else(|| "linear".to_owned(), names),
            gpu.info.name,
            names(&renderable)
        )));
    }
    let buffers = GbmBuffers::allocate(card, path, u32::from(w), u32::from(h), &chosen)?;
    let imported =
        Imported::new(gpu, card, &buffers, u32::from(w), u32::from(h), samples).map_err(refused)?;
    Ok((buffers, imported))
}

/// The renderer drawing into the imported buffers.
pub struct Imported {
    pub gpu: Gpu,
    renderer: Renderer,
    targets: Vec<wgpu::Texture>,
    samples: u32,
}

impl Imported {
    /// Import every buffer of `buffers` (`w` x `h`) into `gpu` and make a
    /// renderer for them with up to `samples` samples per pixel (0: 4 on
    /// a GPU, 1 on a CPU renderer); why not, where the driver refuses.
    pub fn new(
        gpu: Gpu,
        card: &Card,
        buffers: &GbmBuffers,
        w: u32,
        h: u32,
        samples: u32,
    ) -> Result<Self, String> {
        let mut targets = Vec::new();
        for i in 0..buffers.bos.len() {
            let dmabuf = buffers
                .dmabuf(card, i)
                .map_err(|e| format!("exporting gbm buffer {i} as a dma-buf: {e}"))?;
            targets.push(import(&gpu, dmabuf, w, h)?);
        }
        let samples = match samples {
            0 if gpu.is_cpu() => 1,
            0 => 4,
            n => n,
        };
        let renderer = Renderer::new(&gpu, FORMAT, samples);
        Ok(Self {
            gpu,
            renderer,
            targets,
            samples,
        })
    }

    /// The same buffers imported into a new device (after the old one was
    /// lost).
    pub fn rebuild(&mut self, gpu: Gpu, card: &Card, buffers: &GbmBuffers) -> Result<(), String> {
        let (w, h) = (self.targets[0].width(), self.targets[0].height());
        *self = Self::new(gpu, card, buffers, w, h, self.samples)?;
        Ok(())
    }

    /// Samples per pixel the renderer draws with.
    #[must_use]
    pub fn samples(&self) -> u32 {
        self.renderer.samples()
    }

    /// Draw `list` into buffer `i` and wait until it is drawn (the flip
    /// that shows it comes after).
    pub fn draw(&mut self, i: usize, list: &DrawList) -> Result<(), GpuError> {
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        self.renderer
            .draw(&self.gpu, &mut encoder, &self.targets[i], list);
        let index = self.gpu.queue.submit([encoder.finish()]);
        self.gpu
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: Some(std::time::Duration::from_secs(10)),
            })
            .map_err(|e| GpuError::Lost(e.to_string()))?;
        Ok(())
    }
}

/// One buffer as a texture the renderer draws into.
fn import(gpu: &Gpu, dmabuf: DmaBuf, w: u32, h: u32) -> Result<wgpu::Texture, String> {
    let size = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let hal_desc = wgpu::hal::TextureDescriptor {
        label: Some("scanout"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FORMAT,
        usage: wgpu::TextureUses::COLOR_TARGET | wgpu::TextureUses::COPY_DST,
        memory_flags: wgpu::hal::MemoryFlags::empty(),
        view_formats: vec![],
    };
    let modifier = dmabuf.modifier;
    let texture = {
        // SAFETY: the hal device is used only for this import, while `gpu`
        // holds it.
        let Some(device) = (unsafe { gpu.device.as_hal::<Vulkan>() }) else {
            return Err(format!("{} is not a Vulkan device", gpu.info.name));
        };
        // SAFETY: the descriptor's size and format are the buffer's (gbm
        // made it `w` x `h` XRGB8888, one plane), and the modifier, stride
        // and offset are the ones gbm reports for it; Vulkan owns the
        // descriptor from here.
        unsafe {
            device.texture_from_dmabuf_fd(
                dmabuf.fd,
                &hal_desc,
                modifier,
                u64::from(dmabuf.stride),
                u64::from(dmabuf.offset),
            )
        }
        .map_err(|e| {
            format!(
                "{} refused the scanout buffer (modifier {}, stride {}): {e}",
                gpu.info.name,
                super::modifiers::name(modifier),
                dmabuf.stride
            )
        })?
    };
    // SAFETY: `texture` was made on this device from `hal_desc`, which the
    // descriptor below matches; it starts with undefined contents.
    Ok(unsafe {
        gpu.device.create_texture_from_hal::<Vulkan>(
            texture,
            &wgpu::TextureDescriptor {
                label: Some("scanout"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
            wgpu::TextureUses::UNINITIALIZED,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The renderer here (lavapipe) either renders linear scanout buffers
    /// or names the extensions it lacks (lavapipe 22.3 has none of them;
    /// 25.0 lacks the modifiers without udmabuf).
    #[test]
    fn the_renderer_names_what_zero_copy_lacks_or_renders_linear_buffers() {
        let gpu =
            Gpu::new(AdapterChoice::Cpu).expect("lavapipe (apt-get install mesa-vulkan-drivers)");
        match renderable_modifiers(&gpu) {
            Ok(m) => assert!(m.contains(&modifiers::LINEAR), "{m:?}"),
            Err(why) => {
                assert!(why.starts_with(&gpu.info.name), "{why}");
                assert!(why.contains("does not offer VK_"), "{why}");
                assert!(
                    EXTENSIONS
                        .iter()
                        .any(|e| why.contains(e.to_str().unwrap_or("?"))),
                    "{why}"
                );
            }
        }
    }
}
