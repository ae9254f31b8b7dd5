//! The display correction pass: a channel's warp grid and edge-blend ramps
//! (`cig_scene::display`, where the algorithm is described), drawn last, from the finished
//! frame into the frame the display gets.
//!
//! The grid's nodes are a vertex buffer (display position, view point) drawn as indexed
//! triangles over a black target; the fragment reads the frame (a texel's own value when the
//! point falls on its centre, so the identity grid copies the frame exactly; bilinear
//! elsewhere) and multiplies it by the blend's factor at the display pixel. The pass works on
//! the encoded values a projector receives: off-screen both textures are viewed as plain
//! `Rgba8Unorm`; a window's are viewed through the surface's plain format where it has one,
//! and where it offers only an sRGB view the frame's values are encoded after reading and
//! decoded before the store (which encodes them again).

use crate::gpu::Gpu;
use cig_scene::display::{DisplayCorrection, WarpMesh};

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DisplayParams {
    sizes: [f32; 4],
    ramps: [f32; 4],
    gamma: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GridVertex {
    display: [f32; 2],
    view_uv: [f32; 2],
}

/// The format both sides of the pass are viewed in.
pub const DISPLAY_VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub struct DisplayPass {
    correction: DisplayCorrection,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    params: wgpu::Buffer,
    /// The target is viewed with sRGB encoding (a window that offers no plain view): the
    /// pass writes linear values so that the store encodes them back to the frame's.
    target_encodes: bool,
    /// The frame is read through an sRGB view (decoded to linear): the pass encodes it first.
    source_decodes: bool,
}

impl DisplayPass {
    /// The pass into [`DISPLAY_VIEW_FORMAT`] targets (off-screen frames).
    pub fn new(gpu: &Gpu, correction: DisplayCorrection) -> DisplayPass {
        DisplayPass::with_formats(gpu, correction, DISPLAY_VIEW_FORMAT, DISPLAY_VIEW_FORMAT)
    }

    /// The pass from frames viewed as `source_format` into targets viewed as `target_format`
    /// (a window's surface: BGRA or RGBA, plain or, where it offers no plain view, sRGB).
    pub fn with_formats(
        gpu: &Gpu,
        correction: DisplayCorrection,
        source_format: wgpu::TextureFormat,
        target_format: wgpu::TextureFormat,
    ) -> DisplayPass {
        let device = &gpu.device;
        let identity;
        let mesh = match &correction.warp {
            Some(mesh) => mesh,
            None => {
                // A blend alone: the one-cell identity grid.
                identity =
                    WarpMesh::identity(2, 2).unwrap_or_else(|_| unreachable!("2 x 2 is a grid"));
                &identity
            }
        };
        let vertices: Vec<GridVertex> = mesh
            .display_positions()
            .iter()
            .enumerate()
            .map(|(i, d)| GridVertex {
                display: *d,
                view_uv: mesh.view_point(i),
            })
            .collect();
        let indices = mesh.triangle_indices();
        let vertex_buffer = buffer_with(
            gpu,
            "display grid",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        let index_buffer = buffer_with(
            gpu,
            "display grid indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display params"),
            size: std::mem::size_of::<DisplayParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display"),
            entries: &[
                crate::pass::texture_entry(0),
                crate::pass::sampler_entry(1),
                crate::pass::uniform_entry(2),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/display.wgsl").into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<GridVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: target_format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("display"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        DisplayPass {
            correction,
            pipeline,
            layout,
            sampler,
            vertices: vertex_buffer,
            index_count: indices.len() as u32,
            indices: index_buffer,
            params,
            target_encodes: target_format.is_srgb(),
            source_decodes: source_format.is_srgb(),
        }
    }

    pub fn correction(&self) -> &DisplayCorrection {
        &self.correction
    }

    /// Records the pass: `frame` (the finished view, `source_size` pixels, viewed in the
    /// pass's source format) into `display` (`target_size` pixels, viewed in its target
    /// format).
    pub fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        frame: &wgpu::TextureView,
        source_size: (u32, u32),
        display: &wgpu::TextureView,
        target_size: (u32, u32),
    ) {
        let blend = self.correction.blend;
        let params = DisplayParams {
            sizes: [
                source_size.0 as f32,
                source_size.1 as f32,
                target_size.0 as f32,
                target_size.1 as f32,
            ],
            ramps: blend.map_or([0.0; 4], |b| {
                [b.left as f32, b.right as f32, b.top as f32, b.bottom as f32]
            }),
            gamma: [
                blend.map_or(1.0, |b| (1.0 / b.gamma) as f32),
                if self.target_encodes { 1.0 } else { 0.0 },
                if self.source_decodes { 1.0 } else { 0.0 },
                0.0,
            ],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(frame),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.params.as_entire_binding(),
                },
            ],
        });
        let mut pass = crate::pass::cleared_pass(encoder, "display", display, None);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

fn buffer_with(gpu: &Gpu, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (bytes.len() as u64)
            .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
            .max(4),
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    gpu.queue.write_buffer(&buffer, 0, bytes);
    buffer
}
