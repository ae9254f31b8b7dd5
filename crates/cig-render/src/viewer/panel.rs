//! The viewer's operator panel: time of day, visibility and fog, level of detail, wireframe and
//! frame statistics, drawn with egui.
//!
//! Algorithm: the panel edits a plain [`PanelState`] that the frame loop turns into the
//! [`cig_scene::FrameSnapshot`] of the next frame. Simulation time is UTC seconds since 1970; it
//! advances by `rate` simulated minutes per real minute. The date shown and typed is the
//! proleptic Gregorian calendar of the `time` crate (years 1..9999 accepted). Visibility sets the fog
//! through Koschmieder's law ([`cig_scene::lighting::Fog::from_visibility`]).
//!
//! Limits: time zones are not shown (the slider is UTC); leap seconds are ignored, as in Unix
//! time.

use crate::renderer::serde_like::FrameStats;
use crate::viewer::camera::FlyCamera;
use cig_environment::clouds::{CloudKind, CloudLayer};
use cig_scene::lighting::{Fog, FogMode};

/// Seconds in a day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;
/// Visibility slider range, metres.
pub const VISIBILITY_RANGE_M: (f64, f64) = (50.0, 500_000.0);
/// Level-of-detail threshold range, pixels.
pub const MAX_PIXEL_ERROR_RANGE_PX: (f64, f64) = (0.0, 8.0);
/// Time rate range, simulated minutes per real minute.
pub const RATE_RANGE: (f64, f64) = (0.0, 1440.0);

/// The `time` crate's Julian day number of 1970-01-01.
const UNIX_EPOCH_JULIAN_DAY: i64 = 2_440_588;

/// Days since 1970-01-01 of a proleptic Gregorian date; `None` for a date that does not exist.
pub fn days_from_civil(year: i64, month: u32, day: u32) -> Option<i64> {
    let month = time::Month::try_from(u8::try_from(month).ok()?).ok()?;
    let date =
        time::Date::from_calendar_date(i32::try_from(year).ok()?, month, u8::try_from(day).ok()?)
            .ok()?;
    Some(i64::from(date.to_julian_day()) - UNIX_EPOCH_JULIAN_DAY)
}

/// The proleptic Gregorian date (year, month, day) of a day count since 1970-01-01, clamped
/// to the `time` crate's range.
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let julian = (days + UNIX_EPOCH_JULIAN_DAY).clamp(
        i64::from(time::Date::MIN.to_julian_day()),
        i64::from(time::Date::MAX.to_julian_day()),
    ) as i32;
    let date = time::Date::from_julian_day(julian).unwrap_or(time::Date::MIN);
    (
        i64::from(date.year()),
        u32::from(u8::from(date.month())),
        u32::from(date.day()),
    )
}

/// Parses "YYYY-MM-DD" (years 1..=9999) into days since 1970-01-01.
pub fn parse_date(text: &str) -> Option<i64> {
    let mut parts = text.trim().splitn(3, '-');
    let year: i64 = parts.next()?.trim().parse().ok()?;
    let month: u32 = parts.next()?.trim().parse().ok()?;
    let day: u32 = parts.next()?.trim().parse().ok()?;
    if !(1..=9999).contains(&year) {
        return None;
    }
    days_from_civil(year, month, day)
}

/// "YYYY-MM-DD" of a day count since 1970-01-01.
pub fn format_date(days: i64) -> String {
    let (y, m, d) = civil_from_days(days);
    format!("{y:04}-{m:02}-{d:02}")
}

/// "HH:MM:SS" of seconds into the day.
pub fn format_time_of_day(seconds: f64) -> String {
    let s = seconds.clamp(0.0, SECONDS_PER_DAY - 1.0) as u32;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// What the operator has set.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelState {
    /// Simulation time, UTC seconds since 1970.
    pub unix_time_s: f64,
    /// Simulated minutes per real minute (0 stops the clock).
    pub rate: f64,
    pub visibility_m: f64,
    pub fog_mode: FogMode,
    pub max_pixel_error: f64,
    pub wireframe: bool,
    /// A ground fog layer: on, its top (metres above the ellipsoid) and the visibility in it.
    pub ground_fog: bool,
    pub ground_fog_top_m: f64,
    pub ground_fog_visibility_m: f64,
    /// Added to the automatic exposure, EV.
    pub exposure_compensation_ev: f64,
    /// Draw the stars (they still fade by themselves in daylight).
    pub stars: bool,
    /// Heat release of the next plume the operator starts, MW.
    pub plume_heat_mw: f64,
    /// The next plume is a fire (flame) rather than smoke.
    pub plume_flame: bool,
    /// Wind for the obscurants: speed, and the direction it blows from.
    pub wind_speed_mps: f64,
    pub wind_from_deg: f64,
    /// A line about the last obscurant order (e.g. why it could not be done).
    pub obscurant_note: String,
    /// One cloud layer: on, base (metres above mean sea level; the stand-alone viewer draws it
    /// above the ellipsoid), thickness, coverage, kind, and
    /// the wind it drifts in. When on, it replaces the world's clouds.
    pub clouds: bool,
    pub cloud_base_m: f64,
    pub cloud_thickness_m: f64,
    pub cloud_coverage: f64,
    pub cloud_kind: CloudKind,
    pub cloud_wind_speed_mps: f64,
    pub cloud_wind_from_deg: f64,
    /// Rain or snow (`None`: dry) and its rate, mm/h of water.
    pub precipitation_kind: Option<cig_environment::PrecipitationKind>,
    pub precipitation_rate_mm_per_h: f64,
    /// Strikes per minute of the operator's storm around the eye (0: none).
    pub storm_strikes_per_minute: f64,
    /// The view's sensor: `None` the visible channel, else a thermal band.
    pub sensor_band: Option<cig_thermal::IrBand>,
    /// The view is a night-vision goggle's (with no thermal band); its gain from
    /// `sensor_gain` as `10^(2 g - 1)`, 0.1..10.
    pub sensor_nvg: bool,
    pub sensor_black_hot: bool,
    /// Automatic gain; else the manual gain and level (CIGI's 0..1 contrast and brightness).
    pub sensor_automatic_gain: bool,
    pub sensor_gain: f64,
    pub sensor_level: f64,
    /// Orders given this frame, taken by the viewer.
    commands: Vec<ObscurantCommand>,
    /// The date field being edited.
    date_text: String,
    date_error: bool,
}

/// What the operator asked of the obscurants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObscurantCommand {
    /// Start a plume where the camera looks.
    StartPlume { flame: bool, heat_release_w: f64 },
    /// Stop every plume the operator started.
    StopPlumes,
    /// Set the wind the obscurants drift in.
    SetWind { speed_mps: f64, from_deg: f64 },
    /// Rain or snow at a rate (`None`: stop it).
    SetPrecipitation(Option<cig_environment::Precipitation>),
    /// A lightning strike where the camera looks.
    StrikeLightning,
    /// A storm around the eye striking this often (0: none), per minute.
    SetStorm { strikes_per_minute: f64 },
}

/// Precipitation rates the panel offers, mm/h of water.
const PRECIPITATION_RANGE_MM_PER_H: (f64, f64) = (0.1, 100.0);

/// Heat release range of operator plumes, MW.
const PLUME_HEAT_RANGE_MW: (f64, f64) = (0.1, 200.0);

/// Statistics the panel shows, besides the renderer's.
#[derive(Clone, Debug, Default)]
pub struct FrameInfo {
    pub stats: FrameStats,
    /// Frames per second, smoothed.
    pub fps: f64,
    pub width_px: u32,
    pub height_px: u32,
    pub adapter: String,
    /// False when the GPU cannot draw lines (the wireframe toggle then does nothing).
    pub wireframe_supported: bool,
    pub fast: bool,
}

impl PanelState {
    pub fn new(
        unix_time_s: f64,
        visibility_m: f64,
        fog_mode: FogMode,
        max_pixel_error: f64,
        wireframe: bool,
    ) -> PanelState {
        let mut state = PanelState {
            unix_time_s: if unix_time_s.is_finite() {
                unix_time_s
            } else {
                0.0
            },
            rate: 1.0,
            visibility_m: clamp_or(visibility_m, VISIBILITY_RANGE_M, 40_000.0),
            fog_mode,
            max_pixel_error: clamp_or(max_pixel_error, MAX_PIXEL_ERROR_RANGE_PX, 1.0),
            wireframe,
            ground_fog: false,
            ground_fog_top_m: 300.0,
            ground_fog_visibility_m: 300.0,
            exposure_compensation_ev: 0.0,
            stars: true,
            plume_heat_mw: 5.0,
            plume_flame: false,
            wind_speed_mps: 3.0,
            wind_from_deg: 270.0,
            obscurant_note: String::new(),
            clouds: false,
            cloud_base_m: 1500.0,
            cloud_thickness_m: 600.0,
            cloud_coverage: 0.5,
            cloud_kind: CloudKind::Cumulus,
            cloud_wind_speed_mps: 8.0,
            cloud_wind_from_deg: 270.0,
            sensor_band: None,
            sensor_nvg: false,
            sensor_black_hot: false,
            sensor_automatic_gain: true,
            sensor_gain: 0.5,
            sensor_level: 0.5,
            precipitation_kind: None,
            precipitation_rate_mm_per_h: 5.0,
            storm_strikes_per_minute: 0.0,
            commands: Vec::new(),
            date_text: String::new(),
            date_error: false,
        };
        state.date_text = format_date(state.day());
        state
    }

    /// Days since 1970-01-01 of the simulation time.
    pub fn day(&self) -> i64 {
        (self.unix_time_s / SECONDS_PER_DAY).floor() as i64
    }

    /// Seconds into the (UTC) day.
    pub fn seconds_of_day(&self) -> f64 {
        self.unix_time_s.rem_euclid(SECONDS_PER_DAY)
    }

    /// Advances the clock by `real_dt_s` real seconds at the panel's rate.
    pub fn advance(&mut self, real_dt_s: f64) {
        if real_dt_s.is_finite() && real_dt_s > 0.0 {
            let before = self.day();
            self.unix_time_s += real_dt_s * self.rate;
            if self.day() != before && !self.date_error {
                self.date_text = format_date(self.day());
            }
        }
    }

    /// The obscurant orders given since the last call.
    pub fn take_commands(&mut self) -> Vec<ObscurantCommand> {
        std::mem::take(&mut self.commands)
    }

    /// The fog these settings ask for.
    pub fn fog(&self) -> Fog {
        Fog::from_visibility(self.fog_mode, self.visibility_m)
    }

    /// The ground fog layer these settings ask for.
    pub fn ground_fog(&self) -> Option<cig_scene::FogLayer> {
        self.ground_fog.then_some(cig_scene::FogLayer {
            top_m: self.ground_fog_top_m,
            visibility_m: self.ground_fog_visibility_m,
        })
    }

    /// The cloud layer these settings ask for (values brought into range), if on.
    pub fn cloud_layer(&self) -> Option<CloudLayer> {
        self.clouds.then(|| {
            CloudLayer {
                base_m: self.cloud_base_m,
                thickness_m: self.cloud_thickness_m,
                coverage: self.cloud_coverage,
                kind: self.cloud_kind,
                wind_speed_mps: self.cloud_wind_speed_mps,
                wind_from_deg: self.cloud_wind_from_deg,
                seed: 1,
                drift: cig_environment::CloudDrift::default(),
            }
            .clamped()
            .0
        })
    }

    /// Draws the panel (a floating window) and applies the operator's changes.
    pub fn ui(&mut self, ctx: &egui::Context, camera: &mut FlyCamera, info: &FrameInfo) {
        egui::Window::new("cig view")
            .default_pos([8.0, 8.0])
            .resizable(false)
            .vscroll(true)
            .show(ctx, |ui| {
                self.time_ui(ui);
                ui.separator();
                self.atmosphere_ui(ui, info);
                ui.separator();
                self.celestial_ui(ui);
                ui.separator();
                self.detail_ui(ui, info);
                ui.separator();
                self.obscurants_ui(ui);
                ui.separator();
                self.clouds_ui(ui);
                ui.separator();
                self.sensor_ui(ui);
                self.weather_ui(ui);
                ui.separator();
                camera_ui(ui, camera, info);
            });
        egui::Window::new("frame")
            .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
            .auto_sized()
            .show(ctx, |ui| stats_ui(ui, info));
    }

    fn time_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("Time (UTC)");
        let mut seconds = self.seconds_of_day();
        let slider = ui.add(
            egui::Slider::new(&mut seconds, 0.0..=SECONDS_PER_DAY - 1.0)
                .text("time of day")
                .custom_formatter(|v, _| format_time_of_day(v))
                .custom_parser(|text| {
                    let mut parts = text.trim().split(':');
                    let h: f64 = parts.next()?.trim().parse().ok()?;
                    let m: f64 = parts.next().map_or(Some(0.0), |p| p.trim().parse().ok())?;
                    let s: f64 = parts.next().map_or(Some(0.0), |p| p.trim().parse().ok())?;
                    Some(h * 3600.0 + m * 60.0 + s)
                }),
        );
        if slider.changed() {
            self.unix_time_s = self.day() as f64 * SECONDS_PER_DAY + seconds;
        }
        ui.horizontal(|ui| {
            ui.label("date");
            let edit = ui.add(
                egui::TextEdit::singleline(&mut self.date_text)
                    .desired_width(90.0)
                    .hint_text("YYYY-MM-DD"),
            );
            if edit.changed() {
                match parse_date(&self.date_text) {
                    Some(day) => {
                        self.unix_time_s = day as f64 * SECONDS_PER_DAY + self.seconds_of_day();
                        self.date_error = false;
                    }
                    None => self.date_error = true,
                }
            }
            if edit.lost_focus() && self.date_error {
                self.date_text = format_date(self.day());
                self.date_error = false;
            }
            if self.date_error {
                ui.colored_label(egui::Color32::LIGHT_RED, "not a date");
            }
        });
        ui.add(
            egui::Slider::new(&mut self.rate, RATE_RANGE.0..=RATE_RANGE.1)
                .logarithmic(true)
                .smallest_positive(0.1)
                .text("min / min"),
        );
        ui.horizontal(|ui| {
            for (label, rate) in [("stop", 0.0), ("real time", 1.0), ("1 h / min", 60.0)] {
                if ui.button(label).clicked() {
                    self.rate = rate;
                }
            }
        });
    }

    fn atmosphere_ui(&mut self, ui: &mut egui::Ui, info: &FrameInfo) {
        ui.strong("Atmosphere");
        ui.label(format!(
            "natural light {:.3} lux, exposure EV {:.1}",
            info.stats.illuminance_lux, info.stats.exposure_ev
        ));
        ui.add(
            egui::Slider::new(&mut self.exposure_compensation_ev, -4.0..=4.0)
                .text("exposure compensation")
                .suffix(" EV"),
        );
        ui.add(
            egui::Slider::new(
                &mut self.visibility_m,
                VISIBILITY_RANGE_M.0..=VISIBILITY_RANGE_M.1,
            )
            .logarithmic(true)
            .text("visibility")
            .suffix(" m"),
        );
        ui.horizontal(|ui| {
            ui.label("fog");
            for mode in [
                FogMode::Off,
                FogMode::Linear,
                FogMode::Exponential,
                FogMode::ExponentialSquared,
            ] {
                ui.selectable_value(&mut self.fog_mode, mode, mode.name());
            }
        });
        ui.checkbox(&mut self.ground_fog, "ground fog layer");
        ui.add_enabled(
            self.ground_fog,
            egui::Slider::new(&mut self.ground_fog_top_m, -100.0..=3000.0)
                .text("top")
                .suffix(" m"),
        );
        ui.add_enabled(
            self.ground_fog,
            egui::Slider::new(&mut self.ground_fog_visibility_m, 20.0..=5000.0)
                .logarithmic(true)
                .text("in the layer")
                .suffix(" m"),
        );
    }

    fn celestial_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("Sky");
        ui.checkbox(&mut self.stars, "stars")
            .on_hover_text("the moon is always drawn; stars fade out by themselves in daylight");
    }

    fn obscurants_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("Obscurants");
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.plume_flame, false, "smoke");
            ui.selectable_value(&mut self.plume_flame, true, "fire");
        });
        ui.add(
            egui::Slider::new(
                &mut self.plume_heat_mw,
                PLUME_HEAT_RANGE_MW.0..=PLUME_HEAT_RANGE_MW.1,
            )
            .logarithmic(true)
            .text("heat release")
            .suffix(" MW"),
        );
        ui.horizontal(|ui| {
            if ui
                .button("start where I look")
                .on_hover_text("on the ground at the centre of the view")
                .clicked()
            {
                self.commands.push(ObscurantCommand::StartPlume {
                    flame: self.plume_flame,
                    heat_release_w: self.plume_heat_mw * 1.0e6,
                });
            }
            if ui.button("stop all").clicked() {
                self.commands.push(ObscurantCommand::StopPlumes);
            }
        });
        let speed = ui.add(
            egui::Slider::new(&mut self.wind_speed_mps, 0.0..=30.0)
                .text("wind")
                .suffix(" m/s"),
        );
        let from = ui.add(
            egui::Slider::new(&mut self.wind_from_deg, 0.0..=359.0)
                .text("from")
                .suffix("°"),
        );
        if speed.changed() || from.changed() {
            self.commands.push(ObscurantCommand::SetWind {
                speed_mps: self.wind_speed_mps,
                from_deg: self.wind_from_deg,
            });
        }
        if !self.obscurant_note.is_empty() {
            ui.label(&self.obscurant_note);
        }
    }

    fn sensor_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("Sensor");
        let name = |choice: (Option<cig_thermal::IrBand>, bool)| match choice {
            (None, false) => "visible",
            (None, true) => "NVG (image intensifier)",
            (Some(cig_thermal::IrBand::Lwir), _) => "LWIR 8-12 um",
            (Some(cig_thermal::IrBand::Mwir), _) => "MWIR 3-5 um",
        };
        let mut choice = (self.sensor_band, self.sensor_nvg);
        egui::ComboBox::from_label("channel")
            .selected_text(name(choice))
            .show_ui(ui, |ui| {
                for c in [
                    (None, false),
                    (Some(cig_thermal::IrBand::Lwir), false),
                    (Some(cig_thermal::IrBand::Mwir), false),
                    (None, true),
                ] {
                    ui.selectable_value(&mut choice, c, name(c));
                }
            });
        (self.sensor_band, self.sensor_nvg) = (choice.0, choice.0.is_none() && choice.1);
        ui.add_enabled_ui(self.sensor_nvg, |ui| {
            ui.add(egui::Slider::new(&mut self.sensor_gain, 0.0..=1.0).text("NVG gain"))
                .on_hover_text("0.5 is the goggle's nominal gain; 0 a tenth, 1 ten times");
        });
        ui.add_enabled_ui(self.sensor_band.is_some(), |ui| {
            ui.checkbox(&mut self.sensor_black_hot, "black-hot");
            ui.checkbox(&mut self.sensor_automatic_gain, "automatic gain");
            ui.add_enabled_ui(!self.sensor_automatic_gain, |ui| {
                ui.add(egui::Slider::new(&mut self.sensor_gain, 0.0..=1.0).text("gain"));
                ui.add(egui::Slider::new(&mut self.sensor_level, 0.0..=1.0).text("level"));
            });
        });
    }

    /// The night-vision goggle these settings ask for (`None`: not a goggle's view).
    pub fn nvg_view(&self) -> Option<cig_scene::nvg::NvgView> {
        if !self.sensor_nvg || self.sensor_band.is_some() {
            return None;
        }
        let gain = 10f64.powf(2.0 * self.sensor_gain.clamp(0.0, 1.0) - 1.0);
        Some(cig_scene::nvg::NvgView {
            gain: (gain as f32).clamp(0.1, 10.0),
            ..cig_scene::nvg::NvgView::default()
        })
    }

    /// The sensor these settings ask for (`None`: the visible channel).
    pub fn sensor_view(&self) -> Option<cig_scene::thermal::SensorView> {
        let band = self.sensor_band?;
        let mut view = cig_scene::thermal::SensorView::new(band);
        if self.sensor_black_hot {
            view.polarity = cig_scene::thermal::Polarity::BlackHot;
        }
        if !self.sensor_automatic_gain {
            view.manual_gain_level = Some((
                self.sensor_gain.clamp(0.0, 1.0) as f32,
                self.sensor_level.clamp(0.0, 1.0) as f32,
            ));
        }
        Some(view)
    }

    fn clouds_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("Clouds");
        ui.checkbox(&mut self.clouds, "cloud layer")
            .on_hover_text("replaces the scenario's and the host's clouds while on");
        ui.add_enabled_ui(self.clouds, |ui| {
            ui.add(
                egui::Slider::new(&mut self.cloud_base_m, 0.0..=12_000.0)
                    .text("base")
                    .suffix(" m"),
            );
            ui.add(
                egui::Slider::new(&mut self.cloud_thickness_m, 50.0..=5_000.0)
                    .logarithmic(true)
                    .text("thickness")
                    .suffix(" m"),
            );
            ui.add(egui::Slider::new(&mut self.cloud_coverage, 0.0..=1.0).text("coverage"));
            egui::ComboBox::from_label("type")
                .selected_text(self.cloud_kind.name())
                .show_ui(ui, |ui| {
                    for kind in CloudKind::ALL {
                        ui.selectable_value(&mut self.cloud_kind, kind, kind.name());
                    }
                });
            ui.add(
                egui::Slider::new(&mut self.cloud_wind_speed_mps, 0.0..=60.0)
                    .text("wind")
                    .suffix(" m/s"),
            );
            ui.add(
                egui::Slider::new(&mut self.cloud_wind_from_deg, 0.0..=359.0)
                    .text("from")
                    .suffix("°"),
            );
        });
    }

    /// The precipitation these settings ask for.
    pub fn precipitation(&self) -> Option<cig_environment::Precipitation> {
        self.precipitation_kind.map(|kind| {
            cig_environment::Precipitation::clamped(
                kind,
                clamp_or(
                    self.precipitation_rate_mm_per_h,
                    PRECIPITATION_RANGE_MM_PER_H,
                    5.0,
                ),
            )
        })
    }

    fn weather_ui(&mut self, ui: &mut egui::Ui) {
        use cig_environment::PrecipitationKind;
        ui.strong("Weather");
        let mut changed = false;
        ui.horizontal(|ui| {
            for (kind, name) in [
                (None, "dry"),
                (Some(PrecipitationKind::Rain), "rain"),
                (Some(PrecipitationKind::Snow), "snow"),
            ] {
                changed |= ui
                    .selectable_value(&mut self.precipitation_kind, kind, name)
                    .changed();
            }
        });
        changed |= ui
            .add_enabled(
                self.precipitation_kind.is_some(),
                egui::Slider::new(
                    &mut self.precipitation_rate_mm_per_h,
                    PRECIPITATION_RANGE_MM_PER_H.0..=PRECIPITATION_RANGE_MM_PER_H.1,
                )
                .logarithmic(true)
                .text("rate")
                .suffix(" mm/h"),
            )
            .changed();
        if changed {
            self.commands
                .push(ObscurantCommand::SetPrecipitation(self.precipitation()));
        }
        if let Some(p) = self.precipitation() {
            ui.label(format!("visibility in it {:.0} m", p.visibility_m()));
        }
        let storm = ui.add(
            egui::Slider::new(&mut self.storm_strikes_per_minute, 0.0..=60.0)
                .text("lightning")
                .suffix(" /min"),
        );
        if storm.changed() {
            self.commands.push(ObscurantCommand::SetStorm {
                strikes_per_minute: self.storm_strikes_per_minute,
            });
        }
        if ui
            .button("strike now")
            .on_hover_text("a bolt on the ground at the centre of the view")
            .clicked()
        {
            self.commands.push(ObscurantCommand::StrikeLightning);
        }
    }

    fn detail_ui(&mut self, ui: &mut egui::Ui, info: &FrameInfo) {
        ui.strong("Terrain");
        ui.add(
            egui::Slider::new(
                &mut self.max_pixel_error,
                MAX_PIXEL_ERROR_RANGE_PX.0..=MAX_PIXEL_ERROR_RANGE_PX.1,
            )
            .text("max pixel error")
            .suffix(" px"),
        )
        .on_hover_text("0 = full detail everywhere");
        ui.add_enabled(
            info.wireframe_supported,
            egui::Checkbox::new(&mut self.wireframe, "wireframe"),
        )
        .on_disabled_hover_text("this GPU cannot draw lines");
    }
}

fn clamp_or(value: f64, range: (f64, f64), fallback: f64) -> f64 {
    if value.is_finite() {
        value.clamp(range.0, range.1)
    } else {
        fallback
    }
}

fn camera_ui(ui: &mut egui::Ui, camera: &mut FlyCamera, info: &FrameInfo) {
    ui.strong("Camera");
    let e = camera.eye;
    let o = camera.orientation;
    ui.monospace(format!(
        "{:.5}, {:.5}, {:.0} m\nheading {:.1}  pitch {:.1}",
        e.lat_deg, e.lon_deg, e.alt_m, o.heading_deg, o.pitch_deg
    ));
    let mut speed = camera.speed_mps;
    let response = ui.add(
        egui::Slider::new(
            &mut speed,
            super::camera::SPEED_RANGE_MPS.0..=super::camera::SPEED_RANGE_MPS.1,
        )
        .logarithmic(true)
        .text("speed")
        .suffix(" m/s"),
    );
    if response.changed() {
        camera.set_speed(speed);
    }
    if info.fast {
        ui.label(format!(
            "shift: {:.0} m/s",
            camera.effective_speed_mps(true)
        ));
    }
    ui.small(
        "drag: look    WASD / arrows: fly\nQ/E, PgDn/PgUp: down/up    shift: fast\nwheel: speed    Esc: quit",
    );
}

fn stats_ui(ui: &mut egui::Ui, info: &FrameInfo) {
    let s = &info.stats;
    egui::Grid::new("frame statistics")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            let mut row = |name: &str, value: String| {
                ui.label(name);
                ui.monospace(value);
                ui.end_row();
            };
            row("fps", format!("{:.1}", info.fps));
            row("size", format!("{} x {}", info.width_px, info.height_px));
            row("triangles", s.triangles.to_string());
            row("models", s.entities_drawn.to_string());
            row(
                "culture",
                format!(
                    "{} objects, {} triangles, {} blocks behind terrain, {:.2} ms",
                    s.culture_drawn,
                    s.culture_triangles,
                    s.culture_blocks_occluded,
                    s.culture_cpu_ms
                ),
            );
            // The overload control's K_LOD (source 004 Table 4) against the view's nominal.
            row(
                "K_LOD",
                format!("{:.0} of {:.0} ({})", s.klod, s.klod_nominal, s.overload),
            );
            row("nodes", s.terrain_nodes.to_string());
            row("draw calls", s.draw_calls.to_string());
            row("cpu select", format!("{:.2} ms", s.cpu_select_ms));
            row("cpu frame", format!("{:.2} ms", s.cpu_frame_ms));
            row("gpu", format!("{:.2} ms", s.gpu_ms));
            row(
                "tiles",
                format!("{} resident, {} wanted", s.tiles_resident, s.tiles_wanted),
            );
            row(
                "meshes",
                format!("{} built, {} deferred", s.meshes_built, s.meshes_deferred),
            );
            row(
                "imagery",
                format!(
                    "{} tiles written, {} loading",
                    s.imagery_tiles_uploaded, s.imagery_tiles_pending
                ),
            );
        });
    ui.small(&info.adapter);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_sensor_switch_gives_the_view_its_sensor() {
        let mut p = PanelState::new(0.0, 20_000.0, FogMode::Exponential, 1.0, false);
        assert_eq!(p.sensor_view(), None);
        p.sensor_band = Some(cig_thermal::IrBand::Mwir);
        p.sensor_black_hot = true;
        let auto = p.sensor_view().expect("a sensor");
        assert_eq!(auto.band, cig_thermal::IrBand::Mwir);
        assert_eq!(auto.polarity, cig_scene::thermal::Polarity::BlackHot);
        assert_eq!(auto.manual_gain_level, None);
        p.sensor_automatic_gain = false;
        p.sensor_gain = 1.5;
        p.sensor_level = 0.25;
        assert_eq!(
            p.sensor_view().expect("a sensor").manual_gain_level,
            Some((1.0, 0.25))
        );
    }

    #[test]
    fn known_dates() {
        assert_eq!(days_from_civil(1970, 1, 1), Some(0));
        assert_eq!(days_from_civil(2000, 3, 1), Some(11_017));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(parse_date("2026-06-21"), Some(20_625));
        assert_eq!(format_date(20_625), "2026-06-21");
        assert_eq!(parse_date("2024-02-29"), days_from_civil(2024, 2, 29));
        for bad in [
            "2023-02-29",
            "1900-02-29",
            "2026-13-01",
            "2026-04-31",
            "x",
            "",
            "0-1-1",
        ] {
            assert_eq!(parse_date(bad), None, "{bad}");
        }
    }

    #[test]
    fn time_of_day_formatting() {
        assert_eq!(format_time_of_day(0.0), "00:00:00");
        assert_eq!(format_time_of_day(19.0 * 3600.0 + 61.5), "19:01:01");
        assert_eq!(format_time_of_day(1e9), "23:59:59");
    }

    #[test]
    fn the_clock_runs_at_the_rate_and_the_date_follows() {
        let mut p = PanelState::new(
            days_from_civil(2026, 6, 21).expect("a date") as f64 * SECONDS_PER_DAY + 86_000.0,
            1000.0,
            FogMode::Linear,
            1.0,
            false,
        );
        p.rate = 60.0;
        p.advance(10.0);
        assert!((p.seconds_of_day() - 200.0).abs() < 1e-6);
        assert_eq!(p.date_text, "2026-06-22");
        p.rate = 0.0;
        p.advance(100.0);
        assert!((p.seconds_of_day() - 200.0).abs() < 1e-6);
        let fog = p.fog();
        assert_eq!(fog.mode, FogMode::Linear);
        assert!((fog.factor(1000.0) - 0.02).abs() < 1e-3);
    }

    #[test]
    fn out_of_range_settings_are_clamped() {
        let p = PanelState::new(f64::NAN, 1e9, FogMode::Off, -3.0, true);
        assert_eq!(p.unix_time_s, 0.0);
        assert_eq!(p.visibility_m, VISIBILITY_RANGE_M.1);
        assert_eq!(p.max_pixel_error, 0.0);
    }

    #[test]
    fn the_weather_settings_give_checked_precipitation() {
        let mut p = PanelState::new(0.0, 10_000.0, FogMode::Exponential, 1.0, false);
        assert_eq!(p.precipitation(), None);
        p.precipitation_kind = Some(cig_environment::PrecipitationKind::Snow);
        p.precipitation_rate_mm_per_h = 1e9;
        let snow = p.precipitation().expect("snow");
        assert_eq!(snow.rate_mm_per_h, PRECIPITATION_RANGE_MM_PER_H.1);
        p.precipitation_rate_mm_per_h = f64::NAN;
        assert_eq!(p.precipitation().map(|s| s.rate_mm_per_h), Some(5.0));
    }

    proptest! {
        #[test]
        fn civil_dates_match_the_time_crate(days in -719_162i64..2_932_896) {
            // 0001-01-01 ..= 9999-12-31, against an independent implementation.
            let (y, m, d) = civil_from_days(days);
            let reference = time::Date::from_julian_day((days + 2_440_588) as i32)
                .expect("in range");
            prop_assert_eq!(
                (y, m, d),
                (i64::from(reference.year()), u32::from(u8::from(reference.month())), u32::from(reference.day()))
            );
            prop_assert_eq!(days_from_civil(y, m, d), Some(days));
            prop_assert_eq!(parse_date(&format_date(days)), Some(days));
        }
    }

    #[test]
    fn the_cloud_layer_is_off_until_asked_and_always_valid() {
        let mut p = PanelState::new(0.0, 1000.0, FogMode::Linear, 1.0, false);
        assert_eq!(p.cloud_layer(), None);
        p.clouds = true;
        let layer = p.cloud_layer().expect("on");
        assert_eq!((layer.base_m, layer.coverage), (1500.0, 0.5));
        p.cloud_coverage = 7.0;
        p.cloud_thickness_m = f64::NAN;
        let layer = p.cloud_layer().expect("on");
        assert!(layer.validate().is_ok(), "{layer:?}");
        assert_eq!(layer.coverage, 1.0);
    }
}
