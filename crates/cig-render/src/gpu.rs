//! The GPU device: adapter choice (hardware first, then a software rasteriser such as Mesa's
//! lavapipe), and errors when there is none.

use std::sync::{Arc, Mutex};

/// Why rendering could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("no usable GPU adapter (hardware or software; on Debian install mesa-vulkan-drivers for lavapipe): {0}")]
    NoAdapter(String),
    #[error("the GPU device could not be created on {adapter}: {reason}")]
    Device { adapter: String, reason: String },
    #[error("reading the frame back from the GPU failed: {0}")]
    Readback(String),
    #[error("{0}")]
    View(#[from] cig_scene::ViewError),
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
    #[error("frame size {width_px}x{height_px} is larger than this GPU's {max_px} pixels a side")]
    FrameTooLarge {
        width_px: u32,
        height_px: u32,
        max_px: u32,
    },
}

/// Refuses frames larger than the device's largest texture.
pub fn check_frame_size(gpu: &Gpu, width_px: u32, height_px: u32) -> Result<(), RenderError> {
    let max_px = gpu.device.limits().max_texture_dimension_2d;
    if width_px > max_px || height_px > max_px {
        return Err(RenderError::FrameTooLarge {
            width_px,
            height_px,
            max_px,
        });
    }
    Ok(())
}

/// An adapter, its device and queue.
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// True when the device can time GPU work (timestamp queries).
    pub timestamps: bool,
    /// The errors the device reported outside any error scope since they were last taken.
    errors: Arc<Mutex<GpuErrors>>,
}

/// Errors a device reported: how many, and the first one's text.
#[derive(Debug, Default)]
struct GpuErrors {
    count: u64,
    first: Option<String>,
}

impl Gpu {
    /// A device for off-screen rendering: the best hardware adapter, else a software one.
    /// `WGPU_BACKEND` / `WGPU_ADAPTER_NAME` in the environment narrow the choice (wgpu's own
    /// variables).
    pub fn headless() -> Result<Arc<Gpu>, RenderError> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_some() {
            return Self::with_instance(wgpu::Instance::new(desc), None);
        }
        // Vulkan, Metal or DX12 first; OpenGL only when none of them has an adapter (probing GL
        // talks to the display server, which prints its own complaints on headless machines).
        let mut primary = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        primary.backends = wgpu::Backends::PRIMARY;
        match Self::with_instance(wgpu::Instance::new(primary), None) {
            Ok(gpu) => Ok(gpu),
            Err(first) => {
                let mut gl = desc;
                gl.backends = wgpu::Backends::GL;
                let gpu = Self::with_instance(wgpu::Instance::new(gl), None).map_err(|_| first)?;
                tracing::warn!(
                    "no Vulkan, Metal or DX12 adapter: drawing with OpenGL on {} (clouds and light \
                     halos are not drawn, and frame times are not comparable with Vulkan's; \
                     on Debian, Mesa's mesa-vulkan-drivers gives lavapipe)",
                    gpu.info.name
                );
                Ok(gpu)
            }
        }
    }

    /// A device that can present to `surface` (created from `instance`).
    pub fn with_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Arc<Gpu>, RenderError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            ..Default::default()
        }))
        .or_else(|_| {
            pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::LowPower,
                force_fallback_adapter: true,
                compatible_surface: surface,
                ..Default::default()
            }))
        })
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = wgpu::Features::empty();
        if timestamps {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        if adapter
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE)
        {
            required_features |= wgpu::Features::POLYGON_MODE_LINE;
        }
        // Draped imagery is BC1 on disk; sampled as it is where the adapter can.
        if adapter
            .features()
            .contains(wgpu::Features::TEXTURE_COMPRESSION_BC)
        {
            required_features |= wgpu::Features::TEXTURE_COMPRESSION_BC;
        }
        // Ask for what the adapter has (a GL or older adapter may have less than WebGPU's
        // defaults), capped where more would only cost memory.
        let adapter_limits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_texture_dimension_2d: adapter_limits.max_texture_dimension_2d.min(16384),
            max_buffer_size: adapter_limits.max_buffer_size.min(1 << 30),
            max_storage_buffer_binding_size: adapter_limits
                .max_storage_buffer_binding_size
                .min(1 << 27),
            ..adapter_limits
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("cig"),
            required_features,
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        // wgpu's default handler panics on a validation error. A live frame that fails is
        // logged and the IG goes on; the error is also kept, so a one-shot picture
        // (`cig render`) can refuse to write what the GPU rejected ([`Gpu::take_errors`]).
        let errors = Arc::new(Mutex::new(GpuErrors::default()));
        let kept = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |error| {
            tracing::error!("GPU error: {error}");
            let mut kept = kept
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            kept.count += 1;
            kept.first.get_or_insert_with(|| error.to_string());
        }));
        tracing::info!(adapter = %info.name, backend = ?info.backend, "GPU device ready");
        Ok(Arc::new(Gpu {
            instance,
            adapter,
            device,
            queue,
            info,
            timestamps,
            errors,
        }))
    }

    /// The errors the device reported outside any error scope (a shader or pipeline the
    /// driver refused, a command recorded wrongly) since the last call: how many, and the
    /// first one's text; `None` when there were none.
    pub fn take_errors(&self) -> Option<(u64, String)> {
        let mut errors = self
            .errors
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let taken = std::mem::take(&mut *errors);
        (taken.count > 0).then(|| (taken.count, taken.first.unwrap_or_default()))
    }

    /// "name (backend, type)" for logs and statistics.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }
}

/// Maps a buffer slice for reading and waits until the GPU has finished writing it.
pub fn map_for_reading(gpu: &Gpu, slice: &wgpu::BufferSlice<'_>) -> Result<(), RenderError> {
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))
}

/// A 2-D render target of `size` pixels: `format`, `sample_count` samples, usable as a render
/// attachment and for `usage`, also viewable through `view_formats`.
pub fn render_target(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    sample_count: u32,
    usage: wgpu::TextureUsages,
    view_formats: &[wgpu::TextureFormat],
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
        view_formats,
    })
}

/// A full-screen triangle pipeline (`vs_main`, `fs_main`) into one single-sample target, with the
/// bind group layouts of groups 0, 1, ...
pub(crate) fn full_screen_pipeline(
    gpu: &Gpu,
    label: &str,
    module: &wgpu::ShaderModule,
    layouts: &[&wgpu::BindGroupLayout],
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> wgpu::RenderPipeline {
    full_screen_pipeline_to(
        gpu,
        label,
        module,
        layouts,
        &[Some(wgpu::ColorTargetState {
            format,
            blend,
            write_mask: wgpu::ColorWrites::ALL,
        })],
        &[],
    )
}

/// A full-screen pass's pipeline writing several colour targets, with the values of the
/// module's pipeline-overridable constants.
pub(crate) fn full_screen_pipeline_to(
    gpu: &Gpu,
    label: &str,
    module: &wgpu::ShaderModule,
    layouts: &[&wgpu::BindGroupLayout],
    targets: &[Option<wgpu::ColorTargetState>],
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    let pipeline_layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &layouts.iter().map(|l| Some(*l)).collect::<Vec<_>>(),
            immediate_size: 0,
        });
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
}
