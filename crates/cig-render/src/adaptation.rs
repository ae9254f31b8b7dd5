//! Eye adaptation: the exposure follows the luminance the view shows.
//!
//! Algorithm: after the scene is resolved (pre-exposed for the natural illuminance, see
//! `cig_scene::lighting`), a compute pass builds a 64-bin histogram of log2 luminance over every
//! second pixel in each direction; one invocation then takes the mean log2 luminance between the
//! histogram's 10th and 90th percentiles (so the sun's disc and the darkest shadows do not
//! count: the log-average of E. Reinhard et al., "Photographic Tone Reproduction", 2002, trimmed
//! as in histogram metering) and the luminance above which the brightest 8 % lie. The target
//! factor brings the mean to the natural illuminance's key, unless that would push the bright
//! share past the tone curve's knee (so looking into a low sun the sky keeps its gradations
//! and the terrain its contrast), and is bounded to [`DARKEST_EV`, `BRIGHTEST_EV`] around the
//! natural illuminance's exposure: a dark view by day brightens by at most half a stop and a
//! night stays night. The adapted factor approaches the target exponentially, with the time
//! constants of light and dark adaptation ([`TAU_LIGHT_S`], [`TAU_DARK_S`]: the photopic
//! range of S. N. Pattanaik et al., "Time-Dependent Visual Adaptation for Fast Realistic Image
//! Display", SIGGRAPH 2000: light adaptation within a second or two, dark adaptation several
//! times slower). A still frame settles at once (as if the eye had been looking for a while).
//! The tone map multiplies the scene by the adapted factor; nothing is read back to the CPU
//! to draw (the factor is read back only for the frame's statistics). During a transient (a
//! lightning flash) the eye holds its state, so the flash brightens the frame as it should.
//!
//! Limits: one state per view slot (16 slots; views beyond share them by index modulo 16);
//! the rods' slow dark adaptation over tens of minutes is not modelled (the natural
//! illuminance's key stands for the adapted night eye); backends without compute shaders (GL
//! ES 3.0) keep the natural illuminance's exposure. A fixed exposure
//! (`SkySettings::fixed_exposure_ev`) turns adaptation off.

use crate::gpu::Gpu;

/// View slots with their own adaptation state.
pub const ADAPTATION_SLOTS: usize = 16;
/// The most the view can darken the natural illuminance's exposure, EV (looking into a low
/// sun at dusk).
pub const DARKEST_EV: f32 = -5.0;
/// The most the view can brighten it, EV (a dark forest or a slope facing away from the sun;
/// no more, so noon stays noon and night stays night: a view with sky in it needs none).
pub const BRIGHTEST_EV: f32 = 0.5;
/// Time constant toward a brighter view, seconds.
pub const TAU_LIGHT_S: f32 = 0.8;
/// Time constant toward a darker view, seconds.
pub const TAU_DARK_S: f32 = 6.0;
/// Pre-exposed luminance the brightest share may reach: where the ACES curve reaches 0.95
/// (sRGB 250 of 255).
const KNEE: f32 = 3.0;
/// Shares of the histogram: the trimmed mean's low and high, the bright share's start.
const SHARES: [f32; 3] = [0.10, 0.90, 0.92];

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct AdaptParams {
    key: [f32; 4],
    slot: [f32; 4],
    shares: [f32; 4],
    /// x: 1 for a thermal sensor view.
    mode: [f32; 4],
}

/// How a frame's adaptation advances.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Adaptation {
    /// Settle at once: the frame is drawn as if the eye had been looking at it for a while
    /// (still frames, tests, benchmarks).
    #[default]
    Settled,
    /// Advance by this many seconds since the view's previous frame (interactive loops).
    Step(f32),
    /// Keep the natural illuminance's exposure (no view-dependent adaptation).
    Off,
}

/// What a frame's adaptation asks of the pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AdaptRequest {
    pub slot: usize,
    /// log2 of the grey card's key in pre-exposed units (with the exposure compensation).
    pub log2_key: f32,
    pub adaptation: Adaptation,
    /// A transient (a lightning flash) lights this frame: the eye keeps the state it had (or
    /// the natural exposure, with none yet), so the flash brightens the frame.
    pub hold: bool,
    /// A night-vision view: the automatic brightness control's limits instead of the eye's.
    pub intensifier: Option<IntensifierControl>,
}

/// The image intensifier's automatic brightness control, as the adaptation pass runs it: the
/// same trimmed log-mean brought to a key (cig_scene::nvg::OUTPUT_KEY), within the tube's gain
/// limits, with one time constant both ways, no knee, and never held for a flash (the control
/// reacts to it).
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntensifierControl {
    /// log2 of the lowest and highest factor on the pre-exposed scene.
    pub lowest_log2: f32,
    pub highest_log2: f32,
    pub tau_s: f32,
}

/// The tone map's uniform: the slot's state (16 bytes), then for sensor views the histogram's
/// range and the equalisation's weight (16) and the equalised grey at each of the 64 bins' tops
/// (256).
const TONE_BYTES: u64 = 16 + 16 + 256;
/// How much of a sensor view's grey comes from plateau histogram equalisation (the rest is the
/// linear window): large uniform areas (sky, a fire) do not take grey levels from the scene.
const SENSOR_EQUALISATION: f32 = 0.75;

/// What a thermal sensor view's automatic gain asks of the pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SensorAdaptRequest {
    pub slot: usize,
    /// The histogram's radiance range (low, high).
    pub range: (f32, f32),
    /// The narrowest window, radiance (about 2 K: the noise stays below a grey level's worth
    /// of a flat scene).
    pub min_span: f32,
    /// The manual window (radiance), replacing the automatic gain.
    pub manual: Option<(f32, f32)>,
    pub adaptation: Adaptation,
}

/// Shares of the sensor histogram the automatic gain spans (0.5 % of the pixels may saturate
/// at each end: a hot flash or the sun's glint does not darken the rest of the frame).
const SENSOR_SHARES: [f32; 2] = [0.005, 0.995];
/// Time constant of the automatic gain, seconds (short: a flash leaves within a second).
pub const SENSOR_GAIN_TAU_S: f32 = 0.25;

/// The histogram and adaptation passes, and the factor the tone map reads.
pub(crate) struct AdaptationPass {
    /// `None` where the backend has no compute shaders.
    compute: Option<Compute>,
    /// The tone map's uniform: x = the adapted log2 factor of the frame being drawn.
    pub tone_exposure: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Slots that hold an adapted state.
    valid: [bool; ADAPTATION_SLOTS],
}

struct Compute {
    layout: wgpu::BindGroupLayout,
    histogram: wgpu::ComputePipeline,
    adapt: wgpu::ComputePipeline,
    sensor_adapt: wgpu::ComputePipeline,
    bins: wgpu::Buffer,
    params: wgpu::Buffer,
    state: wgpu::Buffer,
    /// A sensor view's histogram range and equalised grey levels (the tone map's tail).
    equalised: wgpu::Buffer,
    /// Bound to the current scene target (rebuilt with the targets).
    bind: Option<wgpu::BindGroup>,
}

impl AdaptationPass {
    pub fn new(gpu: &Gpu) -> AdaptationPass {
        let device = &gpu.device;
        let tone_exposure = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tone exposure"),
            size: TONE_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adaptation readback"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let compute = gpu
            .adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
            .then(|| Compute::new(gpu));
        AdaptationPass {
            compute,
            tone_exposure,
            readback,
            valid: [false; ADAPTATION_SLOTS],
        }
    }

    /// Binds the pass to the resolved scene target (call when the targets change).
    pub fn bind_scene(&mut self, gpu: &Gpu, scene: &wgpu::TextureView) {
        if let Some(c) = &mut self.compute {
            c.bind = Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("adaptation"),
                layout: &c.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(scene),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: c.bins.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: c.params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: c.state.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: c.equalised.as_entire_binding(),
                    },
                ],
            }));
        }
    }

    /// Records the histogram of the scene of `size` pixels and the view's adaptation, and
    /// copies the adapted factor where the tone map reads it. Returns whether it did (with
    /// `Adaptation::Off`, or without compute shaders, the factor is 1).
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        size: (u32, u32),
        request: AdaptRequest,
    ) -> bool {
        let slot = request.slot % ADAPTATION_SLOTS;
        let Some(c) = self
            .compute
            .as_ref()
            .filter(|_| request.adaptation != Adaptation::Off)
        else {
            gpu.queue
                .write_buffer(&self.tone_exposure, 0, bytemuck::bytes_of(&[0f32; 4]));
            return false;
        };
        let Some(bind) = &c.bind else {
            return false;
        };
        let offset = (slot * 16) as u64;
        // The slot's state to the tone map and to the statistics' readback.
        let publish = |encoder: &mut wgpu::CommandEncoder| {
            encoder.copy_buffer_to_buffer(&c.state, offset, &self.tone_exposure, 0, 16);
            encoder.copy_buffer_to_buffer(&c.state, offset, &self.readback, 0, 16);
        };
        if request.hold && request.intensifier.is_none() {
            if self.valid[slot] {
                publish(encoder);
                return true;
            }
            gpu.queue
                .write_buffer(&self.tone_exposure, 0, bytemuck::bytes_of(&[0f32; 4]));
            return false;
        }
        let dt_s = match request.adaptation {
            Adaptation::Step(dt) if dt.is_finite() && dt >= 0.0 => dt,
            _ => -1.0,
        };
        let (lowest, highest, tau_light, tau_dark, knee_log2, nvg) = match request.intensifier {
            Some(c) => (
                c.lowest_log2,
                c.highest_log2,
                c.tau_s,
                c.tau_s,
                // No knee: the tube saturates, it does not hold its highlights.
                60.0,
                1.0,
            ),
            None => (
                DARKEST_EV,
                BRIGHTEST_EV,
                TAU_LIGHT_S,
                TAU_DARK_S,
                KNEE.log2(),
                0.0,
            ),
        };
        let params = AdaptParams {
            key: [request.log2_key, dt_s, lowest, highest],
            slot: [slot as f32, tau_light, tau_dark, knee_log2],
            shares: [
                SHARES[0],
                SHARES[1],
                SHARES[2],
                f32::from(u8::from(self.valid[slot])),
            ],
            mode: [0.0, nvg, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&c.params, 0, bytemuck::bytes_of(&params));
        encoder.clear_buffer(&c.bins, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("adaptation"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, bind, &[]);
            pass.set_pipeline(&c.histogram);
            // 16 x 16 invocations each read every second pixel: 32 x 32 pixels a group.
            pass.dispatch_workgroups(size.0.div_ceil(32), size.1.div_ceil(32), 1);
            pass.set_pipeline(&c.adapt);
            pass.dispatch_workgroups(1, 1, 1);
        }
        publish(encoder);
        self.valid[slot] = true;
        true
    }

    /// Records a thermal sensor view's automatic gain (or writes its manual window) where the
    /// tone map reads it: `(low, high)` radiance. Returns false: there is no exposure factor
    /// for the frame's statistics to read back.
    pub fn encode_sensor(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        size: (u32, u32),
        request: SensorAdaptRequest,
    ) -> bool {
        let slot = request.slot % ADAPTATION_SLOTS;
        // A linear window only: [low, high, 0, 2], then the range with no equalisation.
        let fixed = |window: (f32, f32)| {
            [
                window.0,
                window.1,
                0.0,
                2.0,
                request.range.0,
                request.range.1,
                0.0,
                0.0,
            ]
        };
        let compute = self.compute.as_ref().filter(|_| request.manual.is_none());
        let (Some(c), Some(bind)) = (compute, self.compute.as_ref().and_then(|c| c.bind.as_ref()))
        else {
            let window = request.manual.unwrap_or(request.range);
            gpu.queue
                .write_buffer(&self.tone_exposure, 0, bytemuck::bytes_of(&fixed(window)));
            return false;
        };
        let dt_s = match request.adaptation {
            Adaptation::Step(dt) if dt.is_finite() && dt >= 0.0 => dt,
            _ => -1.0,
        };
        let params = AdaptParams {
            key: [request.range.0, request.range.1, dt_s, request.min_span],
            slot: [slot as f32, SENSOR_GAIN_TAU_S, SENSOR_EQUALISATION, 0.0],
            shares: [
                SENSOR_SHARES[0],
                SENSOR_SHARES[1],
                0.0,
                f32::from(u8::from(self.valid[slot])),
            ],
            mode: [1.0, 0.0, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&c.params, 0, bytemuck::bytes_of(&params));
        encoder.clear_buffer(&c.bins, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("sensor gain"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, bind, &[]);
            pass.set_pipeline(&c.histogram);
            pass.dispatch_workgroups(size.0.div_ceil(32), size.1.div_ceil(32), 1);
            pass.set_pipeline(&c.sensor_adapt);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let offset = (slot * 16) as u64;
        encoder.copy_buffer_to_buffer(&c.state, offset, &self.tone_exposure, 0, 16);
        encoder.copy_buffer_to_buffer(&c.equalised, 0, &self.tone_exposure, 16, TONE_BYTES - 16);
        self.valid[slot] = true;
        // The gain window is no eye's exposure: the frame's statistics do not read it.
        false
    }

    /// The adapted log2 factor the last encoded frame was drawn with (after its submission).
    pub fn read_factor_log2(&self, gpu: &Gpu) -> Option<f32> {
        let slice = self.readback.slice(..);
        if let Err(e) = crate::gpu::map_for_reading(gpu, &slice) {
            tracing::debug!("the adapted exposure was not read back: {e}");
            return None;
        }
        let value = slice.get_mapped_range().ok().and_then(|data| {
            let words: &[f32] = bytemuck::cast_slice(&data);
            words.first().copied()
        });
        self.readback.unmap();
        value.filter(|v| v.is_finite())
    }
}

impl Compute {
    fn new(gpu: &Gpu) -> Compute {
        let device = &gpu.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        // Written by the passes: read-write storage.
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            visibility: compute,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            ..crate::pass::storage_entry(binding)
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("adaptation"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    visibility: compute,
                    ..crate::pass::texture_entry(0)
                },
                storage(1),
                wgpu::BindGroupLayoutEntry {
                    visibility: compute,
                    ..crate::pass::uniform_entry(2)
                },
                storage(3),
                storage(4),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("adaptation"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/adaptation.wgsl").into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("adaptation"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        Compute {
            histogram: pipeline("histogram"),
            adapt: pipeline("adapt"),
            sensor_adapt: pipeline("sensor_adapt"),
            layout,
            bins: buffer("adaptation bins", 64 * 4, U::STORAGE | U::COPY_DST),
            params: buffer(
                "adaptation params",
                std::mem::size_of::<AdaptParams>() as u64,
                U::UNIFORM | U::COPY_DST,
            ),
            state: buffer(
                "adaptation state",
                (ADAPTATION_SLOTS * 16) as u64,
                U::STORAGE | U::COPY_SRC | U::COPY_DST,
            ),
            equalised: buffer(
                "sensor equalisation",
                TONE_BYTES - 16,
                U::STORAGE | U::COPY_SRC,
            ),
            bind: None,
        }
    }
}
