//! Light points: the lights `cig_scene::lights` keeps for a view, drawn instanced as points of
//! their physical illuminance at the eye.
//!
//! Algorithm: a point source of illuminance `E` at the eye spread over pixels of solid angle
//! `Ω` with weights `w` (summing to one) shows luminance `E w / Ω`, so each light's square is
//! filled with the display's point spread (a Gaussian of [`POINT_SPREAD_PX`] pixels, or the
//! tube's blur on goggles if wider) times `π E / Ω` in the frame's light units: the light's
//! energy is the same whatever the display's resolution and its size on screen follows the
//! display, not the world. Lights are depth-tested against the scene (a hill or a house hides
//! them) and added to the multisampled colour. On goggles each light also blooms into a halo
//! of constant angular size (`cig_scene::nvg::halo_diameter_deg`) carrying
//! `cig_scene::nvg::HALO_FRACTION` of its signal, so a halo is as wide in degrees in a narrow
//! view as in a wide one. Which lights are kept, and how bright they arrive (lobe, blink, fog,
//! ground fog, obscurants, Allard's law against the eye's threshold), is `cig_scene::lights`'.
//!
//! Limits: the solid angle of a pixel is taken at the view's centre (off-axis pixels of a wide
//! view are smaller by up to cos³ of the angle, so lights near the edge of a 90° view show
//! up to 65 % too bright); no glare or starburst in the visible (the eye's own bloom is not
//! drawn).

use crate::bolts::{overlay_pipeline, OverlayRecords, ADDITIVE};
use crate::gpu::Gpu;
use crate::pass::{shader, storage_entry, uniform_entry};
use cig_scene::lighting::LIGHTING_UNITS_PER_LUX;
use cig_scene::lights::DrawnLight;
use cig_scene::nvg::NvgView;
use cig_scene::Camera;

/// The display's point spread for a light, pixels (one sigma): a light covers about two
/// pixels across, never one (a single-pixel point crawls as it moves).
pub const POINT_SPREAD_PX: f32 = 0.6;
/// Lights one view draws at most.
pub const MAX_LIGHTS: usize = 65_536;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLight {
    rel: [f32; 4],
    colour: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LightFrame {
    viewport: [f32; 4],
    /// x: 1 to draw halos with the cores (no halo pass).
    mode: [f32; 4],
}

pub(crate) struct LightPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    /// Halos over the resolved scene, their lights' centres tested against the depth samples
    /// (`None` on GL, which cannot read depth samples: halos are drawn with the cores).
    halos: Option<(wgpu::BindGroupLayout, wgpu::RenderPipeline)>,
    /// Whether this frame's lights have halos.
    with_halos: bool,
    lights: OverlayRecords,
    frame: wgpu::Buffer,
    staging: Vec<GpuLight>,
}

impl LightPass {
    pub(crate) fn new(
        gpu: &Gpu,
        colour_format: wgpu::TextureFormat,
        globals: &wgpu::Buffer,
    ) -> LightPass {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("light points"),
            entries: &[uniform_entry(0), storage_entry(1), uniform_entry(2)],
        });
        let module = shader(gpu, "light points", include_str!("shaders/lights.wgsl"));
        let pipeline = overlay_pipeline(
            gpu,
            "light points",
            &module,
            &layout,
            colour_format,
            ADDITIVE,
            false,
        );
        let halos = (gpu.info.backend != wgpu::Backend::Gl).then(|| {
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("light halos"),
                entries: &[
                    uniform_entry(0),
                    storage_entry(1),
                    uniform_entry(2),
                    wgpu::BindGroupLayoutEntry {
                        binding: 3,
                        visibility: wgpu::ShaderStages::VERTEX,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: true,
                        },
                        count: None,
                    },
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("light halos"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("light halos"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_halo"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_halo"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: colour_format,
                        blend: Some(ADDITIVE),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            (layout, pipeline)
        });
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("light frame"),
            size: std::mem::size_of::<LightFrame>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let lights = OverlayRecords::new::<GpuLight>(
            gpu,
            "light points",
            &layout,
            (globals, &frame),
            (256, MAX_LIGHTS),
        );
        LightPass {
            layout,
            pipeline,
            halos,
            with_halos: false,
            lights,
            frame,
            staging: Vec::new(),
        }
    }

    /// Uploads a view's lights (eye-relative, kept and attenuated by `cig_scene::lights`) at
    /// the frame's `exposure`; on goggles (`nvg`) their NVG-weighted illuminance, grey, with
    /// halos. Returns how many to draw.
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        globals: &wgpu::Buffer,
        camera: &Camera,
        lights: &[DrawnLight],
        exposure: f64,
        nvg: Option<&NvgView>,
    ) -> usize {
        self.staging.clear();
        let ppt = camera.pixels_per_tangent;
        let pixel_deg = (1.0 / ppt).atan().to_degrees();
        // π E / Ω in pre-exposed units, Ω = 1 / ppt² at the centre.
        let scale = std::f64::consts::PI * ppt * ppt * LIGHTING_UNITS_PER_LUX * exposure;
        for light in lights.iter().take(MAX_LIGHTS) {
            let (e, colour, halo_px) = match nvg {
                Some(_) => (
                    f64::from(light.nvg_lxa),
                    [1.0; 3],
                    0.5 * cig_scene::nvg::halo_diameter_deg(f64::from(light.nvg_lxa)) / pixel_deg,
                ),
                None => (f64::from(light.illuminance_lux), light.colour, 0.0),
            };
            let value = (e * scale) as f32;
            if !(value.is_finite() && value > 0.0) {
                continue;
            }
            let [x, y, z] = light.rel_m;
            self.staging.push(GpuLight {
                rel: [x, y, z, value.min(1.0e5)],
                colour: [colour[0], colour[1], colour[2], halo_px as f32],
            });
        }
        let count = self.staging.len();
        if count == 0 {
            return 0;
        }
        self.lights
            .write(gpu, &self.layout, (globals, &self.frame), &self.staging);
        let spread_px = nvg.map_or(POINT_SPREAD_PX, |n| {
            let blur_px = n.tube.blur_sigma_deg(f64::from(n.fov_deg)) / pixel_deg;
            POINT_SPREAD_PX.max(blur_px as f32)
        });
        self.with_halos = nvg.is_some();
        let frame = LightFrame {
            viewport: [
                camera.view.width_px as f32,
                camera.view.height_px as f32,
                spread_px,
                cig_scene::nvg::HALO_FRACTION,
            ],
            mode: [f32::from(u8::from(self.halos.is_none())), 0.0, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
        count
    }

    /// Whether the prepared lights need [`Self::encode_halos`] after the scene is resolved
    /// (and so the scene's depth samples kept).
    pub(crate) fn needs_halo_pass(&self, count: usize) -> bool {
        count > 0 && self.with_halos && self.halos.is_some()
    }

    /// Draws the prepared lights' halos onto the resolved scene `hdr`, each where the scene's
    /// depth samples `depth` show its centre; returns the draw calls.
    pub(crate) fn encode_halos(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        globals: &wgpu::Buffer,
        (hdr, depth): (&wgpu::TextureView, &wgpu::TextureView),
        count: usize,
    ) -> u32 {
        let Some((layout, pipeline)) = self.halos.as_ref().filter(|_| self.needs_halo_pass(count))
        else {
            return 0;
        };
        let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light halos"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.lights.buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.frame.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(depth),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("light halos"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: hdr,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..6, 0..count as u32);
        1
    }

    /// Draws `count` prepared lights in the scene pass; returns the draw calls.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>, count: usize) -> u32 {
        if count == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.lights.bind, &[]);
        pass.draw(0..6, 0..count as u32);
        1
    }
}
