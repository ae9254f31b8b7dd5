//! The interactive viewer: a window (winit) showing one view of the terrain from a free-flying
//! camera, with an operator panel (egui) drawn over the frame.
//!
//! Algorithm: one winit event loop drives the frame loop (`ControlFlow::Poll`, a redraw asked
//! after every batch of events). Each frame: acquire the surface texture, fly the camera by the
//! held keys over the frame time ([`camera`]), advance the simulation clock ([`panel`]), call
//! the paging cache's non-blocking `update` with the eye, run the panel, draw the terrain view
//! with [`Renderer::render`] (multisampled and resolved into the surface texture), then draw
//! egui in a second render pass that loads, rather than clears, the same texture, and present.
//! The surface is configured with an sRGB format from its capabilities (or an sRGB view of a
//! linear one), so the renderer's linear-light output and egui's colours are encoded once.
//! Resizes reconfigure the surface; zero-sized (minimised) windows draw nothing. A screenshot,
//! when asked for, re-draws the last frame (terrain and panel) into an off-screen texture and
//! reads it back, since reading a surface texture is not possible on every platform.
//!
//! Limits: one view per window; mouse look uses cursor positions (no pointer grab), so looking
//! round stops at the window's edge until the button is pressed again. A frame time above 1 s
//! (a stall, a dragged window) counts as 1 s, so the camera is not flung across the map. The event loop must run
//! on the process's main thread (a winit rule on several platforms), and only once per process.

pub mod camera;
pub mod panel;

use crate::gpu::{Gpu, RenderError};
use crate::offscreen::Image;
use crate::renderer::serde_like::FrameStats;
use crate::renderer::{FrameOptions, Renderer};
use camera::{FlyCamera, MoveInput};
use cig_geo::Geodetic;
use cig_scene::lighting::FogMode;
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::TileCache;
use panel::{FrameInfo, PanelState};
use std::collections::HashSet;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

pub use panel::ObscurantCommand;

/// What the viewer shows first and how it behaves.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    pub title: String,
    /// First eyepoint, altitude above the WGS84 ellipsoid.
    pub eye: Geodetic,
    pub orientation: Hpr,
    /// Horizontal field of view, degrees; the vertical one follows the window's shape.
    pub horizontal_fov_deg: f64,
    /// First window size (inner, physical pixels).
    pub width_px: u32,
    pub height_px: u32,
    /// Simulation time, UTC seconds since 1970.
    pub unix_time_s: f64,
    pub visibility_m: f64,
    pub fog_mode: FogMode,
    pub max_pixel_error: f64,
    pub wireframe: bool,
    /// First flying speed, metres per second.
    pub speed_mps: f64,
    /// Node meshes built at most per frame.
    pub mesh_budget: usize,
    /// Close the window after this many frames have been presented (for tests).
    pub exit_after_frames: Option<u64>,
    /// Keep an image of the last frame (terrain and panel) in the report.
    pub capture_last_frame: bool,
    /// A scripted flight played from the first frame (eye, orientation and time interpolated
    /// between shots); the camera is the user's once it ends.
    pub script: Vec<Shot>,
    /// Models added to the built-in ones (e.g. glTF files a scenario names).
    pub models: Vec<cig_scene::models::Model>,
    /// The renderer's overload control (`None`: off; see [`Renderer::set_overload`]).
    pub overload: Option<cig_scene::overload::OverloadSettings>,
    /// Keep the natural illuminance's exposure instead of adapting to the view (the channels
    /// of one eyepoint then match at their seams).
    pub natural_exposure: bool,
    /// The channel's display correction (warp grid, edge blend), drawn last into the window
    /// (under the panel).
    pub display_correction: Option<cig_scene::display::DisplayCorrection>,
}

/// Supplies each frame's world when the viewer is driven from outside (an IG serving a host):
/// called once per frame; the operator panel's level-of-detail threshold and wireframe still
/// apply, and its obscurant orders are handed over in the tick.
pub type FrameDriver = Box<dyn FnMut(&ViewerTick) -> FrameSnapshot>;

/// One frame of a driven viewer.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewerTick {
    /// Real seconds since the previous frame.
    pub dt_s: f64,
    pub width_px: u32,
    pub height_px: u32,
    /// The operator's obscurant orders this frame, places resolved on the terrain.
    pub orders: Vec<ObscurantOrder>,
    /// The band radiance of the trackers' gates the last frame asked for
    /// (`FrameSnapshot::track_gates`), read back after it was drawn: (view index, gate,
    /// values row by row).
    pub track_patches: Vec<(usize, [u32; 4], Vec<f32>)>,
}

/// An operator's obscurant order with its place found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObscurantOrder {
    /// Start a plume on the ground at `at` (altitude above the ellipsoid).
    StartPlume {
        at: Geodetic,
        flame: bool,
        heat_release_w: f64,
    },
    /// Stop every plume the operator started.
    StopPlumes,
    /// Set the wind the obscurants drift in (direction it blows from, degrees).
    SetWind { speed_mps: f64, from_deg: f64 },
    /// Rain or snow around the eye (`None`: stop it).
    SetPrecipitation(Option<cig_environment::Precipitation>),
    /// A lightning strike on the ground at `at`.
    StrikeLightning { at: Geodetic },
    /// A storm around `centre` striking this often, per minute (0: none).
    SetStorm {
        centre: Geodetic,
        strikes_per_minute: f64,
    },
    /// The operator's cloud layer (base above mean sea level), or `None`: the clouds go back
    /// to the host and the scenario. Sent when the panel's layer changes.
    SetClouds(Option<cig_environment::CloudLayer>),
    /// The operator's sensor for every view (`None`: back to the host's and the scenario's).
    /// Sent when the panel's sensor changes.
    SetSensor(Option<cig_scene::thermal::SensorView>),
    /// The operator's night-vision goggle for every view (`None`: back to the host's and the
    /// scenario's). Sent when the panel's channel changes.
    SetNvg(Option<cig_scene::nvg::NvgView>),
}

/// Without a driver, the panel's thermal sensor: every material's surface temperatures spun
/// up at the camera's place the first time (default weather), then advanced with the panel's
/// clock; the frame's views drawn by `sensor` (the infrared paths' heights counted from sea
/// level: the stand-alone viewer knows no ground under the table).
fn own_sensor(
    table: &mut Option<cig_thermal::SurfaceTable>,
    eye: Geodetic,
    unix_time_s: f64,
    sensor: cig_scene::thermal::SensorView,
    snapshot: &mut FrameSnapshot,
) {
    let Ok(time) = cig_environment::UtcTime::from_unix_seconds(unix_time_s) else {
        return;
    };
    match table {
        Some(t) => t.advance_to(time),
        None => match cig_thermal::SurfaceTable::spin_up(
            eye.lat_deg,
            eye.lon_deg,
            time,
            cig_thermal::ThermalWeather::default(),
            &cig_thermal::ThermalMaterial::ALL,
            cig_thermal::Orientations::Standard,
        ) {
            Ok(t) => *table = Some(t),
            Err(e) => {
                tracing::warn!("the thermal sensor cannot be drawn here: {e}");
                return;
            }
        },
    }
    let Some(t) = table else {
        return;
    };
    let atmosphere = cig_scene::thermal::atmosphere_over(t, cig_thermal::Aerosol::Rural, 23_000.0);
    snapshot.thermal = Some(std::sync::Arc::new(
        cig_scene::thermal::ThermalScene::from_table(t, atmosphere, Vec::new()),
    ));
    snapshot.sensors = vec![Some(sensor); snapshot.views.len()];
}

/// Without a driver, the panel's weather: rain or snow around the eye, and the last
/// lightning strike's bolt and flash (a storm needs the IG's world, `cig serve`).
fn own_weather(
    panel: &mut PanelState,
    eye: Geodetic,
    own_bolt: &mut Option<(f64, cig_scene::bolt::MadeBolt)>,
    own_strikes: &mut u64,
    orders: &[ObscurantOrder],
    snapshot: &mut FrameSnapshot,
) {
    let now = panel.unix_time_s;
    for order in orders {
        match *order {
            ObscurantOrder::StrikeLightning { at } => {
                *own_strikes += 1;
                *own_bolt = Some((now, cig_scene::bolt::make_bolt(at, 1500.0, *own_strikes)));
            }
            ObscurantOrder::SetStorm {
                strikes_per_minute, ..
            } if strikes_per_minute > 0.0 => {
                panel.obscurant_note =
                    "a storm needs the IG (cig serve); strike now works here".into();
            }
            _ => {}
        }
    }
    let wind = panel.wind_from_deg.to_radians() + std::f64::consts::PI;
    snapshot.precipitation =
        panel
            .precipitation()
            .map(|precipitation| cig_scene::PrecipitationDraw {
                precipitation,
                wind_en_mps: [
                    panel.wind_speed_mps * wind.sin(),
                    panel.wind_speed_mps * wind.cos(),
                ],
                seed: 1,
            });
    if let Some(p) = panel.precipitation() {
        let v = p.combined_visibility_m(panel.visibility_m);
        snapshot.fog = cig_scene::Fog::from_visibility(panel.fog_mode, v);
    }
    let envelope = cig_environment::lightning::FlashEnvelope::default();
    let mut over = false;
    if let Some((start, bolt)) = &*own_bolt {
        // The panel's clock may run at any rate: the flash runs on its time.
        let k = envelope.intensity(now - start);
        if k > 0.0 {
            snapshot.bolts.push(cig_scene::BoltDraw {
                origin_ecef_m: bolt.origin_ecef_m,
                lines: Arc::clone(&bolt.lines),
                intensity: k as f32,
            });
            snapshot.flash_lux =
                cig_scene::bolt::flash_lux_from(eye.to_ecef(), bolt.centre_ecef_m, k);
        } else if now - start > envelope.duration_s() || now < *start {
            over = true;
        }
    }
    if over {
        *own_bolt = None;
    }
}

/// Where the camera's view axis meets the terrain, within 30 km.
fn ground_ahead(q: &mut cig_terrain::QuerySession, camera: &FlyCamera) -> Option<Geodetic> {
    let (forward, _, _) = camera.orientation.axes_enu();
    let frame = cig_geo::EnuFrame::new(camera.eye);
    let end = frame.enu_to_geodetic(forward * 30_000.0);
    q.los(camera.eye, end).ok()?.hit.map(|h| h.point)
}

/// One shot of a scripted flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shot {
    /// Seconds after the first frame.
    pub at_s: f64,
    pub eye: Geodetic,
    pub orientation: Hpr,
    /// Simulation time, UTC seconds since 1970.
    pub unix_time_s: f64,
}

/// The script's pose at `t_s` seconds: linear between shots (headings the short way round),
/// `None` before the first frame or after the last shot.
pub fn scripted_pose(script: &[Shot], t_s: f64) -> Option<Shot> {
    let last = script.last()?;
    if t_s.is_nan() || t_s < 0.0 || t_s > last.at_s {
        return None;
    }
    let i = script.iter().position(|s| s.at_s >= t_s)?;
    let b = script[i];
    let Some(a) = i.checked_sub(1).map(|j| script[j]) else {
        return Some(b);
    };
    let span = (b.at_s - a.at_s).max(1e-9);
    let k = ((t_s - a.at_s) / span).clamp(0.0, 1.0);
    let lerp = |x: f64, y: f64| x + (y - x) * k;
    let dh =
        (b.orientation.heading_deg - a.orientation.heading_deg + 540.0).rem_euclid(360.0) - 180.0;
    Some(Shot {
        at_s: t_s,
        eye: Geodetic::new(
            lerp(a.eye.lat_deg, b.eye.lat_deg),
            lerp(a.eye.lon_deg, b.eye.lon_deg),
            lerp(a.eye.alt_m, b.eye.alt_m),
        ),
        orientation: Hpr {
            heading_deg: (a.orientation.heading_deg + dh * k).rem_euclid(360.0),
            pitch_deg: lerp(a.orientation.pitch_deg, b.orientation.pitch_deg),
            roll_deg: lerp(a.orientation.roll_deg, b.orientation.roll_deg),
        },
        unix_time_s: lerp(a.unix_time_s, b.unix_time_s),
    })
}

impl ViewerOptions {
    /// Options with the defaults of `cig view` for a first eyepoint and orientation.
    pub fn new(eye: Geodetic, orientation: Hpr) -> ViewerOptions {
        ViewerOptions {
            title: "cig view".into(),
            eye,
            orientation,
            horizontal_fov_deg: 60.0,
            width_px: 1280,
            height_px: 720,
            unix_time_s: 1_782_068_400.0, // 2026-06-21T19:00:00Z
            visibility_m: 40_000.0,
            fog_mode: FogMode::Exponential,
            max_pixel_error: 1.0,
            wireframe: false,
            speed_mps: 100.0,
            mesh_budget: FrameOptions::default().mesh_budget,
            exit_after_frames: None,
            capture_last_frame: false,
            script: Vec::new(),
            models: Vec::new(),
            overload: Some(cig_scene::overload::OverloadSettings::default()),
            natural_exposure: false,
            display_correction: None,
        }
    }

    fn view(&self, width_px: u32, height_px: u32, camera: &FlyCamera) -> View {
        View {
            eye: camera.eye,
            orientation: camera.orientation,
            fov: FovDeg::from_horizontal(self.horizontal_fov_deg, width_px, height_px),
            width_px,
            height_px,
        }
    }
}

/// What a viewer session did.
#[derive(Clone, Debug, Default)]
pub struct ViewerReport {
    /// Frames presented.
    pub frames: u64,
    /// Seconds from the first to the last frame presented.
    pub seconds: f64,
    /// The adapter, as [`Gpu::describe`] gives it.
    pub adapter: String,
    /// The format frames were drawn in.
    pub colour_format: String,
    pub last_stats: FrameStats,
    /// The last frame, when [`ViewerOptions::capture_last_frame`] was set and a frame was drawn.
    pub last_frame: Option<Image>,
}

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("no display to open a window on ({0})")]
    NoDisplay(String),
    #[error("the window cannot be drawn into: {0}")]
    Surface(String),
    #[error("the window system failed: {0}")]
    EventLoop(String),
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// Opens a window on the database behind `cache` and runs until it is closed (Esc, the
/// window's close button) or [`ViewerOptions::exit_after_frames`] frames have been shown.
/// Must be called on the main thread.
pub fn run_viewer(
    cache: Arc<TileCache>,
    options: ViewerOptions,
) -> Result<ViewerReport, ViewerError> {
    run_viewer_driven(cache, options, None)
}

/// As [`run_viewer`], with each frame's world (views, entities, time, fog) from `driver` when
/// one is given instead of the free camera and the panel's clock.
pub fn run_viewer_driven(
    cache: Arc<TileCache>,
    options: ViewerOptions,
    driver: Option<FrameDriver>,
) -> Result<ViewerReport, ViewerError> {
    options
        .view(
            options.width_px,
            options.height_px,
            &FlyCamera::new(options.eye, options.orientation, options.speed_mps),
        )
        .validate()
        .map_err(RenderError::from)?;
    let event_loop =
        EventLoop::new().map_err(|e| ViewerError::NoDisplay(plain_reason(&e.to_string())))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    // Start with the eye's active area resident, so the first frames show terrain.
    cache.update(&[options.eye]);
    cache.wait_idle();
    let mut app = App {
        camera: FlyCamera::new(options.eye, options.orientation, options.speed_mps),
        panel: PanelState::new(
            options.unix_time_s,
            options.visibility_m,
            options.fog_mode,
            options.max_pixel_error,
            options.wireframe,
        ),
        cache,
        options,
        running: None,
        error: None,
        report: ViewerReport::default(),
        first_frame: None,
        driver,
        effects: None,
        operator_plumes: Vec::new(),
        sent_cloud_layer: None,
        sent_sensor: None,
        sent_nvg: None,
        track_patches: Vec::new(),
        own_thermal: None,
        own_bolt: None,
        own_strikes: 0,
        puff_scratch: Vec::new(),
    };
    let run = event_loop.run_app(&mut app);
    if let Some(error) = app.error.take() {
        return Err(error);
    }
    run.map_err(|e| ViewerError::EventLoop(e.to_string()))?;
    if app.options.capture_last_frame {
        if let Some(running) = app.running.as_mut() {
            app.report.last_frame = running.capture()?;
        }
    }
    Ok(app.report)
}

struct App {
    cache: Arc<TileCache>,
    options: ViewerOptions,
    camera: FlyCamera,
    panel: PanelState,
    running: Option<Running>,
    error: Option<ViewerError>,
    report: ViewerReport,
    first_frame: Option<Instant>,
    driver: Option<FrameDriver>,
    /// The stand-alone viewer's own obscurants (a driven viewer's belong to its driver).
    effects: Option<cig_effects::EffectSystem>,
    operator_plumes: Vec<cig_effects::EffectHandle>,
    /// With a driver: the panel's cloud layer last sent to it (`None`: nothing sent yet).
    sent_cloud_layer: Option<Option<cig_environment::CloudLayer>>,
    /// The trackers' gates read back from the last frame drawn, for the driver's next tick.
    track_patches: Vec<(usize, [u32; 4], Vec<f32>)>,
    /// The operator's sensor last sent to the driver.
    sent_sensor: Option<Option<cig_scene::thermal::SensorView>>,
    /// The operator's goggle last sent to the driver.
    sent_nvg: Option<Option<cig_scene::nvg::NvgView>>,
    /// Without a driver, the thermal state the panel's sensor draws (spun up when first
    /// chosen, at the camera's place).
    own_thermal: Option<cig_thermal::SurfaceTable>,
    /// Without a driver: the operator's last lightning strike (its time and bolt).
    own_bolt: Option<(f64, cig_scene::bolt::MadeBolt)>,
    own_strikes: u64,
    puff_scratch: Vec<cig_effects::PuffInstance>,
}

/// What was drawn last, to re-draw it off-screen for a screenshot.
struct LastFrame {
    snapshot: FrameSnapshot,
    paint_jobs: Vec<egui::ClippedPrimitive>,
    pixels_per_point: f32,
    /// Seconds since the previous frame (the eye's adaptation advances by it).
    dt_s: f64,
}

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    formats: Formats,
    gpu: Arc<Gpu>,
    renderer: Renderer,
    cache: Arc<TileCache>,
    /// The viewer's terrain questions (the free camera's clearance, the ground ahead), one
    /// session for the window's life.
    query: cig_terrain::QuerySession,
    mesh_budget: usize,
    natural_exposure: bool,
    /// The display correction into the window's panel view, and the frame it reads (remade
    /// at the window's size).
    display: Option<crate::display::DisplayPass>,
    corrected_frame: Option<wgpu::Texture>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    gpu_errors: Arc<Mutex<Option<String>>>,
    keys: HashSet<KeyCode>,
    dragging: Option<MouseButton>,
    cursor: Option<PhysicalPosition<f64>>,
    last_frame_at: Instant,
    fps_window: (Instant, u32),
    info: FrameInfo,
    last: Option<LastFrame>,
}

/// A winit error without the source location winit puts in front ("os error at FILE:LINE: ").
fn plain_reason(text: &str) -> String {
    let reason = text
        .find(".rs:")
        .and_then(|i| text.get(i + 4..))
        .and_then(|after| after.find(": ").and_then(|j| after.get(j + 2..)))
        .unwrap_or(text);
    reason.trim().trim_end_matches('.').to_string()
}

/// The formats of a window's frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Formats {
    /// The surface's own format.
    surface: wgpu::TextureFormat,
    /// The view the terrain is drawn through: sRGB, so linear light is encoded on store.
    scene: wgpu::TextureFormat,
    /// The view egui draws through: the same texels without sRGB encoding where the surface
    /// allows a second view format (egui blends in gamma space), else the scene's.
    panel: wgpu::TextureFormat,
}

impl Formats {
    /// An sRGB format the surface supports, else an sRGB view of its first format (when
    /// `view_formats_supported`, the surface's texels can be seen through another format that
    /// differs only in sRGB encoding).
    fn choose(formats: &[wgpu::TextureFormat], view_formats_supported: bool) -> Option<Formats> {
        let surface = formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| formats.first().copied())?;
        let (scene, panel) = if view_formats_supported {
            (surface.add_srgb_suffix(), surface.remove_srgb_suffix())
        } else {
            (surface, surface)
        };
        Some(Formats {
            surface,
            scene,
            panel,
        })
    }

    /// The (scene, panel) views of a texture of the surface's format.
    fn views(&self, texture: &wgpu::Texture) -> (wgpu::TextureView, wgpu::TextureView) {
        let view = |format| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(format),
                ..Default::default()
            })
        };
        (view(self.scene), view(self.panel))
    }

    /// The formats other than the surface's that its textures are viewed through.
    fn extra_view_formats(&self) -> Vec<wgpu::TextureFormat> {
        let mut extra: Vec<wgpu::TextureFormat> = [self.scene, self.panel]
            .into_iter()
            .filter(|f| *f != self.surface)
            .collect();
        extra.dedup();
        extra
    }
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<Running, ViewerError> {
        let attributes = Window::default_attributes()
            .with_title(self.options.title.clone())
            .with_inner_size(PhysicalSize::new(
                self.options.width_px,
                self.options.height_px,
            ));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewerError::NoDisplay(plain_reason(&e.to_string())))?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| ViewerError::Surface(e.to_string()))?;
        let gpu = Gpu::with_instance(instance, Some(&surface))?;
        let gpu_errors = Arc::new(Mutex::new(None));
        {
            let gpu_errors = Arc::clone(&gpu_errors);
            gpu.device
                .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                    if let Ok(mut slot) = gpu_errors.lock() {
                        slot.get_or_insert_with(|| e.to_string().replace('\n', " "));
                    }
                }));
        }
        let capabilities = surface.get_capabilities(&gpu.adapter);
        let view_formats_supported = gpu
            .adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::SURFACE_VIEW_FORMATS);
        let formats =
            Formats::choose(&capabilities.formats, view_formats_supported).ok_or_else(|| {
                ViewerError::Surface(format!(
                    "the adapter {} cannot present to this window",
                    gpu.describe()
                ))
            })?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format: formats.surface,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: capabilities
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: formats.extra_view_formats(),
        };
        surface.configure(&gpu.device, &config);
        if !formats.scene.is_srgb() {
            tracing::warn!(
                format = ?formats.scene,
                "the window has no sRGB format: colours will look too dark"
            );
        }
        let mut renderer = Renderer::new(Arc::clone(&gpu), &self.cache, formats.scene);
        if !self.options.models.is_empty() {
            renderer.set_models(self.options.models.clone());
        }
        renderer
            .set_overload(self.options.overload)
            .map_err(|e| RenderError::Gpu(format!("bad overload settings: {e}")))?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, formats.panel, Default::default());
        self.report.adapter = gpu.describe();
        self.report.colour_format = format!("{:?}", formats.scene);
        let info = FrameInfo {
            adapter: gpu.describe(),
            wireframe_supported: gpu
                .device
                .features()
                .contains(wgpu::Features::POLYGON_MODE_LINE),
            ..Default::default()
        };
        tracing::info!(
            adapter = %gpu.describe(),
            formats = ?formats,
            width = config.width,
            height = config.height,
            "viewer window ready"
        );
        let now = Instant::now();
        let display = self
            .options
            .display_correction
            .clone()
            .filter(|c| !c.is_none())
            .map(|c| {
                // The frame is drawn through the scene's view and read through the plain one.
                crate::display::DisplayPass::with_formats(&gpu, c, formats.panel, formats.panel)
            });
        Ok(Running {
            window,
            surface,
            config,
            formats,
            gpu,
            renderer,
            cache: Arc::clone(&self.cache),
            query: cig_terrain::QuerySession::new(Arc::clone(&self.cache)),
            mesh_budget: self.options.mesh_budget,
            natural_exposure: self.options.natural_exposure,
            display,
            corrected_frame: None,
            egui_ctx,
            egui_state,
            egui_renderer,
            gpu_errors,
            keys: HashSet::new(),
            dragging: None,
            cursor: None,
            last_frame_at: now,
            fps_window: (now, 0),
            info,
            last: None,
        })
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewerError) {
        if self.error.is_none() {
            self.error = Some(error);
        }
        event_loop.exit();
    }

    /// One frame; `Ok(false)` when nothing was presented.
    fn frame(&mut self) -> Result<bool, ViewerError> {
        let Some(r) = self.running.as_mut() else {
            return Ok(false);
        };
        let now = Instant::now();
        let dt_s = (now - r.last_frame_at).as_secs_f64().min(1.0);
        r.last_frame_at = now;
        let size = r.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(false);
        }
        if (size.width, size.height) != (r.config.width, r.config.height) {
            r.resize(size);
        }
        let held = |codes: &[KeyCode]| codes.iter().any(|c| r.keys.contains(c));
        let axis = |plus: &[KeyCode], minus: &[KeyCode]| {
            f64::from(u8::from(held(plus))) - f64::from(u8::from(held(minus)))
        };
        let input = MoveInput {
            forward: axis(
                &[KeyCode::KeyW, KeyCode::ArrowUp],
                &[KeyCode::KeyS, KeyCode::ArrowDown],
            ),
            right: axis(
                &[KeyCode::KeyD, KeyCode::ArrowRight],
                &[KeyCode::KeyA, KeyCode::ArrowLeft],
            ),
            up: axis(
                &[KeyCode::KeyE, KeyCode::PageUp],
                &[KeyCode::KeyQ, KeyCode::PageDown],
            ),
            fast: held(&[KeyCode::ShiftLeft, KeyCode::ShiftRight]),
        };
        self.camera.fly(input, dt_s);
        if self.driver.is_none() {
            // The free camera does not fly into the ground: an eye that would go below the
            // terrain stays on its surface (a query may load one finest tile here).
            if let Ok(hat_m) = r.query.hat_m(self.camera.eye) {
                let clearance_m = cig_scene::snapshot::EYE_CLEARANCE_M;
                if hat_m.is_finite() && hat_m < clearance_m {
                    self.camera.eye.alt_m += clearance_m - hat_m;
                }
            }
        }
        self.panel.advance(dt_s);
        let script_t_s = self.first_frame.map_or(0.0, |f| (now - f).as_secs_f64());
        if let Some(shot) = scripted_pose(&self.options.script, script_t_s) {
            self.camera.eye = shot.eye;
            self.camera.orientation = shot.orientation;
            self.panel.unix_time_s = shot.unix_time_s;
        }
        r.cache.update(&[self.camera.eye]);

        let surface_texture = match r.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                // Draw this one; the next frame reconfigures.
                r.config.width = 0;
                t
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(false)
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                r.resize(size);
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(r.gpu_error().unwrap_or_else(|| {
                    ViewerError::Surface("the surface texture could not be acquired".into())
                }))
            }
        };
        let targets = r.formats.views(&surface_texture.texture);
        let (width_px, height_px) = (
            surface_texture.texture.width(),
            surface_texture.texture.height(),
        );

        r.info.fast = input.fast;
        let raw_input = r.egui_state.take_egui_input(&r.window);
        let panel = &mut self.panel;
        let camera = &mut self.camera;
        let info = &r.info;
        let output = r
            .egui_ctx
            .run_pass(raw_input, |ctx| panel.ui(ctx, camera, info));
        r.egui_state
            .handle_platform_output(&r.window, output.platform_output);
        let paint_jobs = r
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        // Take egui's texture changes out at once (a delta dropped unapplied is a bug to egui).
        let mut textures_delta = output.textures_delta;
        let texture_updates: Vec<_> = textures_delta.set.drain().collect();
        let textures_to_free: Vec<egui::TextureId> = textures_delta.free.drain().collect();
        textures_delta.clear();
        for (id, deltas) in &texture_updates {
            for delta in deltas {
                r.egui_renderer
                    .update_texture(&r.gpu.device, &r.gpu.queue, *id, delta);
            }
        }

        let mut orders = Vec::new();
        for command in self.panel.take_commands() {
            match command {
                ObscurantCommand::StartPlume {
                    flame,
                    heat_release_w,
                } => match ground_ahead(&mut r.query, &self.camera) {
                    Some(at) => orders.push(ObscurantOrder::StartPlume {
                        at,
                        flame,
                        heat_release_w,
                    }),
                    None => {
                        self.panel.obscurant_note =
                            "no ground within 30 km at the centre of the view".into();
                    }
                },
                ObscurantCommand::StopPlumes => orders.push(ObscurantOrder::StopPlumes),
                ObscurantCommand::SetPrecipitation(p) => {
                    orders.push(ObscurantOrder::SetPrecipitation(p));
                }
                ObscurantCommand::StrikeLightning => match ground_ahead(&mut r.query, &self.camera)
                {
                    Some(at) => orders.push(ObscurantOrder::StrikeLightning { at }),
                    None => {
                        self.panel.obscurant_note =
                            "no ground within 30 km at the centre of the view".into();
                    }
                },
                ObscurantCommand::SetStorm { strikes_per_minute } => {
                    orders.push(ObscurantOrder::SetStorm {
                        centre: self.camera.eye,
                        strikes_per_minute,
                    });
                }
                ObscurantCommand::SetWind {
                    speed_mps,
                    from_deg,
                } => orders.push(ObscurantOrder::SetWind {
                    speed_mps,
                    from_deg,
                }),
            }
        }
        // The panel's cloud layer goes to the world whenever it changes (with a driver, the
        // world's clouds are the snapshot's, so the host's weather answers and the smoke's
        // ceiling see the operator's layer too).
        let cloud_layer = self.panel.cloud_layer();
        if self.driver.is_some() && self.sent_cloud_layer != Some(cloud_layer) {
            orders.push(ObscurantOrder::SetClouds(cloud_layer));
            self.sent_cloud_layer = Some(cloud_layer);
        }
        let sensor = self.panel.sensor_view();
        if self.driver.is_some() && self.sent_sensor != Some(sensor) {
            orders.push(ObscurantOrder::SetSensor(sensor));
            self.sent_sensor = Some(sensor);
        }
        let nvg = self.panel.nvg_view();
        if self.driver.is_some() && self.sent_nvg != Some(nvg) {
            orders.push(ObscurantOrder::SetNvg(nvg));
            self.sent_nvg = Some(nvg);
        }
        let mut snapshot = match self.driver.as_mut() {
            Some(driver) => {
                let snapshot = driver(&ViewerTick {
                    dt_s,
                    width_px,
                    height_px,
                    orders,
                    track_patches: std::mem::take(&mut self.track_patches),
                });
                if let Some(first) = snapshot.views.first() {
                    self.camera.eye = first.eye;
                    self.camera.orientation = first.orientation;
                    self.panel.unix_time_s = snapshot.unix_time_s;
                    r.cache
                        .update(&snapshot.views.iter().map(|v| v.eye).collect::<Vec<_>>());
                }
                snapshot
            }
            None => {
                let mut snapshot = FrameSnapshot::new(
                    self.panel.unix_time_s,
                    vec![self.options.view(width_px, height_px, &self.camera)],
                );
                snapshot.fog = self.panel.fog();
                snapshot.ground_fog = self.panel.ground_fog();
                own_weather(
                    &mut self.panel,
                    self.camera.eye,
                    &mut self.own_bolt,
                    &mut self.own_strikes,
                    &orders,
                    &mut snapshot,
                );
                let note = run_own_obscurants(
                    &mut self.effects,
                    &mut self.operator_plumes,
                    &orders,
                    cig_effects::effect_time_s(self.panel.unix_time_s),
                    (self.panel.wind_speed_mps, self.panel.wind_from_deg),
                );
                if let Some(note) = note {
                    self.panel.obscurant_note = note;
                }
                if let Some(effects) = &self.effects {
                    let origin = self.camera.eye.to_ecef();
                    effects.snapshot(origin, &mut self.puff_scratch);
                    snapshot.puffs.clone_from(&self.puff_scratch);
                    snapshot.puff_origin_ecef_m = origin;
                }
                snapshot
            }
        };
        if self.driver.is_none() {
            // The stand-alone viewer's clouds are anchored at its starting eye's whole degrees.
            snapshot.cloud_origin = cig_environment::CloudOrigin {
                lat_deg: self.options.eye.lat_deg.round(),
                lon_deg: self.options.eye.lon_deg.round(),
            };
        }
        // Without a driver, the operator's cloud layer is the frame's.
        if let (None, Some(layer)) = (self.driver.as_ref(), cloud_layer) {
            snapshot.cloud_layers = vec![layer];
            snapshot.cloud_cover_fraction =
                cig_environment::cloud_cover_fraction(&snapshot.cloud_layers);
        }
        if let (None, Some(sensor)) = (self.driver.as_ref(), sensor) {
            own_sensor(
                &mut self.own_thermal,
                self.camera.eye,
                self.panel.unix_time_s,
                sensor,
                &mut snapshot,
            );
        }
        // Without a driver, the panel's goggle draws every view.
        if let (None, Some(nvg)) = (self.driver.as_ref(), nvg) {
            snapshot.nvg = vec![Some(nvg); snapshot.views.len()];
        }
        snapshot.max_pixel_error = self.panel.max_pixel_error;
        snapshot.wireframe = self.panel.wireframe;
        snapshot.sky.exposure_compensation_ev += self.panel.exposure_compensation_ev;
        snapshot.stars_visible = self.panel.stars;
        let last = LastFrame {
            snapshot,
            paint_jobs,
            pixels_per_point: output.pixels_per_point,
            dt_s,
        };
        let stats = r.draw(&last, &targets)?;
        // The window shows the first view: its trackers' gates go back to the driver.
        for (index, gate) in last.snapshot.track_gates.iter().filter(|g| g.0 == 0) {
            match r.renderer.read_scene_region(*gate) {
                Ok(values) => self.track_patches.push((*index, *gate, values)),
                Err(e) => tracing::debug!("a tracker's gate was not read back: {e}"),
            }
        }
        r.window.pre_present_notify();
        r.gpu.queue.present(surface_texture);
        for id in &textures_to_free {
            r.egui_renderer.free_texture(id);
        }
        r.last = Some(last);
        if let Some(e) = r.gpu_error() {
            return Err(e);
        }

        r.fps_window.1 += 1;
        let window_s = (now - r.fps_window.0).as_secs_f64();
        if window_s >= 0.5 {
            r.info.fps = f64::from(r.fps_window.1) / window_s;
            r.fps_window = (now, 0);
        }
        r.info.width_px = width_px;
        r.info.height_px = height_px;
        r.info.stats = stats.clone();
        self.report.last_stats = stats;
        self.report.frames += 1;
        let first = *self.first_frame.get_or_insert(now);
        self.report.seconds = (now - first).as_secs_f64();
        Ok(true)
    }
}

impl Running {
    fn resize(&mut self, size: PhysicalSize<u32>) {
        if size.width == 0 || size.height == 0 {
            return;
        }
        self.config.width = size.width;
        self.config.height = size.height;
        self.surface.configure(&self.gpu.device, &self.config);
    }

    fn gpu_error(&self) -> Option<ViewerError> {
        let message = self.gpu_errors.lock().ok()?.take()?;
        Some(ViewerError::Render(RenderError::Gpu(message)))
    }

    /// Draws the terrain view, then the panel over it, into the (scene, panel) views of one
    /// texture.
    fn draw(
        &mut self,
        frame: &LastFrame,
        targets: &(wgpu::TextureView, wgpu::TextureView),
    ) -> Result<FrameStats, ViewerError> {
        let view = frame.snapshot.views.first().copied();
        // With a display correction the view is drawn off-screen first, then warped and
        // blended into the window.
        let size = view.map_or((1, 1), |v| (v.width_px, v.height_px));
        if self.display.is_some()
            && self
                .corrected_frame
                .as_ref()
                .is_none_or(|t| (t.width(), t.height()) != size)
        {
            self.corrected_frame = Some(crate::gpu::render_target(
                &self.gpu.device,
                "frame before the display correction",
                size,
                self.formats.surface,
                1,
                wgpu::TextureUsages::TEXTURE_BINDING,
                &self.formats.extra_view_formats(),
            ));
        }
        let offscreen = match (&self.display, &self.corrected_frame) {
            (Some(_), Some(texture)) => Some(self.formats.views(texture)),
            _ => None,
        };
        let stats = self.renderer.render(
            &self.cache,
            &frame.snapshot,
            0,
            offscreen.as_ref().map_or(&targets.0, |views| &views.0),
            FrameOptions {
                mesh_budget: self.mesh_budget,
                key_background: false,
                adaptation: if self.natural_exposure {
                    crate::adaptation::Adaptation::Off
                } else {
                    crate::adaptation::Adaptation::Step(frame.dt_s as f32)
                },
                ..FrameOptions::default()
            },
        )?;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: view.map_or([1, 1], |v| [v.width_px, v.height_px]),
            pixels_per_point: frame.pixels_per_point,
        };
        let device = &self.gpu.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("panel"),
        });
        if let (Some(display), Some(views)) = (&self.display, &offscreen) {
            display.record(&self.gpu, &mut encoder, &views.1, size, &targets.1, size);
        }
        let mut commands = self.egui_renderer.update_buffers(
            device,
            &self.gpu.queue,
            &mut encoder,
            &frame.paint_jobs,
            &screen,
        );
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("panel"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &targets.1,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            self.egui_renderer
                .render(&mut pass, &frame.paint_jobs, &screen);
        }
        commands.push(encoder.finish());
        self.gpu.queue.submit(commands);
        Ok(stats)
    }

    /// Re-draws the last frame off-screen and reads it back (RGBA, sRGB).
    fn capture(&mut self) -> Result<Option<Image>, ViewerError> {
        let Some(last) = self.last.take() else {
            return Ok(None);
        };
        let Some(view) = last.snapshot.views.first().copied() else {
            return Ok(None);
        };
        let (width, height) = (view.width_px, view.height_px);
        let device = &self.gpu.device;
        let texture = crate::gpu::render_target(
            device,
            "screenshot",
            (width, height),
            self.formats.surface,
            1,
            wgpu::TextureUsages::COPY_SRC,
            &self.formats.extra_view_formats(),
        );
        let targets = self.formats.views(&texture);
        self.draw(&last, &targets)?;
        let image = crate::offscreen::read_rgba(&self.gpu, &texture)?;
        if let Some(e) = self.gpu_error() {
            return Err(e);
        }
        Ok(Some(image))
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() || self.error.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(running) => self.running = Some(running),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(
        &mut self,
        event_loop: &ActiveEventLoop,
        window_id: WindowId,
        event: WindowEvent,
    ) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        if window_id != r.window.id() {
            return;
        }
        let response = r.egui_state.on_window_event(&r.window, &event);
        let egui_has_keyboard = r.egui_ctx.egui_wants_keyboard_input();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => r.resize(size),
            WindowEvent::Focused(false) => {
                r.keys.clear();
                r.dragging = None;
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                match event.state {
                    ElementState::Pressed => {
                        if code == KeyCode::Escape && !egui_has_keyboard {
                            event_loop.exit();
                        } else if !response.consumed && !egui_has_keyboard {
                            r.keys.insert(code);
                        }
                    }
                    ElementState::Released => {
                        r.keys.remove(&code);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => match state {
                ElementState::Pressed
                    if matches!(button, MouseButton::Left | MouseButton::Right)
                        && !response.consumed
                        && !r.egui_ctx.is_pointer_over_egui() =>
                {
                    r.dragging = Some(button);
                }
                ElementState::Released if r.dragging == Some(button) => r.dragging = None,
                _ => {}
            },
            WindowEvent::CursorMoved { position, .. } => {
                if let (Some(_), Some(previous)) = (r.dragging, r.cursor) {
                    // Look the way the mouse moves, at the view's own angular scale.
                    let degrees_per_pixel =
                        self.options.horizontal_fov_deg / f64::from(r.config.width.max(1));
                    self.camera.look(
                        (position.x - previous.x) * degrees_per_pixel,
                        -(position.y - previous.y) * degrees_per_pixel,
                    );
                }
                r.cursor = Some(position);
            }
            WindowEvent::CursorLeft { .. } => r.cursor = None,
            WindowEvent::MouseWheel { delta, .. } if !r.egui_ctx.is_pointer_over_egui() => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.camera.scale_speed(notches);
                tracing::debug!(?delta, speed_mps = self.camera.speed_mps, "mouse wheel");
            }
            WindowEvent::RedrawRequested => {
                let presented = self.frame();
                match presented {
                    Ok(true) => {
                        if let Some(limit) = self.options.exit_after_frames {
                            if self.report.frames >= limit {
                                event_loop.exit();
                            }
                        }
                    }
                    Ok(false) => {}
                    Err(e) => self.fail(event_loop, e),
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(r) = self.running.as_ref() {
            let size = r.window.inner_size();
            if size.width == 0 || size.height == 0 {
                // Minimised: nothing to draw; look again a little later rather than spin.
                event_loop.set_control_flow(ControlFlow::WaitUntil(
                    Instant::now() + std::time::Duration::from_millis(100),
                ));
            } else {
                event_loop.set_control_flow(ControlFlow::Poll);
            }
            r.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_srgb_surface_format_is_preferred_and_egui_gets_a_linear_view() {
        use wgpu::TextureFormat as F;
        let formats = |surface, scene, panel| {
            Some(Formats {
                surface,
                scene,
                panel,
            })
        };
        let f = Formats::choose(&[F::Bgra8Unorm, F::Bgra8UnormSrgb], true);
        assert_eq!(
            f,
            formats(F::Bgra8UnormSrgb, F::Bgra8UnormSrgb, F::Bgra8Unorm)
        );
        assert_eq!(f.map(|f| f.extra_view_formats()), Some(vec![F::Bgra8Unorm]));
        assert_eq!(
            Formats::choose(&[F::Bgra8Unorm, F::Bgra8UnormSrgb], false),
            formats(F::Bgra8UnormSrgb, F::Bgra8UnormSrgb, F::Bgra8UnormSrgb)
        );
        let f = Formats::choose(&[F::Rgba8Unorm], true);
        assert_eq!(f, formats(F::Rgba8Unorm, F::Rgba8UnormSrgb, F::Rgba8Unorm));
        assert_eq!(
            f.map(|f| f.extra_view_formats()),
            Some(vec![F::Rgba8UnormSrgb])
        );
        assert_eq!(Formats::choose(&[], true), None);
    }

    #[test]
    fn winit_source_locations_are_dropped_from_reasons() {
        assert_eq!(
            plain_reason(
                "os error at /src/linux/mod.rs:788: Failed to open connection to X server."
            ),
            "Failed to open connection to X server"
        );
        assert_eq!(plain_reason("no display"), "no display");
    }
}

#[cfg(test)]
mod script_tests {
    use super::*;

    #[test]
    fn the_script_interpolates_between_shots_and_ends_after_the_last() {
        let shot = |at_s: f64, lat: f64, heading_deg: f64, t: f64| Shot {
            at_s,
            eye: Geodetic::new(lat, -121.0, 500.0),
            orientation: Hpr {
                heading_deg,
                ..Default::default()
            },
            unix_time_s: t,
        };
        let script = [shot(0.0, 36.0, 350.0, 100.0), shot(2.0, 36.1, 10.0, 300.0)];
        let mid = scripted_pose(&script, 1.0).expect("inside");
        assert!((mid.eye.lat_deg - 36.05).abs() < 1e-12);
        assert!(
            (mid.orientation.heading_deg - 0.0).abs() < 1e-9
                || (mid.orientation.heading_deg - 360.0).abs() < 1e-9
        );
        assert!((mid.unix_time_s - 200.0).abs() < 1e-9);
        assert_eq!(
            scripted_pose(&script, 0.0).map(|s| s.eye),
            Some(script[0].eye)
        );
        assert!(scripted_pose(&script, 2.5).is_none());
        assert!(scripted_pose(&[], 0.0).is_none());
        assert!(scripted_pose(&script, f64::NAN).is_none());
    }
}

/// The stand-alone viewer's obscurants: carries out the operator's orders and advances them to
/// effect time `t_s` (starting over when the panel's clock goes back). Returns a note for the
/// panel when an order could not be carried out.
fn run_own_obscurants(
    effects: &mut Option<cig_effects::EffectSystem>,
    plumes: &mut Vec<cig_effects::EffectHandle>,
    orders: &[ObscurantOrder],
    t_s: f64,
    (wind_speed_mps, wind_from_deg): (f64, f64),
) -> Option<String> {
    let mut note = None;
    if effects.is_none() && !orders.is_empty() {
        match cig_effects::EffectSystem::new(cig_effects::EffectsConfig::default()) {
            Ok(system) => *effects = Some(system),
            Err(e) => return Some(format!("obscurants unavailable: {e}")),
        }
    }
    let system = effects.as_mut()?;
    if system.time_s().is_some_and(|now| t_s < now - 1.0) {
        // The clock went back: start over (the plumes' past is not kept).
        match cig_effects::EffectSystem::new(*system.config()) {
            Ok(fresh) => {
                *system = fresh;
                plumes.clear();
                note = Some("the clock went back: the plumes start over".into());
                // The panel's wind still holds.
                let mut air = *system.atmosphere();
                air.wind = cig_effects::system::Wind {
                    speed_mps: wind_speed_mps,
                    from_deg: wind_from_deg,
                };
                let _ = system.set_atmosphere(air);
            }
            Err(e) => return Some(format!("obscurants cannot start over: {e}")),
        }
    }
    if let Err(e) = system.advance_to(t_s) {
        return Some(format!("obscurants stopped: {e}"));
    }
    for order in orders {
        match *order {
            ObscurantOrder::StartPlume {
                at,
                flame,
                heat_release_w,
            } => {
                let id = cig_effects::EffectId(0x5649_4557_0000_0000 | plumes.len() as u64);
                let spec = cig_effects::system::PlumeSpec {
                    id,
                    kind: if flame {
                        cig_effects::system::PlumeKind::Flame
                    } else {
                        cig_effects::system::PlumeKind::Smoke
                    },
                    position: at,
                    size_m: 5.0,
                    source: cig_effects::system::PlumeSource::HeatReleaseW(heat_release_w),
                    start_time_s: t_s,
                    duration_s: 3600.0,
                };
                match system.start_plume(&spec) {
                    Ok(h) => {
                        plumes.push(h);
                        note = Some(format!(
                            "{} at {:.5}, {:.5}",
                            if flame { "fire" } else { "smoke" },
                            at.lat_deg,
                            at.lon_deg
                        ));
                    }
                    Err(e) => note = Some(format!("cannot start: {e}")),
                }
            }
            ObscurantOrder::StopPlumes => {
                for h in plumes.drain(..) {
                    let _ = system.stop(h, t_s);
                }
            }
            ObscurantOrder::SetWind {
                speed_mps,
                from_deg,
            } => {
                let mut air = *system.atmosphere();
                air.wind = cig_effects::system::Wind {
                    speed_mps,
                    from_deg,
                };
                if let Err(e) = system.set_atmosphere(air) {
                    note = Some(format!("wind refused: {e}"));
                }
            }
            // Weather and sensor orders are not the obscurants' ([`own_weather`],
            // [`own_sensor`]).
            ObscurantOrder::SetPrecipitation(_)
            | ObscurantOrder::StrikeLightning { .. }
            | ObscurantOrder::SetStorm { .. }
            | ObscurantOrder::SetClouds(_)
            | ObscurantOrder::SetSensor(_)
            | ObscurantOrder::SetNvg(_) => {}
        }
    }
    note
}

#[cfg(test)]
mod obscurant_tests {
    use super::*;

    const WIND: (f64, f64) = (3.0, 270.0);

    #[test]
    fn operator_orders_start_stop_and_blow_plumes_and_a_clock_set_back_starts_over() {
        let mut effects = None;
        let mut plumes = Vec::new();
        let at = Geodetic::new(36.0, -121.0, 100.0);
        let start = ObscurantOrder::StartPlume {
            at,
            flame: false,
            heat_release_w: 4.0e6,
        };
        assert!(run_own_obscurants(&mut effects, &mut plumes, &[], 0.0, WIND).is_none());
        assert!(effects.is_none(), "no system until the first order");
        let note = run_own_obscurants(&mut effects, &mut plumes, &[start], 100.0, WIND);
        assert!(note.is_some_and(|n| n.starts_with("smoke at")));
        assert_eq!(plumes.len(), 1);
        let wind = ObscurantOrder::SetWind {
            speed_mps: 12.0,
            from_deg: 45.0,
        };
        run_own_obscurants(&mut effects, &mut plumes, &[wind], 101.0, (12.0, 45.0));
        let system = effects.as_ref().expect("system");
        assert_eq!(system.atmosphere().wind.speed_mps, 12.0);
        for i in 0..60 {
            run_own_obscurants(
                &mut effects,
                &mut plumes,
                &[],
                101.0 + f64::from(i),
                (12.0, 45.0),
            );
        }
        let spawned = effects.as_ref().map_or(0, |e| e.stats().spawned_total);
        assert!(spawned > 0);
        run_own_obscurants(
            &mut effects,
            &mut plumes,
            &[ObscurantOrder::StopPlumes],
            161.0,
            (12.0, 45.0),
        );
        assert!(plumes.is_empty());
        run_own_obscurants(&mut effects, &mut plumes, &[start], 162.0, (12.0, 45.0));
        // The panel's clock set back an hour: the obscurants start over, empty.
        let note = run_own_obscurants(&mut effects, &mut plumes, &[], 162.0 - 3600.0, (12.0, 45.0));
        assert!(note.is_some_and(|n| n.contains("went back")));
        assert!(plumes.is_empty());
        assert_eq!(effects.as_ref().map(|e| e.stats().spawned_total), Some(0));
        // The wind the panel shows still blows.
        assert_eq!(
            effects.as_ref().map(|e| e.atmosphere().wind.speed_mps),
            Some(12.0)
        );
    }
}
