//! A thermal sensor's AC coupling: each scan line of the band radiance through a first-order
//! high-pass filter (CIGI Sensor Control's AC coupling, a decay time constant in microseconds).
//!
//! Algorithm: an AC-coupled detector amplifier passes the signal's changes and forgets its
//! level with the coupling's time constant `tau`: along a line, the baseline follows the
//! signal, `b += (s - b)(1 - exp(-dt / tau))`, and the output is `s - b`. A pixel lasts
//! `dt` = the active line time (52.6 us, RS-170) over the frame's width. Each line starts its
//! baseline at its first pixel, so lines of different content settle to different levels (the
//! banding of AC-coupled imagers), and hot objects leave a dark trail after them along the line.
//! The level the display shows mid-grey (the manual window's centre, else the middle of the
//! automatic gain's histogram range) is added back, as the display's level control does.
//!
//! One compute invocation per line (lines are independent), into a scratch texture copied back
//! onto the scene before the gain is worked out.
//!
//! Limits: one time constant for the whole detector; no line-to-line DC restoration other than
//! the line start; skipped where the backend has no compute shaders or storage textures of the
//! scene's format.

use crate::atmosphere::HDR_FORMAT;
use crate::gpu::Gpu;

/// Active line time of an RS-170 video line, microseconds.
pub const ACTIVE_LINE_US: f32 = 52.6;

pub(crate) struct AcCouplingPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// The scratch target and its size.
    scratch: Option<(wgpu::Texture, (u32, u32))>,
}

impl AcCouplingPass {
    /// `None` where the backend cannot run it.
    pub fn new(gpu: &Gpu) -> Option<AcCouplingPass> {
        let downlevel = gpu.adapter.get_downlevel_capabilities();
        if !downlevel
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
        {
            return None;
        }
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ac coupling"),
            entries: &[
                crate::pass::unfiltered_texture_entry(0, wgpu::ShaderStages::COMPUTE),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: HDR_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
                crate::pass::uniform_entry_for(2, wgpu::ShaderStages::COMPUTE),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ac coupling"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/ac_coupling.wgsl").into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ac coupling"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("ac coupling"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("couple"),
            compilation_options: Default::default(),
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ac coupling"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(AcCouplingPass {
            pipeline,
            layout,
            params,
            scratch: None,
        })
    }

    /// Records the coupling of `scene` (the resolved frame, `size` pixels) with time constant
    /// `tau_us`, around `mean_radiance` (the level added back), and copies the result back
    /// onto it.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: (&wgpu::Texture, &wgpu::TextureView),
        size: (u32, u32),
        tau_us: f32,
        mean_radiance: f32,
    ) {
        if !(tau_us.is_finite() && tau_us > 0.0) {
            return;
        }
        if self.scratch.as_ref().is_none_or(|s| s.1 != size) {
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("ac coupling"),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: HDR_FORMAT,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            self.scratch = Some((texture, size));
        }
        let Some((scratch, _)) = &self.scratch else {
            return;
        };
        let pixel_us = ACTIVE_LINE_US / size.0.max(1) as f32;
        let step = 1.0 - (-pixel_us / tau_us).exp();
        gpu.queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&[step, mean_radiance, 0.0, 0.0]),
        );
        let scratch_view = scratch.create_view(&Default::default());
        let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ac coupling"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(scene.1),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&scratch_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.params.as_entire_binding(),
                },
            ],
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("ac coupling"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(size.1.div_ceil(64), 1, 1);
        }
        encoder.copy_texture_to_texture(
            scratch.as_image_copy(),
            scene.0.as_image_copy(),
            wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
        );
    }
}
