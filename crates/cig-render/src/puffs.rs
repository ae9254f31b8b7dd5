//! Obscurant puffs (smoke, flame, dust) drawn as soft, lit, camera-facing Gaussian volumes, in
//! an order-independent pass.
//!
//! Algorithm: each puff is a Gaussian blob (the optics of `cig_effects::optics`, source 000
//! chapter II.A Eq 1-4) whose column optical depth through its centre is
//! `tau_c = -ln(1 - opacity)`; a ray passing at distance `b` from the centre meets
//! `tau_c exp(-b^2 / 2 sigma^2)` (`sigma = radius / 2.5`), windowed to reach 0 at the radius
//! so the billboard has no rim. One instanced draw sends every puff as a square facing the eye
//! that holds the sphere's outline (a full-screen triangle when the eye is inside a puff); the
//! fragment works on the exact view ray. Against the scene, the pass reads the multisampled
//! depth buffer with `textureLoad`: the part of the puff's column between the eye and the
//! surface, the Gaussian's distribution along the ray cut at the eye and at each depth sample
//! (`erf`), scales the optical depth, so puffs fade softly into terrain with no intersection
//! lines and the average over the samples keeps the frame's edge smoothing. Fragments add, in
//! two single-sample float targets, the optical depth `tau` and `tau` times the puff's
//! in-scattered radiance (albedo lit by the sun, wrapped, and the sky's ambient — the terrain's
//! lighting — then fogged with the distance), and the flame's emitted radiance times
//! `1 - exp(-tau)`. A full-screen pass composites onto the resolved frame:
//! `scene T + (sum tau L / sum tau)(1 - T) + emission`, `T = exp(-sum tau)` (Beer-Lambert).
//! Addition does not depend on the order of the puffs, so there is no sorting; puffs of one
//! plume that overlap add optical depth as one medium does, and never darken each other by
//! repeated alpha blending (the fault source 004 section 2.5.1.4 met with intersecting
//! translucent spheres of smoke).
//!
//! Limits: the colour is the optical-depth-weighted mean of the puffs on a pixel, not the
//! front-to-back order (a bright flame behind thick smoke shows through as much as in front of
//! it); no self-shadowing or phase function; emission is not dimmed by smoke in front of it;
//! the optical depth is summed in half floats (order changes the last bit). On wgpu's GL
//! backend, which cannot sample multisampled textures, the fallback draws each puff's square at
//! its nearest point and depth-tests it against the scene per sample (accumulating in
//! multisampled targets, then resolved): terrain inside a puff is hidden by it rather than
//! faded, and terrain in front cuts it with the frame's edge smoothing but no soft contact.

use crate::gpu::Gpu;
use crate::pass::{shader, uniform_entry, DEPTH_FORMAT, MSAA_SAMPLES};
use cig_effects::PuffInstance;
use cig_scene::view::NEAR_PLANE_M;
use cig_scene::{Camera, FrameSnapshot};

/// Most puffs one view draws (12 MB of instances); beyond it the rest are left out.
pub const MAX_PUFFS_DRAWN: usize = 1 << 18;
const ACCUMULATION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// How the puffs meet the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DepthMode {
    /// The fragment reads the scene's depth samples: soft contact (every backend but GL).
    Samples,
    /// The GL fallback: a depth test against the scene's depth buffer, multisampled targets.
    Test,
}

struct PuffTargets {
    accumulate_bind: wgpu::BindGroup,
    composite_bind: wgpu::BindGroup,
    /// The targets the composite reads (single-sample).
    scatter: wgpu::TextureView,
    emission: wgpu::TextureView,
    /// In `DepthMode::Test`: the multisampled targets drawn into, resolved into the above.
    multisampled: Option<(wgpu::TextureView, wgpu::TextureView)>,
}

/// The puff pass's pipelines, instance buffer and accumulation targets.
pub(crate) struct PuffPass {
    mode: DepthMode,
    /// False when the device cannot draw puffs at all (logged once at start).
    usable: bool,
    accumulate_layout: wgpu::BindGroupLayout,
    composite_layout: wgpu::BindGroupLayout,
    accumulate_pipeline: wgpu::RenderPipeline,
    composite_pipeline: wgpu::RenderPipeline,
    instances: wgpu::Buffer,
    capacity: usize,
    /// This frame's puffs, culled and relative to the view's eye (reused between frames).
    staging: Vec<PuffInstance>,
    targets: Option<PuffTargets>,
}

fn instance_buffer(gpu: &Gpu, capacity: usize) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("puff instances"),
        size: (capacity * std::mem::size_of::<PuffInstance>()) as u64,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl PuffPass {
    /// `atmosphere_layout`: group 1 of the accumulation (the atmosphere's tables, for the
    /// aerial perspective).
    pub(crate) fn new(
        gpu: &Gpu,
        colour_format: wgpu::TextureFormat,
        atmosphere_layout: &wgpu::BindGroupLayout,
    ) -> PuffPass {
        let device = &gpu.device;
        let mode = if gpu.info.backend == wgpu::Backend::Gl {
            DepthMode::Test
        } else {
            DepthMode::Samples
        };
        let usable = match mode {
            DepthMode::Samples => true,
            DepthMode::Test => {
                let flags = gpu
                    .adapter
                    .get_texture_format_features(ACCUMULATION_FORMAT)
                    .flags;
                let ok = flags.sample_count_supported(MSAA_SAMPLES)
                    && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE);
                if !ok {
                    tracing::warn!(
                        "obscurant puffs are not drawn: this GL device cannot multisample {ACCUMULATION_FORMAT:?} targets"
                    );
                }
                ok
            }
        };
        let float_texture = |binding, multisampled| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled,
            },
            count: None,
        };
        let accumulate_entries = match mode {
            // Depth32Float bound as unfilterable float (WebGPU allows it; GLSL needs it).
            DepthMode::Samples => vec![uniform_entry(0), float_texture(1, true)],
            DepthMode::Test => vec![uniform_entry(0)],
        };
        let accumulate_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("puff accumulate"),
            entries: &accumulate_entries,
        });
        let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("puff composite"),
            entries: &[
                uniform_entry(0),
                float_texture(1, false),
                float_texture(2, false),
            ],
        });
        let depth_source = match mode {
            DepthMode::Samples => include_str!("shaders/puff_depth_samples.wgsl"),
            DepthMode::Test => include_str!("shaders/puff_depth_test.wgsl"),
        };
        let source = format!(
            "const NEAR_PLANE_M: f32 = {NEAR_PLANE_M:?};\nconst SCENE_SAMPLES: i32 = {MSAA_SAMPLES};\n{depth_source}\n{}",
            include_str!("shaders/puffs.wgsl")
        );
        let accumulate_module =
            crate::atmosphere::atmosphere_shader(gpu, "puff accumulate", &source);
        let composite_module = shader(
            gpu,
            "puff composite",
            include_str!("shaders/puff_composite.wgsl"),
        );
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let accumulate_target = Some(wgpu::ColorTargetState {
            format: ACCUMULATION_FORMAT,
            blend: Some(wgpu::BlendState {
                color: additive,
                alpha: additive,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        });
        let (depth_stencil, multisample) = match mode {
            DepthMode::Samples => (None, wgpu::MultisampleState::default()),
            DepthMode::Test => (
                Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Greater),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                wgpu::MultisampleState {
                    count: MSAA_SAMPLES,
                    mask: !0,
                    alpha_to_coverage_enabled: false,
                },
            ),
        };
        let accumulate_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("puff accumulate"),
            layout: Some(
                &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("puff accumulate"),
                    bind_group_layouts: &[Some(&accumulate_layout), Some(atmosphere_layout)],
                    immediate_size: 0,
                }),
            ),
            vertex: wgpu::VertexState {
                module: &accumulate_module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<PuffInstance>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![
                        0 => Float32x4, 1 => Float32x4, 2 => Float32x2
                    ],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil,
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &accumulate_module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[accumulate_target.clone(), accumulate_target],
            }),
            multiview_mask: None,
            cache: None,
        });
        // frame = composite + frame * T (alpha carries T); the frame's alpha stays.
        let composite_pipeline = crate::gpu::full_screen_pipeline(
            gpu,
            "puff composite",
            &composite_module,
            &[&composite_layout],
            colour_format,
            Some(wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::SrcAlpha,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::Zero,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
            }),
        );
        let capacity = 1024;
        PuffPass {
            mode,
            usable,
            accumulate_layout,
            composite_layout,
            accumulate_pipeline,
            composite_pipeline,
            instances: instance_buffer(gpu, capacity),
            capacity,
            staging: Vec::new(),
            targets: None,
        }
    }

    /// Re-bases the snapshot's puffs on the view's eye (the difference of the two origins in
    /// f64, then each position rounded to f32), leaves out puffs outside the view, without
    /// optical depth or with non-finite values, clamps colours and emission to 0-1, and uploads
    /// the rest. Returns how many will be drawn.
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        snapshot: &FrameSnapshot,
        sensor: Option<(
            cig_scene::thermal::SensorView,
            &cig_scene::thermal::ThermalScene,
        )>,
    ) -> usize {
        self.staging.clear();
        if snapshot.puffs.is_empty() || !self.usable {
            return 0;
        }
        let shift = snapshot.puff_origin_ecef_m - camera.eye_ecef;
        if !shift.is_finite() {
            return 0;
        }
        let mut planes = camera.planes;
        if let Some(near) = planes.get_mut(4) {
            near.offset_m = 0.0;
        }
        for puff in &snapshot.puffs {
            if self.staging.len() >= MAX_PUFFS_DRAWN {
                break;
            }
            let radius = f64::from(puff.radius_m);
            let opacity = puff.opacity;
            if !(radius.is_finite() && radius > 0.0 && opacity.is_finite() && opacity > 0.0) {
                continue;
            }
            let [x, y, z] = puff.position_eye_m.map(f64::from);
            let rel = glam::DVec3::new(x, y, z) + shift;
            if !rel.is_finite() {
                continue;
            }
            // Outside a side plane by more than the radius; the near plane taken through the
            // eye, so a puff around the eye is kept.
            let outside = planes
                .iter()
                .any(|p| p.normal.dot(rel) < p.offset_m - radius);
            if outside {
                continue;
            }
            self.staging.push(PuffInstance {
                position_eye_m: [rel.x as f32, rel.y as f32, rel.z as f32],
                colour_rgb: puff.colour_rgb.map(|c| {
                    if c.is_finite() {
                        c.clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                }),
                opacity: opacity.min(1.0),
                emissive: if puff.emissive.is_finite() {
                    puff.emissive.clamp(0.0, 1.0)
                } else {
                    0.0
                },
                ..*puff
            });
            if let (Some((view, scene)), Some(last)) = (sensor, self.staging.last_mut()) {
                *last = infrared_puff(last, view.band, scene.air_k);
            }
        }
        let count = self.staging.len();
        if count > self.capacity {
            self.capacity = count.next_power_of_two().min(MAX_PUFFS_DRAWN);
            self.instances = instance_buffer(gpu, self.capacity);
        }
        if count > 0 {
            gpu.queue
                .write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.staging));
        }
        count
    }

    /// Extra usage the frame's depth buffer needs for this pass.
    pub(crate) fn depth_usage(&self) -> wgpu::TextureUsages {
        match self.mode {
            DepthMode::Samples => wgpu::TextureUsages::TEXTURE_BINDING,
            DepthMode::Test => wgpu::TextureUsages::empty(),
        }
    }

    /// Makes the accumulation targets for frames of `size` reading `depth` (the frame's
    /// multisampled depth buffer); called whenever the renderer makes its targets.
    pub(crate) fn resize(
        &mut self,
        gpu: &Gpu,
        size: (u32, u32),
        depth: &wgpu::TextureView,
        globals: &wgpu::Buffer,
    ) {
        if !self.usable {
            return;
        }
        let device = &gpu.device;
        let make = |label, sample_count, usage| {
            crate::gpu::render_target(
                device,
                label,
                size,
                ACCUMULATION_FORMAT,
                sample_count,
                usage,
                &[],
            )
            .create_view(&Default::default())
        };
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        let scatter = make("puff scatter sum", 1, sampled);
        let emission = make("puff emission sum", 1, sampled);
        let none = wgpu::TextureUsages::empty();
        let (multisampled, accumulate_entries) = match self.mode {
            DepthMode::Samples => (
                None,
                vec![
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: globals.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(depth),
                    },
                ],
            ),
            DepthMode::Test => (
                Some((
                    make("puff scatter samples", MSAA_SAMPLES, none),
                    make("puff emission samples", MSAA_SAMPLES, none),
                )),
                vec![wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                }],
            ),
        };
        let accumulate_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("puff accumulate"),
            layout: &self.accumulate_layout,
            entries: &accumulate_entries,
        });
        let composite_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("puff composite"),
            layout: &self.composite_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&scatter),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&emission),
                },
            ],
        });
        self.targets = Some(PuffTargets {
            accumulate_bind,
            composite_bind,
            scatter,
            emission,
            multisampled,
        });
    }

    /// Records the accumulation (one instanced draw of `count` puffs) and the composite onto
    /// `target` (the resolved frame). Returns the draw calls recorded.
    pub(crate) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        count: usize,
        atmosphere_bind: &wgpu::BindGroup,
        timestamps: Option<(&wgpu::QuerySet, u32, u32)>,
    ) -> u32 {
        let Some(targets) = self.targets.as_ref() else {
            return 0;
        };
        if count == 0 {
            return 0;
        }
        let multisampled = targets.multisampled.as_ref();
        // Multisampled targets are resolved; only the resolved ones are kept.
        let clear = wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: if multisampled.is_some() {
                wgpu::StoreOp::Discard
            } else {
                wgpu::StoreOp::Store
            },
        };
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("puff accumulate"),
                color_attachments: &[
                    Some(wgpu::RenderPassColorAttachment {
                        view: multisampled.map_or(&targets.scatter, |m| &m.0),
                        depth_slice: None,
                        resolve_target: multisampled.map(|_| &targets.scatter),
                        ops: clear,
                    }),
                    Some(wgpu::RenderPassColorAttachment {
                        view: multisampled.map_or(&targets.emission, |m| &m.1),
                        depth_slice: None,
                        resolve_target: multisampled.map(|_| &targets.emission),
                        ops: clear,
                    }),
                ],
                depth_stencil_attachment: multisampled.map(|_| {
                    wgpu::RenderPassDepthStencilAttachment {
                        view: depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }
                }),
                timestamp_writes: timestamps.map(|(set, begin, _)| {
                    wgpu::RenderPassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(begin),
                        end_of_pass_write_index: None,
                    }
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.accumulate_pipeline);
            pass.set_bind_group(0, &targets.accumulate_bind, &[]);
            pass.set_bind_group(1, atmosphere_bind, &[]);
            let bytes = (count * std::mem::size_of::<PuffInstance>()) as u64;
            pass.set_vertex_buffer(0, self.instances.slice(..bytes));
            pass.draw(0..6, 0..count as u32);
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("puff composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps.map(|(set, _, end)| wgpu::RenderPassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: None,
                end_of_pass_write_index: Some(end),
            }),
            ..Default::default()
        });
        pass.set_pipeline(&self.composite_pipeline);
        pass.set_bind_group(0, &targets.composite_bind, &[]);
        pass.draw(0..3, 0..1);
        2
    }
}

/// A puff as a thermal sensor sees it (puffs.wgsl's sensor branch): its optical depth scaled by
/// its kind's infrared ratio (`cig_scene::thermal::obscurant_ir_ratio`), its colour the band
/// radiance of its gas (smoke and dust at their temperature, near the air's; flames glowing at
/// theirs, as emission).
fn infrared_puff(puff: &PuffInstance, band: cig_thermal::IrBand, air_k: f64) -> PuffInstance {
    let kind = cig_effects::ObscurantKind::ALL
        .get(puff.kind as usize)
        .copied()
        .unwrap_or(cig_effects::ObscurantKind::Smoke);
    let ratio = cig_scene::thermal::obscurant_ir_ratio(kind, band);
    let tau = -(1.0 - puff.opacity.min(0.9999)).ln() * ratio;
    let temperature_k = if puff.temperature_k.is_finite() && puff.temperature_k > 100.0 {
        f64::from(puff.temperature_k)
    } else {
        air_k
    };
    let radiance = cig_thermal::planck::band_radiance_unchecked(band.band(), temperature_k) as f32;
    let flame = kind == cig_effects::ObscurantKind::Flame;
    PuffInstance {
        opacity: 1.0 - (-tau).exp(),
        colour_rgb: [radiance; 3],
        emissive: if flame { 1.0 } else { 0.0 },
        ..*puff
    }
}
