//! The GPU: a Vulkan adapter chosen from what the machine offers (a real
//! GPU first, else Mesa's lavapipe on the CPU), its device and queue. What
//! was chosen is logged, so that an operator can see in the journal whether
//! the kiosk runs on the GPU or on the CPU.

use thiserror::Error;

/// Why the renderer could not start.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No Vulkan adapter at all: no driver, or no ICD installed.
    #[error(
        "no Vulkan adapter found: install the Vulkan loader and a driver \
         (without a GPU driver: apt-get install libvulkan1 mesa-vulkan-drivers)"
    )]
    NoAdapter,
    /// The adapter refused to give a device.
    #[error("the Vulkan adapter {adapter} refused a device: {source}")]
    Device {
        adapter: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// The device went away or failed while rendering.
    #[error("the GPU device was lost or failed: {0}")]
    Lost(String),
    /// A picture larger than the adapter can render or read back.
    #[error(
        "a picture of {width}x{height} is larger than {adapter} renders (at most {max_side} pixels a side and {max_bytes} bytes a picture): lower display.width and display.height"
    )]
    TooLarge {
        width: u32,
        height: u32,
        adapter: String,
        max_side: u32,
        max_bytes: u64,
    },
}

impl GpuError {
    /// A picture too large for the adapter: the configuration asks for it.
    #[must_use]
    pub fn is_configuration(&self) -> bool {
        matches!(self, Self::TooLarge { .. })
    }
}

/// Which adapters to accept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AdapterChoice {
    /// A real GPU if there is one, else a CPU renderer.
    #[default]
    Auto,
    /// Only a CPU renderer (lavapipe): reproducible images for tests.
    Cpu,
}

/// An adapter, its device and queue.
#[derive(Debug)]
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
}

impl Gpu {
    /// A Vulkan instance (with the display extensions where the driver
    /// has them).
    #[must_use]
    pub fn instance() -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        })
    }

    /// Open the best Vulkan adapter allowed by `choice`.
    pub fn new(choice: AdapterChoice) -> Result<Self, GpuError> {
        let instance = Self::instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        for a in &adapters {
            let i = a.get_info();
            tracing::debug!(name = %i.name, kind = ?i.device_type, driver = %i.driver, "Vulkan adapter offered");
        }
        let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Other => 3,
            wgpu::DeviceType::Cpu => 4,
        };
        adapters.retain(|a| {
            choice == AdapterChoice::Auto || a.get_info().device_type == wgpu::DeviceType::Cpu
        });
        adapters.sort_by_key(rank);
        let adapter = adapters.into_iter().next().ok_or(GpuError::NoAdapter)?;
        Self::open(adapter)
    }

    /// The adapter that can draw into `surface` (the one driving its
    /// display), with its device.
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
    ) -> Result<Self, GpuError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(surface),
            ..Default::default()
        }))
        .map_err(|_| GpuError::NoAdapter)?;
        Self::open(adapter)
    }

    fn open(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        // Importing dma-bufs (gbm's scanout buffers drawn into without a
        // copy) where the driver can.
        let features = adapter.features() & wgpu::Features::VULKAN_EXTERNAL_MEMORY_DMA_BUF;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("marionette"),
            required_features: features,
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|source| GpuError::Device {
            adapter: info.name.clone(),
            source,
        })?;
        // An error wgpu does not hand back (a buffer past the device's
        // limits, a validation error) is said in the journal; wgpu's own
        // handler would end the process with a panic.
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            tracing::error!(error = %e, "the GPU refused a command");
        }));
        tracing::info!(
            adapter = %info.name,
            kind = ?info.device_type,
            driver = %format!("{} {}", info.driver, info.driver_info),
            "rendering with Vulkan"
        );
        Ok(Self {
            adapter,
            device,
            queue,
            info,
        })
    }

    /// Whether a buffer of `bytes` is within what the device holds in
    /// one buffer; said where it is not.
    pub(crate) fn holds(&self, label: &str, bytes: u64) -> bool {
        let max = self.device.limits().max_buffer_size;
        if bytes > max {
            tracing::error!(
                buffer = label,
                bytes,
                max,
                "over the largest buffer the GPU holds: not drawn"
            );
        }
        bytes <= max
    }

    /// A buffer for `usage` (and copying into) holding `bytes`.
    pub(crate) fn filled_buffer(
        &self,
        label: &str,
        usage: wgpu::BufferUsages,
        bytes: &[u8],
    ) -> wgpu::Buffer {
        let b = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (bytes.len() as u64).next_multiple_of(4).max(4),
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.queue.write_buffer(&b, 0, bytes);
        b
    }

    /// Whether the adapter renders on the CPU.
    #[must_use]
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The most samples per pixel up to `wanted` that `format` supports.
    #[must_use]
    pub fn sample_count(&self, format: wgpu::TextureFormat, wanted: u32) -> u32 {
        let flags = self.adapter.get_texture_format_features(format).flags;
        [16, 8, 4, 2]
            .into_iter()
            .find(|&n| n <= wanted && flags.sample_count_supported(n))
            .unwrap_or(1)
    }
}

/// A vertex or index buffer that grows when a frame needs more.
pub(crate) struct GrowBuffer {
    pub(crate) buffer: wgpu::Buffer,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &'static str,
        usage: wgpu::BufferUsages,
    ) -> Self {
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

    /// Write `bytes` (grown to hold them, within the device's largest
    /// buffer); nothing written, and said, where they are over it.
    pub(crate) fn write(&mut self, gpu: &Gpu, bytes: &[u8]) {
        let need = (bytes.len() as u64).next_multiple_of(4);
        if !gpu.holds(self.label, need) {
            return;
        }
        if need > self.buffer.size() {
            let max = gpu.device.limits().max_buffer_size;
            self.buffer = Self::make(
                &gpu.device,
                self.label,
                self.usage,
                need.next_power_of_two().min(max),
            );
        }
        if !bytes.is_empty() {
            let mut padded = bytes.to_vec();
            padded.resize(need as usize, 0);
            gpu.queue.write_buffer(&self.buffer, 0, &padded);
        }
    }
}
