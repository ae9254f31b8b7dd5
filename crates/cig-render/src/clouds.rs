//! Cloud layers drawn as a full-screen ray march over the scene, with their shade on the ground.
//!
//! Algorithm: the CPU uploads each layer's seeded noise (`cig_environment::clouds::CloudNoise`,
//! the very texels the CPU model reads, one layer per RGBA channel of a 256² texture sampled
//! bilinearly with repeat) and, every frame, the eye's noise coordinates per layer (east/north
//! metres from the snapshot's world-fixed origin minus the wind's displacement at the frame's
//! time, reduced modulo the tile in f64), the texels per metre (with the equirectangular
//! stretch at the eye), the slab's base and thickness relative to the eye, extinction, coverage
//! and profile. After the opaque scene, a full-screen pass at half resolution (a quarter of
//! the pixels, into a float target) reads the scene's depth (sample 0 of the multisampled
//! depth, as the puff pass reads it) and, per pixel, finds the nearest part
//! of the view ray inside each slab (heights along the ray with the earth's curvature, the
//! `height_above_eye` parabola of common.wgsl), cut at the scene and at `FAR_M`, and marches it
//! with 3 to 8 samples (one per half thickness of path), offset per pixel by a hash of the pixel
//! (the PCG hash of Jarzynski and Olano, JCGT 2020: white noise, so no periodic dot or checker
//! pattern; interleaved gradient noise showed one at half resolution) so the slices of a
//! fixed-step march show as fine grain rather than bands: extinction from the same cover strength and vertical profile as the
//! CPU model, single scattering of the sun (a two-lobe Henyey-Greenstein phase, forward peak
//! g = 0.6) dimmed by the depth into the layer toward the sun with a floor for multiple
//! scattering, plus the sky's ambient light; accumulated front to back (Beer-Lambert). Clouds
//! take the frame's fog at their mean distance, as the terrain does. For terrain pixels the same pass dims the
//! sun's share of the light (sun against ambient luminance) by the transmittance of the slant
//! column through each layer above at the layer's mid-height. A second full-screen pass
//! upsamples the half-resolution result with four bilinear taps half a texel apart (a kernel of
//! 1/8, 1/2, 3/8 per axis, the same for both quarters of a texel, so the half-resolution grid
//! leaves no 2 x 2 blocks) and blends it onto the
//! frame as `clouds + scene * (transmittance * shade)`, pre-exposed. With the eye inside a slab the
//! segment starts at the eye, so flying into a cloud fogs the view and flying out clears it.
//!
//! Sources: Beer-Lambert and single scattering as in Hillaire, "Physically based sky, atmosphere
//! and cloud rendering in Frostbite" (SIGGRAPH 2016 course) and Schneider, "The real-time
//! volumetric cloudscapes of Horizon Zero Dawn" (SIGGRAPH 2015): the phase lobes, the
//! multiple-scattering floor and the height-fraction profiles are theirs in spirit, much
//! simplified; the NPS thesis (source 000, chapter VII) lists its clouds' lack of motion.
//!
//! Limits: at most 8 samples per layer leave fine noise on thick clouds seen edge-on; the field is 2-D
//! (no overhangs); self-shadowing is by height only; the shade ignores the terrain's normal and
//! uses one column per layer; the half resolution and the upsampling kernel soften cloud edges
//! against terrain silhouettes (a halo of up to two pixels) and the shade's edges; clouds beyond `FAR_M` (80 km) are not drawn; on wgpu's GL backend,
//! which cannot sample multisampled depth, clouds are not drawn at all (logged once).

use crate::gpu::{full_screen_pipeline, Gpu};
use crate::pass::{sampler_entry, shader, texture_entry, uniform_entry};
use cig_environment::clouds::{CloudLayer, CloudNoise, CloudShape, MAX_CLOUD_LAYERS, NOISE_SIZE};
use cig_scene::view::NEAR_PLANE_M;
use cig_scene::{Camera, FrameSnapshot};

/// Farthest distance along a ray that clouds are drawn, metres.
pub const FAR_M: f64 = 80_000.0;
/// Format of the half-resolution cloud frame (radiance, and what the scene keeps).
const HALF_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LayerUniform {
    place: [f32; 4],
    params: [f32; 4],
    shape: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CloudsUniform {
    east: [f32; 4],
    north: [f32; 4],
    layers: [LayerUniform; MAX_CLOUD_LAYERS],
}

/// The cloud pass: pipeline, noise texture, per-frame uniform.
pub(crate) struct CloudPass {
    usable: bool,
    layout: wgpu::BindGroupLayout,
    composite_layout: wgpu::BindGroupLayout,
    /// The march and the composite (none where the pass is not usable: their shaders read
    /// multisampled depth, which GL cannot).
    pipelines: Option<(wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    uniform: wgpu::Buffer,
    noise: wgpu::Texture,
    noise_view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// Bilinear, clamped: the composite's upsampling.
    half_sampler: wgpu::Sampler,
    /// Seeds of the noise now in the texture's channels.
    seeds: Vec<u64>,
    /// The half-resolution frame and the bind groups of the march and the composite.
    targets: Option<(wgpu::TextureView, wgpu::BindGroup, wgpu::BindGroup)>,
    /// Lowest base of this frame's layers above the eye, metres (for the order against puffs).
    lowest_base_above_eye_m: f64,
}

impl CloudPass {
    /// The pass for frames whose resolved colour target has `colour_format`.
    pub(crate) fn new(gpu: &Gpu, colour_format: wgpu::TextureFormat) -> CloudPass {
        let device = &gpu.device;
        let usable = gpu.info.backend != wgpu::Backend::Gl;
        if !usable {
            tracing::warn!("clouds are not drawn: the GL backend cannot sample multisampled depth");
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("clouds"),
            entries: &[
                uniform_entry(0),
                uniform_entry(1),
                texture_entry(2),
                sampler_entry(3),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    // Depth32Float read as unfilterable float (as the puff pass does).
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: true,
                    },
                    count: None,
                },
            ],
        });
        let source = format!(
            "const NEAR_PLANE_M: f32 = {NEAR_PLANE_M:?};\n{}",
            include_str!("shaders/clouds.wgsl")
        );
        let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("clouds composite"),
            entries: &[uniform_entry(0), texture_entry(1), sampler_entry(2)],
        });
        let pipelines = usable.then(|| {
            (
                full_screen_pipeline(
                    gpu,
                    "clouds",
                    &shader(gpu, "clouds", &source),
                    &[&layout],
                    HALF_FORMAT,
                    None,
                ),
                composite_pipeline(gpu, &composite_layout, colour_format),
            )
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("clouds"),
            size: std::mem::size_of::<CloudsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let noise = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("cloud noise"),
            size: wgpu::Extent3d {
                width: NOISE_SIZE as u32,
                height: NOISE_SIZE as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let noise_view = noise.create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("cloud noise"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let half_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("clouds half frame"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        CloudPass {
            half_sampler,
            usable,
            layout,
            composite_layout,
            pipelines,
            uniform,
            noise,
            noise_view,
            sampler,
            seeds: Vec::new(),
            targets: None,
            lowest_base_above_eye_m: f64::INFINITY,
        }
    }

    /// Extra usage the frame's depth buffer needs for this pass.
    pub(crate) fn depth_usage(&self) -> wgpu::TextureUsages {
        if self.usable {
            wgpu::TextureUsages::TEXTURE_BINDING
        } else {
            wgpu::TextureUsages::empty()
        }
    }

    /// Makes the half-resolution frame for frames of `size` and binds the frame's
    /// multisampled depth; called whenever the renderer makes its targets.
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
        let half = crate::gpu::render_target(
            device,
            "clouds half frame",
            (size.0.div_ceil(2).max(1), size.1.div_ceil(2).max(1)),
            HALF_FORMAT,
            1,
            wgpu::TextureUsages::TEXTURE_BINDING,
            &[],
        )
        .create_view(&Default::default());
        let march = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("clouds"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&self.noise_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(depth),
                },
            ],
        });
        let composite = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("clouds composite"),
            layout: &self.composite_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&half),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.half_sampler),
                },
            ],
        });
        self.targets = Some((half, march, composite));
    }

    /// Uploads the snapshot's layers for a view (invalid layers are left out; the world
    /// validates and clamps them first) and, when their seeds changed, their noise. Returns how
    /// many layers will be drawn.
    pub(crate) fn prepare(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        snapshot: &FrameSnapshot,
    ) -> usize {
        self.lowest_base_above_eye_m = f64::INFINITY;
        if !self.usable {
            return 0;
        }
        let mut layers: Vec<CloudLayer> = snapshot
            .cloud_layers
            .iter()
            .filter(|l| l.validate().is_ok() && l.coverage > 0.0)
            .take(MAX_CLOUD_LAYERS)
            .copied()
            .collect();
        // Lowest first: the march takes the layers in the order a ray meets them (upward rays
        // from the first, downward from the last), so the nearer layer composites in front.
        layers.sort_by(|a, b| a.base_m.total_cmp(&b.base_m));
        if layers.is_empty() {
            return 0;
        }
        let seeds: Vec<u64> = layers.iter().map(|l| l.seed).collect();
        if seeds != self.seeds {
            let noises: Vec<CloudNoise> = seeds.iter().map(|&s| CloudNoise::new(s)).collect();
            let mut rgba = vec![0u8; NOISE_SIZE * NOISE_SIZE * 4];
            for (channel, noise) in noises.iter().enumerate() {
                for (texel, value) in rgba.chunks_exact_mut(4).zip(noise.texels()) {
                    if let Some(t) = texel.get_mut(channel) {
                        *t = *value;
                    }
                }
            }
            gpu.queue.write_texture(
                self.noise.as_image_copy(),
                &rgba,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(NOISE_SIZE as u32 * 4),
                    rows_per_image: None,
                },
                wgpu::Extent3d {
                    width: NOISE_SIZE as u32,
                    height: NOISE_SIZE as u32,
                    depth_or_array_layers: 1,
                },
            );
            self.seeds = seeds;
        }
        let eye = camera.view.eye;
        let enu = cig_geo::EnuFrame::new(eye);
        let east = enu.enu_vector_to_ecef(glam::DVec3::X);
        let north = enu.enu_vector_to_ecef(glam::DVec3::Y);
        let origin = snapshot.cloud_origin;
        let (eye_east_m, eye_north_m) = origin.plane_m(eye.lat_deg, eye.lon_deg);
        let stretch = origin.east_stretch(eye.lat_deg);
        let mut uniform = CloudsUniform {
            east: [
                east.x as f32,
                east.y as f32,
                east.z as f32,
                layers.len() as f32,
            ],
            north: [north.x as f32, north.y as f32, north.z as f32, FAR_M as f32],
            ..Default::default()
        };
        for (slot, layer) in uniform.layers.iter_mut().zip(&layers) {
            let params = layer.kind.params();
            let per_m = NOISE_SIZE as f64 / params.tile_m;
            let (x, y) = layer.noise_coords(eye_east_m, eye_north_m, snapshot.unix_time_s);
            let base_rel = layer.base_m - eye.alt_m;
            self.lowest_base_above_eye_m = self.lowest_base_above_eye_m.min(base_rel);
            *slot = LayerUniform {
                place: [
                    x as f32,
                    y as f32,
                    base_rel as f32,
                    layer.thickness_m as f32,
                ],
                params: [
                    (per_m * stretch) as f32,
                    per_m as f32,
                    params.extinction_per_m as f32,
                    layer.coverage as f32,
                ],
                shape: [
                    if params.shape == CloudShape::Heap {
                        1.0
                    } else {
                        0.0
                    },
                    cig_environment::clouds::EDGE.min(1.0 - layer.coverage) as f32,
                    0.0,
                    0.0,
                ],
            };
        }
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        layers.len()
    }

    /// Whether the eye is below every layer's base (then the clouds are drawn before the
    /// puffs, which are nearer; otherwise after them).
    pub(crate) fn eye_below_clouds(&self) -> bool {
        self.lowest_base_above_eye_m > 0.0
    }

    /// Records the march into the half-resolution frame and its composite onto `target`
    /// (the resolved frame). Returns the draw calls recorded.
    pub(crate) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        timestamps: Option<(&wgpu::QuerySet, u32, Option<u32>)>,
    ) -> u32 {
        let (Some((half, march, composite)), Some((pipeline, composite_pipeline))) =
            (self.targets.as_ref(), self.pipelines.as_ref())
        else {
            return 0;
        };
        let passes = [
            (
                half,
                march,
                pipeline,
                wgpu::LoadOp::Clear(wgpu::Color::WHITE),
            ),
            (target, composite, composite_pipeline, wgpu::LoadOp::Load),
        ];
        for (i, (view, bind, pipeline, load)) in passes.into_iter().enumerate() {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("clouds"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timestamps.and_then(|(set, begin, end)| {
                    let (b, e) = if i == 0 {
                        (Some(begin), None)
                    } else {
                        (None, end)
                    };
                    (b.is_some() || e.is_some()).then_some(wgpu::RenderPassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: b,
                        end_of_pass_write_index: e,
                    })
                }),
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.draw(0..3, 0..1);
        }
        2
    }
}

/// The composite: upsamples the half-resolution frame onto a `colour_format` target.
fn composite_pipeline(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    colour_format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    full_screen_pipeline(
        gpu,
        "clouds composite",
        &shader(
            gpu,
            "clouds composite",
            include_str!("shaders/clouds_composite.wgsl"),
        ),
        &[layout],
        colour_format,
        // frame = clouds + frame * alpha; the frame's alpha stays.
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
    )
}
