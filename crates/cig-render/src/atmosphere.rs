//! The physical sky on the GPU: the atmosphere's tables, the per-frame sky-view table, and the
//! frame's exposure and tone map.
//!
//! Algorithm: S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering
//! Technique" (EGSR 2020). The transmittance (256 × 64, Bruneton's mapping) and
//! multiple-scattering (32 × 32) tables are computed once on the CPU by
//! [`cig_environment::atmosphere`] and uploaded as half floats. Each frame a 192 × 108 sky-view
//! table (latitude concentrated at the horizon, longitude from the sun's azimuth, full circle
//! so the moon-lit sky fits too) is ray marched in 24 steps by a full-screen fragment pass (one
//! pipeline with the moon's light, one without, so a daylit or moonless sky is not charged for
//! it); the
//! sky pass and the horizon fog colour sample it (`shaders/atmosphere.wgsl`). The same pass
//! writes a second table, each direction's source function `L / (1 − T(ray))`: its radiance
//! over the share of light the whole ray scatters in, with `T(ray)` the march's own
//! transmittance. Aerial perspective: the transmittance `T(d)` between the eye and a surface is
//! the flat-layer closed form of the exponential Rayleigh and Mie profiles (their densities at
//! the eye worked out once per frame), and the in-scattered light is the source function along
//! the ray times the surface's share `1 − T(d)` — one table sample per pixel instead of
//! Hillaire's 32³ froxel volume. The scene is drawn into a half-float
//! target as pre-exposed radiance; [`ToneMap`] maps it to the caller's target (scotopic blue
//! shift at night, ACES filmic curve, sRGB encoding where the target is not sRGB).
//!
//! Limits: the aerial perspective's in-scattering assumes it grows along the ray as the
//! extinction does (good for horizontal and descending rays, too bright in the earth's shadow
//! at dusk by at most the shadowed share); no volumetric shadows (mountains do not shade the
//! air); the moon-lit sky uses the sun's spectrum.

use crate::gpu::Gpu;
use crate::pass::{sampler_entry, texture_entry};
use cig_environment::atmosphere::{Atmosphere, Lut, SUN_ANGULAR_RADIUS_DEG};

/// Format of the scene target (pre-exposed linear radiance).
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Sky-view table size (Hillaire: 192 × 108).
pub const SKY_VIEW_SIZE: (u32, u32) = (192, 108);

/// The WGSL constants of the Earth's atmosphere and the table sizes, from the same values the
/// CPU model uses.
pub(crate) fn wgsl_constants() -> String {
    let p = cig_environment::AtmosphereParams::EARTH;
    let v3 = |v: [f64; 3]| format!("vec3<f32>({:e}, {:e}, {:e})", v[0], v[1], v[2]);
    format!(
        "const ATM_BOTTOM: f32 = {:.1};\nconst ATM_TOP: f32 = {:.1};\n\
         const ATM_RAYLEIGH: vec3<f32> = {};\nconst ATM_RAYLEIGH_H: f32 = {:.1};\n\
         const ATM_MIE_SCAT: f32 = {:e};\nconst ATM_MIE_EXT: f32 = {:e};\n\
         const ATM_MIE_H: f32 = {:.1};\nconst ATM_MIE_G: f32 = {};\n\
         const ATM_OZONE: vec3<f32> = {};\nconst ATM_OZONE_PEAK: f32 = {:.1};\n\
         const ATM_OZONE_HALF: f32 = {:.1};\nconst ATM_SUN_RADIUS: f32 = {:e};\n\
         const SKY_VIEW_SIZE: vec2<f32> = vec2<f32>({:.1}, {:.1});\n",
        p.bottom_radius_m,
        p.top_radius_m,
        v3(p.rayleigh_scattering_per_m),
        p.rayleigh_scale_height_m,
        p.mie_scattering_per_m,
        p.mie_extinction_per_m,
        p.mie_scale_height_m,
        p.mie_g,
        v3(p.ozone_absorption_per_m),
        p.ozone_peak_altitude_m,
        p.ozone_half_width_m,
        SUN_ANGULAR_RADIUS_DEG.to_radians(),
        SKY_VIEW_SIZE.0,
        SKY_VIEW_SIZE.1,
    )
}

/// A shader of common.wgsl, the atmosphere's constants and functions, and `body`.
pub(crate) fn atmosphere_shader(gpu: &Gpu, label: &str, body: &str) -> wgpu::ShaderModule {
    let source = format!(
        "{}\n{}\n{}\n{}",
        include_str!("shaders/common.wgsl"),
        wgsl_constants(),
        include_str!("shaders/atmosphere.wgsl"),
        body
    );
    gpu.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        })
}

fn upload_lut(gpu: &Gpu, label: &str, lut: &Lut) -> wgpu::TextureView {
    let texels: Vec<half_bits::F16x4> = lut.texels.iter().map(|t| half_bits::pack(*t)).collect();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: lut.width as u32,
            height: lut.height as u32,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: HDR_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(lut.width as u32 * 8),
            rows_per_image: Some(lut.height as u32),
        },
        wgpu::Extent3d {
            width: lut.width as u32,
            height: lut.height as u32,
            depth_or_array_layers: 1,
        },
    );
    texture.create_view(&Default::default())
}

/// IEEE half floats without a dependency: round-to-nearest-even conversion of finite values.
mod half_bits {
    pub type F16x4 = [u16; 4];

    pub fn pack(v: [f32; 4]) -> F16x4 {
        v.map(to_f16)
    }

    pub fn to_f16(x: f32) -> u16 {
        let bits = x.to_bits();
        let sign = ((bits >> 16) & 0x8000) as u16;
        if !x.is_finite() {
            return sign | 0x7c00;
        }
        let a = x.abs();
        if a >= 65504.0 {
            return sign | 0x7bff;
        }
        if a < 6.103_515_6e-5 {
            // Subnormal: units of 2^-24.
            let m = (a * 16_777_216.0).round_ties_even() as u16;
            return sign | m;
        }
        let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
        let mant = bits & 0x7f_ffff;
        let mut h = ((exp as u32) << 10) | (mant >> 13);
        let rest = mant & 0x1fff;
        if rest > 0x1000 || (rest == 0x1000 && (h & 1) == 1) {
            h += 1;
        }
        sign | h as u16
    }

    #[cfg(test)]
    mod tests {
        use super::to_f16;

        #[test]
        fn half_floats_match_known_encodings() {
            assert_eq!(to_f16(1.0), 0x3c00);
            assert_eq!(to_f16(-2.0), 0xc000);
            assert_eq!(to_f16(0.5), 0x3800);
            assert_eq!(to_f16(65504.0), 0x7bff);
            assert_eq!(to_f16(1e9), 0x7bff);
            assert_eq!(to_f16(0.0), 0);
            assert_eq!(to_f16(5.960_464_5e-8), 1);
            assert_eq!(to_f16(0.333_333_34), 0x3555);
        }
    }
}

/// The atmosphere's GPU resources: the tables and the sky-view pass.
pub(crate) struct AtmosphereGpu {
    /// Layout of `@group(1)` of the sky, terrain and model pipelines (and the sky-view pass).
    pub layout: wgpu::BindGroupLayout,
    /// Group 1 for the scene's pipelines (samples the sky-view table).
    pub scene_bind: wgpu::BindGroup,
    sky_view: wgpu::TextureView,
    /// The sky-view pass's second table: each direction's source function.
    sky_source: wgpu::TextureView,
    /// Group 1 for the sky-view pass (placeholders in the sky-view tables' slots).
    lut_bind: wgpu::BindGroup,
    /// The sky-view pass without and with the moon's light, and the one that reads it from
    /// the globals, each built when a frame first needs it (the moonless one at start-up).
    sky_view_pipelines: [std::sync::OnceLock<wgpu::RenderPipeline>; 3],
    sky_view_module: wgpu::ShaderModule,
    globals_layout: wgpu::BindGroupLayout,
    globals_bind: wgpu::BindGroup,
}

impl AtmosphereGpu {
    /// Uploads the tables (computed once per process) and builds the sky-view pass;
    /// `globals_layout` and `globals_bind` are group 0 (the frame's `Globals`).
    pub fn new(
        gpu: &Gpu,
        globals_layout: &wgpu::BindGroupLayout,
        globals_bind: wgpu::BindGroup,
    ) -> AtmosphereGpu {
        let device = &gpu.device;
        let atmosphere = Atmosphere::earth();
        let transmittance = upload_lut(gpu, "transmittance table", &atmosphere.transmittance);
        let multi = upload_lut(
            gpu,
            "multiple-scattering table",
            &atmosphere.multi_scattering,
        );
        let placeholder = upload_lut(
            gpu,
            "sky-view placeholder",
            &Lut {
                width: 1,
                height: 1,
                texels: vec![[0.0; 4]],
            },
        );
        let table = |label| {
            crate::gpu::render_target(
                device,
                label,
                SKY_VIEW_SIZE,
                HDR_FORMAT,
                1,
                wgpu::TextureUsages::TEXTURE_BINDING,
                &[],
            )
            .create_view(&Default::default())
        };
        let sky_view = table("sky-view table");
        let sky_source = table("sky-view source table");
        let clamp = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("atmosphere tables"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let wrap = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sky-view table"),
            address_mode_u: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("atmosphere"),
            entries: &[
                texture_entry(0),
                texture_entry(1),
                texture_entry(2),
                sampler_entry(3),
                sampler_entry(4),
                texture_entry(5),
            ],
        });
        let bind = |label, radiance: &wgpu::TextureView, source: &wgpu::TextureView| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(radiance),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&transmittance),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&multi),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Sampler(&clamp),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::Sampler(&wrap),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(source),
                    },
                ],
            })
        };
        let scene_bind = bind("atmosphere (scene)", &sky_view, &sky_source);
        let lut_bind = bind("atmosphere (sky-view pass)", &placeholder, &placeholder);
        let module = atmosphere_shader(gpu, "sky view", include_str!("shaders/sky_view.wgsl"));
        let atmosphere = AtmosphereGpu {
            layout,
            scene_bind,
            sky_view,
            sky_source,
            lut_bind,
            sky_view_pipelines: Default::default(),
            sky_view_module: module,
            globals_layout: globals_layout.clone(),
            globals_bind,
        };
        atmosphere.sky_view_pipeline(gpu, Some(false));
        atmosphere
    }

    /// The sky-view pass's pipeline for `moon_sky` (see `encode_sky_view`), built on first use.
    fn sky_view_pipeline(&self, gpu: &Gpu, moon_sky: Option<bool>) -> &wgpu::RenderPipeline {
        let index = moon_sky.map_or(2, usize::from);
        self.sky_view_pipelines[index].get_or_init(|| {
            let table = Some(wgpu::ColorTargetState {
                format: HDR_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            });
            let moon_sky = moon_sky.map_or(-1.0, |on| f64::from(u8::from(on)));
            crate::gpu::full_screen_pipeline_to(
                gpu,
                "sky view",
                &self.sky_view_module,
                &[&self.globals_layout, &self.layout],
                &[table.clone(), table],
                &[("MOON_SKY", moon_sky)],
            )
        })
    }

    /// Records the sky-view table's pass (the frame's globals must be written); `moon_sky`:
    /// whether the moon lights the sky (`Lighting::moon_lights_the_sky`), or `None` for the
    /// pipeline that reads the moon's light from the globals.
    pub fn encode_sky_view(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        moon_sky: Option<bool>,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sky view"),
            color_attachments: &[&self.sky_view, &self.sky_source].map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })
            }),
            depth_stencil_attachment: None,
            timestamp_writes,
            ..Default::default()
        });
        pass.set_pipeline(self.sky_view_pipeline(gpu, moon_sky));
        pass.set_bind_group(0, &self.globals_bind, &[]);
        pass.set_bind_group(1, &self.lut_bind, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// The tone-map pass: the HDR scene target to the caller's target.
pub(crate) struct ToneMap {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

impl ToneMap {
    pub fn new(
        gpu: &Gpu,
        globals_layout: &wgpu::BindGroupLayout,
        target: wgpu::TextureFormat,
    ) -> ToneMap {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tone map"),
            entries: &[
                crate::pass::unfiltered_texture_entry(0, wgpu::ShaderStages::FRAGMENT),
                // The eye's adaptation (adaptation.rs): x the log2 factor; a sensor view's gain.
                crate::pass::uniform_entry_for(1, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let module = crate::pass::shader(gpu, "tone map", include_str!("shaders/tonemap.wgsl"));
        let pipeline = crate::gpu::full_screen_pipeline(
            gpu,
            "tone map",
            &module,
            &[globals_layout, &layout],
            target,
            None,
        );
        ToneMap { layout, pipeline }
    }

    /// The bind group that reads `scene` (the resolved HDR target) and the eye's adaptation
    /// factor (`exposure`, a 16-byte uniform).
    pub fn bind(
        &self,
        gpu: &Gpu,
        scene: &wgpu::TextureView,
        exposure: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tone map"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(scene),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: exposure.as_entire_binding(),
                },
            ],
        })
    }

    /// Records the tone map of the scene (bound by `scene_bind`) into `target`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        globals_bind: &wgpu::BindGroup,
        scene_bind: &wgpu::BindGroup,
        target: &wgpu::TextureView,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = crate::pass::cleared_pass(encoder, "tone map", target, timestamp_writes);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, globals_bind, &[]);
        pass.set_bind_group(1, scene_bind, &[]);
        pass.draw(0..3, 0..1);
    }
}
