//! The wgpu device: picks whichever adapter exists (Vulkan lavapipe, GL llvmpipe, a real GPU)
//! and says which it used. No adapter is a typed error that names what to install.

use thiserror::Error;

/// Everything that can go wrong while rendering.
#[derive(Debug, Error)]
pub enum RenderError {
    #[error(
        "no graphics adapter found (backends tried: {backends}). On a machine without a GPU \
         install Mesa's software rasterizers: `apt-get install -y mesa-vulkan-drivers libvulkan1 \
         libegl1 libegl-mesa0 libgl1-mesa-dri` (lavapipe for Vulkan, llvmpipe for OpenGL). \
         WGPU_BACKEND=vulkan|gl selects a backend. ({reason})"
    )]
    NoAdapter { backends: String, reason: String },
    #[error("cannot open a device on adapter {adapter}: {reason}")]
    NoDevice { adapter: String, reason: String },
    #[error("image size {width}x{height} is invalid: {reason}")]
    BadSize {
        width: u32,
        height: u32,
        reason: String,
    },
    #[error("MSAA sample count {0} is not supported (use 1 or 4)")]
    BadSampleCount(u32),
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("reading back the rendered image failed: {0}")]
    Readback(String),
    /// A buffer the scene needs is larger than the device allows (e.g. the fat-border
    /// vertices of a million patches past wgpu's 2 GiB buffers).
    #[error(
        "the {what} of this scene need {bytes} bytes: more than this adapter's largest buffer ({limit} bytes)"
    )]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
    },
}

/// Device, queue and a description of the adapter in use.
#[derive(Debug)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Whether the device draws from indirect buffers (`multi_draw_indexed_indirect`).
    pub indirect: bool,
}

impl Gpu {
    /// Opens the default adapter (honouring `WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, …).
    pub fn new() -> Result<Gpu, RenderError> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let instance = wgpu::Instance::new(desc);
        let adapter = Self::adapter(&instance, None)?;
        Self::open(&adapter)
    }

    /// Picks an adapter of `instance` (able to present to `surface`, if given).
    pub fn adapter(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<wgpu::Adapter, RenderError> {
        let backends = format!(
            "{:?}",
            wgpu::InstanceDescriptor::new_without_display_handle_from_env().backends
        );
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference:
                wgpu::PowerPreference::from_env().unwrap_or(wgpu::PowerPreference::HighPerformance),
            force_fallback_adapter: false,
            compatible_surface: surface,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RenderError::NoAdapter {
            backends,
            reason: e.to_string(),
        })
    }

    /// Opens a device on `adapter`.
    pub fn open(adapter: &wgpu::Adapter) -> Result<Gpu, RenderError> {
        let info = adapter.get_info();
        let indirect = adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION);
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("patchwork"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| RenderError::NoDevice {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        Ok(Gpu {
            device,
            queue,
            info,
            indirect,
        })
    }

    /// A caller's device and queue (wgpu's handles are shared references: the caller keeps
    /// its own). Cut ranges of mesh patches are then drawn one call each, not from indirect
    /// buffers: a device does not say whether its adapter executes indirect draws.
    pub(crate) fn from_device(device: &wgpu::Device, queue: &wgpu::Queue) -> Gpu {
        Gpu {
            device: device.clone(),
            queue: queue.clone(),
            info: device.adapter_info(),
            indirect: false,
        }
    }

    /// "llvmpipe (LLVM 15.0.6, 256 bits) via Vulkan (Cpu)".
    pub fn describe(&self) -> String {
        format!(
            "{} via {:?} ({:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Largest square texture side the device accepts.
    pub(crate) fn max_texture_side(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }
}
