//! Lightning bolts drawn as emissive lines in the scene pass.
//!
//! Algorithm: every line of every lit bolt (`FrameSnapshot::bolts`, generated once per strike
//! by the world) is re-based on the view's eye in f64 and sent as an eye-relative f32 segment
//! with its radiance; one instanced draw widens each segment into a screen-aligned quad
//! [`LINE_HALF_WIDTH_PX`] pixels each side of the line (`shaders/screen_lines.wgsl`), so a bolt
//! 20 km away is as visible as one nearby and never breaks up between pixels, with a Gaussian
//! glow across it; the quads are depth-tested against the scene (terrain and models in front
//! hide the bolt; it writes its depth, so the cloud and puff passes after the scene see it at
//! its distance) and added to the multisampled colour (additive blending: an
//! emitter over whatever is behind it). The radiance follows the contract of the frame's light
//! (`pi * L * LIGHTING_UNITS_PER_LUX` for a luminance `L`, [`radiance_units`]) times the
//! bolt's envelope and the branch's brightness, and is dimmed by the fog along the line of sight
//! (transmittance only: emission is not replaced by the fog's colour).
//!
//! Limits: the channel (centimetres thick) is drawn as a line of fixed pixel width whose
//! luminance [`CHANNEL_LUMINANCE_CD_M2`] is a visual value, not the physical peak (1e8 cd/m²
//! and more for microseconds): it saturates the frame at any exposure, which is what the eye
//! sees. No bloom (the glow is the quad's own), no scattering by the cloud.

use crate::gpu::Gpu;
use crate::pass::{shader, storage_entry, uniform_entry, DEPTH_FORMAT, MSAA_SAMPLES};
use cig_scene::lighting::{FLASH_COLOUR, LIGHTING_UNITS_PER_LUX};
use cig_scene::{Camera, FrameSnapshot};

/// Half the width of a drawn bolt line, pixels.
pub const LINE_HALF_WIDTH_PX: f32 = 1.5;
/// Luminance a bolt's main channel is drawn with at its peak, cd/m².
pub const CHANNEL_LUMINANCE_CD_M2: f64 = 1.0e6;
/// Lines one view draws at most (16 bolts at the 2000-segment cap).
const MAX_LINES: usize = 32_768;

/// A luminance in cd/m² as the frame's light units (the value a white Lambert surface under
/// illuminance `pi * L` shows).
pub fn radiance_units(luminance_cd_m2: f64) -> f64 {
    std::f64::consts::PI * luminance_cd_m2 * LIGHTING_UNITS_PER_LUX
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLine {
    start: [f32; 4],
    end: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct BoltFrame {
    viewport: [f32; 4],
    colour: [f32; 4],
}

/// A pipeline drawing six vertices per instance into the scene pass's multisampled target,
/// depth-tested (reversed depth), writing depth when `depth_write`, with `blend`.
pub(crate) fn overlay_pipeline(
    gpu: &Gpu,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    colour_format: wgpu::TextureFormat,
    blend: wgpu::BlendState,
    depth_write: bool,
) -> wgpu::RenderPipeline {
    let pipeline_layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(layout)],
            immediate_size: 0,
        });
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(depth_write),
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: MSAA_SAMPLES,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: colour_format,
                    blend: Some(blend),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// The bolt pass: pipeline, line buffer and per-frame uniform.
pub(crate) struct BoltPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    lines: OverlayRecords,
    frame: wgpu::Buffer,
    staging: Vec<GpuLine>,
}

/// Emitters over what is behind them: colour added, alpha kept.
pub(crate) const ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Zero,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

/// A storage buffer of `capacity` records of `T` that the CPU writes.
pub(crate) fn record_buffer<T>(gpu: &Gpu, label: &str, capacity: usize) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (capacity * std::mem::size_of::<T>()) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The bind group of an overlay pass: the globals at 0, the records at 1, the pass's
/// per-frame uniform at 2.
pub(crate) fn overlay_bind(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    (globals, records, frame): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
) -> wgpu::BindGroup {
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: records.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: frame.as_entire_binding(),
            },
        ],
    })
}

/// An overlay pass's records on the GPU: the buffer, how many it holds, and the pass's bind
/// group over it (rebuilt when the buffer grows).
pub(crate) struct OverlayRecords {
    label: &'static str,
    pub buffer: wgpu::Buffer,
    capacity: usize,
    max: usize,
    pub bind: wgpu::BindGroup,
}

impl OverlayRecords {
    /// Room for `capacity` records of `T` (growing to at most `max`), bound with the globals
    /// and the pass's `frame` uniform in `layout`.
    pub(crate) fn new<T>(
        gpu: &Gpu,
        label: &'static str,
        layout: &wgpu::BindGroupLayout,
        (globals, frame): (&wgpu::Buffer, &wgpu::Buffer),
        (capacity, max): (usize, usize),
    ) -> OverlayRecords {
        let buffer = record_buffer::<T>(gpu, label, capacity);
        let bind = overlay_bind(gpu, label, layout, (globals, &buffer, frame));
        OverlayRecords {
            label,
            buffer,
            capacity,
            max,
            bind,
        }
    }

    /// Writes `records` (at most `max` of them), growing the buffer by powers of two first.
    pub(crate) fn write<T: bytemuck::Pod>(
        &mut self,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        (globals, frame): (&wgpu::Buffer, &wgpu::Buffer),
        records: &[T],
    ) {
        let records = &records[..records.len().min(self.max)];
        if records.len() > self.capacity {
            self.capacity = records.len().next_power_of_two().min(self.max);
            self.buffer = record_buffer::<T>(gpu, self.label, self.capacity);
            self.bind = overlay_bind(gpu, self.label, layout, (globals, &self.buffer, frame));
        }
        gpu.queue
            .write_buffer(&self.buffer, 0, bytemuck::cast_slice(records));
    }
}

impl BoltPass {
    pub(crate) fn new(
        gpu: &Gpu,
        colour_format: wgpu::TextureFormat,
        globals: &wgpu::Buffer,
    ) -> BoltPass {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("bolts"),
            entries: &[uniform_entry(0), storage_entry(1), uniform_entry(2)],
        });
        let source = format!(
            "{}\n{}",
            include_str!("shaders/screen_lines.wgsl"),
            include_str!("shaders/bolts.wgsl")
        );
        let module = shader(gpu, "bolts", &source);
        // The bolt writes its depth, so the cloud and puff passes after the scene see it where
        // it is (in front of an overcast, behind smoke).
        let pipeline = overlay_pipeline(
            gpu,
            "bolts",
            &module,
            &layout,
            colour_format,
            ADDITIVE,
            true,
        );
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bolt frame"),
            size: std::mem::size_of::<BoltFrame>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lines = OverlayRecords::new::<GpuLine>(
            gpu,
            "bolt lines",
            &layout,
            (globals, &frame),
            (256, MAX_LINES),
        );
        BoltPass {
            layout,
            pipeline,
            lines,
            frame,
            staging: Vec::new(),
        }
    }

    /// Uploads the snapshot's bolt lines relative to the camera's eye; returns how many to
    /// draw.
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        globals: &wgpu::Buffer,
        camera: &Camera,
        snapshot: &FrameSnapshot,
    ) -> usize {
        self.staging.clear();
        let peak = radiance_units(CHANNEL_LUMINANCE_CD_M2);
        'bolts: for bolt in &snapshot.bolts {
            if !(bolt.intensity.is_finite() && bolt.intensity > 0.0) {
                continue;
            }
            let base = bolt.origin_ecef_m - camera.eye_ecef;
            for line in bolt.lines.iter() {
                if self.staging.len() >= MAX_LINES {
                    break 'bolts;
                }
                let at = |p: [f32; 3]| {
                    let v =
                        base + glam::DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
                    [v.x as f32, v.y as f32, v.z as f32]
                };
                let [ax, ay, az] = at(line.start_m);
                let [bx, by, bz] = at(line.end_m);
                let radiance =
                    (peak * f64::from(bolt.intensity * line.brightness.clamp(0.0, 1.0))) as f32;
                self.staging.push(GpuLine {
                    start: [ax, ay, az, radiance],
                    end: [bx, by, bz, 0.0],
                });
            }
        }
        let count = self.staging.len();
        if count == 0 {
            return 0;
        }
        self.lines
            .write(gpu, &self.layout, (globals, &self.frame), &self.staging);
        let frame = BoltFrame {
            viewport: [
                camera.view.width_px as f32,
                camera.view.height_px as f32,
                LINE_HALF_WIDTH_PX,
                0.0,
            ],
            colour: [FLASH_COLOUR[0], FLASH_COLOUR[1], FLASH_COLOUR[2], 0.0],
        };
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
        count
    }

    /// Draws `count` prepared lines in the scene pass; returns the draw calls.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>, count: usize) -> u32 {
        if count == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.lines.bind, &[]);
        pass.draw(0..6, 0..count as u32);
        1
    }
}
