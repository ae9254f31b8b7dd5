//! Rain streaks and snow flakes around the eye, drawn in the scene pass.
//!
//! Algorithm: particles live on a lattice of period [`BOX_M`] in a local east-north-up frame
//! anchored at the eye's 0.1° cell. Particle `i` sits at a hashed place `h(seed, i)` in the
//! cell, moved by the fall velocity (`cig_environment::precipitation`: Atlas et al. 1973 for
//! rain, 1 m/s for snow) and the wind times the world time, and wrapped into the box centred
//! on the eye: `rel = fract((h - (eye - v t)) / L) L - L / 2`. The offset `(eye - v t) mod L`
//! is taken in f64 on the CPU, so the places are a function of (seed, index, time) alone, do
//! not depend on the frame rate, and stay put in the world when the eye moves (the eye moves
//! through them). One instanced draw of six vertices per particle: rain as a streak, the
//! drop's path over [`STREAK_EXPOSURE_S`] (1/30 s, about the eye's integration time) widened to a pixel-wide quad
//! (`screen_lines.wgsl`); snow as a soft disc facing the eye, its size 12 mm (an aggregate) or three pixels,
//! swaying ±0.3 m. Particles are lit by the frame's light (the ambient sky light and a share
//! of the sun, after any lightning flash), semi-transparent (premultiplied alpha over the
//! scene), depth-tested against terrain and models, faded out at the edge of the ball inscribed
//! in the box and in the last metre before the eye. The number drawn grows with the rate
//! toward [`MAX_RAIN_PARTICLES`] / [`MAX_SNOW_PARTICLES`] (`1 - exp(-R / R0)`).
//!
//! Limits: the drawn particles stand for the visible ones (the real number of drops within
//! 12 m is millions); all drops of a frame fall at one speed; the pattern is laid again when
//! the eye crosses into another 0.1° cell (about every 10 km of travel); no splashes, no
//! wet surfaces, no occlusion by a roof or cockpit (the box ignores what is above the eye).

use crate::bolts::overlay_pipeline;
use crate::gpu::Gpu;
use crate::pass::uniform_entry;
use cig_environment::PrecipitationKind;
use cig_geo::{EnuFrame, Geodetic};
use cig_scene::lighting::Lighting;
use cig_scene::{Camera, FrameSnapshot};
use glam::DVec3;

/// Common period of the snow's two sway frequencies (2.1 and 1.7 rad/s: 21 and 17 turns in
/// 20π s), so wrapping the time sent to the shader never makes a flake jump.
const SWAY_PERIOD_S: f64 = 20.0 * std::f64::consts::PI;

/// Side of the box of particles around the eye, m.
pub const BOX_M: f64 = 24.0;
/// Exposure over which a drop's streak is drawn, s (about the eye's integration time).
pub const STREAK_EXPOSURE_S: f64 = 1.0 / 30.0;
/// Most raindrops drawn.
pub const MAX_RAIN_PARTICLES: u32 = 10_000;
/// Most snow flakes drawn.
pub const MAX_SNOW_PARTICLES: u32 = 12_000;
/// Rates at which the drawn numbers reach 63 % of their maximum, mm/h of water.
const RAIN_SCALE_MM_PER_H: f64 = 8.0;
const SNOW_SCALE_MM_PER_H: f64 = 1.0;
/// Flake diameter, m.
const FLAKE_DIAMETER_M: f32 = 0.012;
/// Time the particles' motion counts from (2020-01-01 UTC), to keep the products small.
const EPOCH_UNIX_S: f64 = 1_577_836_800.0;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct PrecipUniform {
    east: [f32; 4],
    north: [f32; 4],
    up: [f32; 4],
    offset: [f32; 4],
    velocity: [f32; 4],
    params: [f32; 4],
    colour: [f32; 4],
    viewport: [f32; 4],
}

/// The precipitation pass.
pub(crate) struct PrecipitationPass {
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
}

/// How many particles a rate draws.
pub fn particle_count(kind: PrecipitationKind, rate_mm_per_h: f64) -> u32 {
    if !(rate_mm_per_h.is_finite() && rate_mm_per_h > 0.0) {
        return 0;
    }
    let (max, scale) = match kind {
        PrecipitationKind::Snow => (MAX_SNOW_PARTICLES, SNOW_SCALE_MM_PER_H),
        PrecipitationKind::Rain | PrecipitationKind::Sleet => {
            (MAX_RAIN_PARTICLES, RAIN_SCALE_MM_PER_H)
        }
    };
    (f64::from(max) * (1.0 - (-rate_mm_per_h / scale).exp())).round() as u32
}

impl PrecipitationPass {
    pub(crate) fn new(
        gpu: &Gpu,
        colour_format: wgpu::TextureFormat,
        globals: &wgpu::Buffer,
    ) -> PrecipitationPass {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("precipitation"),
            entries: &[uniform_entry(0), uniform_entry(1)],
        });
        let source = format!(
            "{}\n{}",
            include_str!("shaders/screen_lines.wgsl"),
            include_str!("shaders/precipitation.wgsl")
        );
        let module = crate::pass::shader(gpu, "precipitation", &source);
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let pipeline = overlay_pipeline(
            gpu,
            "precipitation",
            &module,
            &layout,
            colour_format,
            wgpu::BlendState {
                color: over,
                alpha: over,
            },
            // Translucent streaks: no depth (a cloud or puff behind a drop still shows).
            false,
        );
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("precipitation"),
            size: std::mem::size_of::<PrecipUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("precipitation"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: globals.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: uniform.as_entire_binding(),
                },
            ],
        });
        PrecipitationPass {
            pipeline,
            uniform,
            bind,
        }
    }

    /// Writes the frame's particle parameters; returns how many particles to draw.
    pub(crate) fn prepare(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        snapshot: &FrameSnapshot,
        lighting: &Lighting,
    ) -> u32 {
        let Some(draw) = snapshot.precipitation else {
            return 0;
        };
        let p = draw.precipitation;
        let count = particle_count(p.kind, p.rate_mm_per_h);
        let eye = camera.view.eye;
        if count == 0 || !snapshot.unix_time_s.is_finite() {
            return 0;
        }
        let anchor = Geodetic::new(
            (eye.lat_deg * 10.0).round() / 10.0,
            (eye.lon_deg * 10.0).round() / 10.0,
            0.0,
        );
        let frame = EnuFrame::new(anchor);
        let eye_enu = frame.geodetic_to_enu(eye);
        let [wind_e, wind_n] = draw.wind_en_mps;
        let wind = |w: f64| {
            if w.is_finite() {
                w.clamp(-100.0, 100.0)
            } else {
                0.0
            }
        };
        let velocity = DVec3::new(wind(wind_e), wind(wind_n), -p.fall_speed_mps());
        let t = snapshot.unix_time_s - EPOCH_UNIX_S;
        let offset = (eye_enu - velocity * t)
            .to_array()
            .map(|c| c.rem_euclid(BOX_M) as f32);
        let axis = |v: DVec3| {
            let e = frame.enu_vector_to_ecef(v);
            [e.x as f32, e.y as f32, e.z as f32, 0.0]
        };
        let snow = p.kind == PrecipitationKind::Snow;
        // Light on a particle: the sky's ambient light and a share of the sun (drops
        // refract most of what is behind them; flakes are white and scatter it all).
        // Flakes are lit mostly by the sky, so against a bright sky they show grey, against
        // terrain or at night white, as real snow does.
        let (albedo, sun_share, opacity) = if snow {
            (0.9f32, 0.1f32, 0.9f32)
        } else {
            (0.5, 0.15, 0.45)
        };
        let sun_up = (lighting.sun_elevation_deg.to_radians().sin() as f32).max(0.0);
        let lit: [f32; 3] = std::array::from_fn(|i| {
            albedo
                * (lighting.ambient_colour[i] + lighting.sun_colour[i] * sun_share * (0.3 + sun_up))
        });
        let uniform = PrecipUniform {
            east: axis(DVec3::X),
            north: axis(DVec3::Y),
            up: axis(DVec3::Z),
            offset: [offset[0], offset[1], offset[2], BOX_M as f32],
            velocity: [
                velocity.x as f32,
                velocity.y as f32,
                velocity.z as f32,
                STREAK_EXPOSURE_S as f32,
            ],
            params: [
                if snow { 1.0 } else { 0.0 },
                count as f32,
                FLAKE_DIAMETER_M,
                opacity,
            ],
            colour: [lit[0], lit[1], lit[2], t.rem_euclid(SWAY_PERIOD_S) as f32],
            viewport: [
                camera.view.width_px as f32,
                camera.view.height_px as f32,
                if snow { 1.5 } else { 0.6 },
                ((draw.seed ^ (draw.seed >> 32)) & 0x7F_FFFF) as f32,
            ],
        };
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        count
    }

    /// Draws the prepared particles in the scene pass; returns the draw calls.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>, count: u32) -> u32 {
        if count == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.draw(0..6, 0..count);
        1
    }
}
