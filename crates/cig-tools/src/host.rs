//! The scripted CIGI host of `cig host` (for demos and tests), without its socket.
//!
//! Each host frame (at `rate_hz`) it sends one message: IG Control (operate, host frame number,
//! the host's clock as a valid 10 µs timestamp, the last IG frame number it received), the
//! script's entities moved along their paths, the views attached to its entity, and the
//! requests due (HAT/HOT and LOS every frame or once). The first frame and then one frame a
//! second also set the time of day (the script's time plus the host's clock), the visibility
//! and the views' frusta when the script gives them, so an IG channel that starts late or
//! restarts has the whole state within a second.
//! Between frames it reads what the IG sent ([`Replies`]): Start of Frame counters and every
//! answer, each described as one JSON object with the latency in host frames (from the 4-bit
//! host frame number the answers carry), and a summary at the end. The `cig` binary sends,
//! receives and prints; this module only builds and reads messages.
//!
//! Script (TOML):
//! ```toml
//! version = "3.3"              # or "4.0"
//! byte_order = "little"        # or "big"
//! rate_hz = 60
//! frames = 120
//! time = "2026-06-21T10:00:00Z"
//! visibility_m = 8000
//! [[entities]]
//! id = 0
//! type = 1
//! clamp = "none"               # none, height, conformal
//! alt_m = 300                  # MSL, or above the terrain when clamped
//! speed_mps = 50
//! path = [[51.0, -1.5], [51.02, -1.5]]
//! repeat = false               # true: round the path again and again (a racetrack)
//! [view]                       # view 0; or [[views]] tables, each with its `id`
//! entity = 0
//! offset_m = [0, 0, -2]
//! hpr_deg = [0, -5, 0]
//! fov_deg = [-30, 30, -20, 20] # left, right, bottom, top
//! view_type = 1                # View Definition's (cig: 0 visible, 1 LWIR, 2 MWIR)
//! [view.sensor]                # a Sensor Control on the view, restated each second
//! on = true
//! black_hot = false
//! automatic_gain = true        # false: gain and level (0..1)
//! gain = 0.5
//! level = 0.5
//! noise = 0.1                  # 0..1 (cig: NETD 0.5 K x noise)
//! track_mode = 3               # 0 off, 3 target: the IG's tracker answers Sensor Response
//! track_black = false
//! extended = true              # Sensor Extended Response (entity and track point)
//! [[hat]]
//! id = 1
//! entity = 0                   # below the entity; or lat_deg, lon_deg, alt_m
//! type = "hot"                 # hat, hot, extended
//! every_frame = true
//! [[los]]
//! id = 2
//! from = [51.0, -1.5, 400]
//! to = [51.02, -1.5, 400]
//! extended = true
//! alpha_threshold = 0          # least alpha (surface or smoke) that stops the line
//! ```
//!
//! Three channels of one eyepoint are three `[[views]]` with ids 0, 1, 2 on the same entity
//! and adjacent frusta (`fov_deg = [-45, -15, -20, 20]`, `[-15, 15, -20, 20]`, `[15, 45, -20, 20]`).
//!
//! Limits: requests go out every frame or once (frame 0); answers are matched to requests by
//! nothing but their id.

use crate::ToolError;
use cig_cigi::{
    decode_message, AtmosphereControl, ByteOrder, CelestialSphereControl, EntityControl,
    EntityControl4, EntityPosition, HatHotRequest, IgControl, LosSegmentRequest, Message, Packet,
    SensorControl, Version, ViewControl, ViewDefinition,
};
use cig_environment::UtcTime;
use cig_geo::{EnuFrame, Geodetic};
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScriptFile {
    #[serde(default = "v33")]
    version: String,
    #[serde(default = "little")]
    byte_order: String,
    #[serde(default = "sixty")]
    rate_hz: f64,
    #[serde(default = "sixty_frames")]
    frames: u32,
    #[serde(default)]
    time: Option<String>,
    #[serde(default)]
    visibility_m: Option<f32>,
    #[serde(default)]
    entities: Vec<HostEntity>,
    #[serde(default)]
    view: Option<HostView>,
    #[serde(default)]
    views: Vec<HostView>,
    #[serde(default)]
    hat: Vec<HostHat>,
    #[serde(default)]
    los: Vec<HostLos>,
}

fn v33() -> String {
    "3.3".into()
}
fn little() -> String {
    "little".into()
}
fn sixty() -> f64 {
    60.0
}
fn sixty_frames() -> u32 {
    60
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HostEntity {
    id: u16,
    #[serde(default, rename = "type")]
    entity_type: u16,
    #[serde(default = "no_clamp")]
    clamp: String,
    #[serde(default)]
    alt_m: f64,
    #[serde(default)]
    speed_mps: f64,
    path: Vec<[f64; 2]>,
    /// Fly the path round and round: back to its first point after the last, then again
    /// (a racetrack), instead of stopping at its end.
    #[serde(default)]
    repeat: bool,
}

fn no_clamp() -> String {
    "none".into()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HostView {
    #[serde(default)]
    id: u16,
    #[serde(default)]
    entity: u16,
    #[serde(default)]
    offset_m: [f32; 3],
    #[serde(default)]
    hpr_deg: [f32; 3],
    #[serde(default)]
    fov_deg: Option<[f32; 4]>,
    /// View Definition's view type (cig: 0 visible, 1 LWIR, 2 MWIR).
    #[serde(default)]
    view_type: u8,
    /// A Sensor Control on the view, restated with the view's frustum.
    #[serde(default)]
    sensor: Option<HostSensor>,
}

/// A Sensor Control the script sends.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HostSensor {
    #[serde(default)]
    id: u8,
    #[serde(default = "yes")]
    on: bool,
    #[serde(default)]
    black_hot: bool,
    #[serde(default = "yes")]
    automatic_gain: bool,
    #[serde(default = "half")]
    gain: f32,
    #[serde(default = "half")]
    level: f32,
    #[serde(default)]
    noise: f32,
    #[serde(default)]
    line_dropout: bool,
    #[serde(default)]
    ac_coupling_us: f32,
    /// 0 off, 3 target (CIGI's track modes).
    #[serde(default)]
    track_mode: u8,
    #[serde(default)]
    track_black: bool,
    /// Ask for Sensor Extended Response.
    #[serde(default)]
    extended: bool,
}

fn yes() -> bool {
    true
}

fn half() -> f32 {
    0.5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HostHat {
    id: u16,
    #[serde(default)]
    entity: Option<u16>,
    #[serde(default)]
    lat_deg: f64,
    #[serde(default)]
    lon_deg: f64,
    #[serde(default)]
    alt_m: f64,
    #[serde(default = "hot", rename = "type")]
    kind: String,
    #[serde(default)]
    every_frame: bool,
}

fn hot() -> String {
    "hot".into()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HostLos {
    id: u16,
    from: [f64; 3],
    to: [f64; 3],
    #[serde(default)]
    extended: bool,
    #[serde(default)]
    every_frame: bool,
    /// Least alpha of a surface (or obscurant) that stops the line, 0-255.
    #[serde(default)]
    alpha_threshold: u8,
}

fn check(script: &ScriptFile) -> Result<(Version, ByteOrder), ToolError> {
    let version = match script.version.as_str() {
        "3.3" => Version::V3_3,
        "4.0" | "4" => Version::V4_0,
        other => {
            return Err(ToolError::Script(format!(
                "version {other:?} is not 3.3 or 4.0"
            )))
        }
    };
    let order = match script.byte_order.as_str() {
        "little" => ByteOrder::LittleEndian,
        "big" => ByteOrder::BigEndian,
        other => {
            return Err(ToolError::Script(format!(
                "byte_order {other:?} is not little or big"
            )))
        }
    };
    if !(script.rate_hz.is_finite() && (1.0..=1000.0).contains(&script.rate_hz)) {
        return Err(ToolError::Script(format!(
            "rate_hz {} must lie between 1 and 1000",
            script.rate_hz
        )));
    }
    let mut view_ids = std::collections::BTreeSet::new();
    for v in script.view.iter().chain(&script.views) {
        if !view_ids.insert(v.id) {
            return Err(ToolError::Script(format!("view {} is given twice", v.id)));
        }
    }
    for (i, e) in script.entities.iter().enumerate() {
        if e.path.is_empty() {
            return Err(ToolError::Script(format!("entities[{i}].path is empty")));
        }
        let ok = e
            .path
            .iter()
            .all(|p| p[0].abs() <= 90.0 && p[1].abs() <= 360.0)
            && e.alt_m.is_finite()
            && e.speed_mps.is_finite()
            && e.speed_mps >= 0.0;
        if !ok {
            return Err(ToolError::Script(format!(
                "entities[{i}]: a point, altitude or speed is out of range"
            )));
        }
        if !["none", "height", "conformal"].contains(&e.clamp.as_str()) {
            return Err(ToolError::Script(format!(
                "entities[{i}].clamp {:?} is not none, height or conformal",
                e.clamp
            )));
        }
    }
    for (i, h) in script.hat.iter().enumerate() {
        if !["hat", "hot", "extended"].contains(&h.kind.as_str()) {
            return Err(ToolError::Script(format!(
                "hat[{i}].type {:?} is not hat, hot or extended",
                h.kind
            )));
        }
        if h.entity
            .is_some_and(|id| !script.entities.iter().any(|e| e.id == id))
        {
            return Err(ToolError::Script(format!(
                "hat[{i}].entity is not an entity of the script"
            )));
        }
    }
    if let Some(t) = &script.time {
        UtcTime::parse_iso8601(t).map_err(|e| ToolError::Time(e.to_string()))?;
    }
    Ok((version, order))
}

/// Where an entity is after `t_s` seconds: latitude, longitude, heading.
fn entity_at(e: &HostEntity, t_s: f64) -> (f64, f64, f64) {
    let first = e.path[0];
    let frame = EnuFrame::new(Geodetic::new(first[0], first[1], 0.0));
    let mut pts: Vec<glam::DVec3> = e
        .path
        .iter()
        .map(|p| frame.geodetic_to_enu(Geodetic::new(p[0], p[1], 0.0)))
        .collect();
    let mut s = e.speed_mps * t_s;
    if e.repeat {
        // Closed: the last point back to the first, and the distance round the loop.
        pts.push(pts[0]);
        let loop_m: f64 = pts
            .windows(2)
            .map(|w| (w[1] - w[0]).truncate().length())
            .sum();
        if loop_m > 0.0 {
            s = s.rem_euclid(loop_m);
        }
    }
    let mut last_heading = 0.0;
    for w in pts.windows(2) {
        let d = w[1] - w[0];
        let len = d.truncate().length();
        // The heading in the segment's own tangent frame (the path's frame turns with longitude).
        let start = frame.enu_to_geodetic(w[0]);
        let local = EnuFrame::new(start).geodetic_to_enu(frame.enu_to_geodetic(w[1]));
        let heading = local.x.atan2(local.y).to_degrees().rem_euclid(360.0);
        if len > 0.0 {
            last_heading = heading;
        }
        if len == 0.0 {
            // A repeated point: on to the next segment.
            continue;
        }
        if s <= len {
            let p = w[0] + d * (s / len).min(1.0);
            let g = frame.enu_to_geodetic(glam::DVec3::new(p.x, p.y, 0.0));
            return (g.lat_deg, g.lon_deg, heading);
        }
        s -= len;
    }
    // Past the end: at the last point, facing along the last segment (a repeated path's last
    // point is its first: only rounding gets here).
    let last = if e.repeat {
        e.path[0]
    } else {
        e.path[e.path.len() - 1]
    };
    (last[0], last[1], last_heading)
}

/// A host script, read and checked.
#[derive(Debug)]
pub struct HostScript {
    file: ScriptFile,
    version: Version,
    order: ByteOrder,
}

impl HostScript {
    /// Reads a script from its TOML text and checks it.
    ///
    /// # Errors
    /// One line: the first line of the TOML parser's message, or the value that is out of
    /// range.
    pub fn from_toml(text: &str) -> Result<HostScript, ToolError> {
        let file: ScriptFile = toml::from_str(text).map_err(|e| {
            ToolError::Script(
                e.message()
                    .lines()
                    .next()
                    .unwrap_or("syntax error")
                    .to_string(),
            )
        })?;
        let (version, order) = check(&file)?;
        Ok(HostScript {
            file,
            version,
            order,
        })
    }

    /// Host frames a second.
    #[must_use]
    pub fn rate_hz(&self) -> f64 {
        self.file.rate_hz
    }

    /// Host frames to send.
    #[must_use]
    pub fn frames(&self) -> u32 {
        self.file.frames
    }

    /// The message of host frame `frame`, telling the IG the last IG frame number received.
    ///
    /// # Errors
    /// When the script's time cannot be read (checked already when the script was read).
    pub fn frame(&self, frame: u32, last_ig_frame: u32) -> Result<Message, ToolError> {
        build_frame(&self.file, self.version, self.order, frame, last_ig_frame)
    }
}

fn build_frame(
    script: &ScriptFile,
    version: Version,
    order: ByteOrder,
    frame: u32,
    last_ig_frame: u32,
) -> Result<Message, ToolError> {
    let t_s = f64::from(frame) / script.rate_hz;
    let mut packets = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: frame,
        last_ig_frame_number: last_ig_frame,
        timestamp_valid: true,
        // The host's clock in 10 µs ticks, wrapping as the field does.
        timestamp_10us: ((t_s * 1e5).round() as u64 & u64::from(u32::MAX)) as u32,
        ..IgControl::default()
    })];
    // The state an IG keeps (time of day, visibility, frusta) is told at the start and again
    // once a second, for channels that join late.
    let restate = frame.is_multiple_of(script.rate_hz.round().max(1.0) as u32);
    if restate {
        if let Some(t) = &script.time {
            let start = UtcTime::parse_iso8601(t).map_err(|e| ToolError::Time(e.to_string()))?;
            let c = start.plus_seconds(t_s).to_calendar();
            packets.push(Packet::CelestialSphereControl(CelestialSphereControl {
                hour: c.hour as u8,
                minute: c.minute as u8,
                seconds: c.second as f32,
                date_time_valid: true,
                ephemeris_enable: true,
                sun_enable: true,
                moon_enable: true,
                date_mmddyyyy: c.month * 1_000_000 + c.day * 10_000 + c.year as u32,
                ..CelestialSphereControl::default()
            }));
        }
        if let Some(v) = script.visibility_m {
            packets.push(Packet::AtmosphereControl(AtmosphereControl {
                atmospheric_model_enable: true,
                humidity_pct: 50,
                air_temperature_c: 15.0,
                visibility_range_m: v,
                barometric_pressure_mbar: 1013.25,
                ..AtmosphereControl::default()
            }));
        }
    }
    for e in &script.entities {
        let (lat, lon, heading) = entity_at(e, t_s);
        let clamp = match e.clamp.as_str() {
            "height" => 1,
            "conformal" => 2,
            _ => 0,
        };
        if version.major == 3 {
            packets.push(Packet::EntityControl(EntityControl {
                entity_id: e.id,
                entity_state: 1,
                entity_type: e.entity_type,
                ground_ocean_clamp: clamp,
                alpha: 255,
                yaw_deg: heading as f32,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: e.alt_m,
                ..EntityControl::default()
            }));
        } else {
            packets.push(Packet::EntityControl4(EntityControl4 {
                entity_id: e.id,
                entity_state: 1,
                alpha: 255,
                entity_type_or_country: e.entity_type,
                ..EntityControl4::default()
            }));
            packets.push(Packet::EntityPosition(EntityPosition {
                entity_id: e.id,
                ground_ocean_clamp: clamp,
                yaw_deg: heading as f32,
                lat_deg_or_x_m: lat,
                lon_deg_or_y_m: lon,
                alt_m_or_z_m: e.alt_m,
                ..EntityPosition::default()
            }));
        }
    }
    for v in script.view.iter().chain(&script.views) {
        packets.push(Packet::ViewControl(ViewControl {
            view_id: v.id,
            entity_id: v.entity,
            x_offset_enable: true,
            y_offset_enable: true,
            z_offset_enable: true,
            roll_enable: true,
            pitch_enable: true,
            yaw_enable: true,
            x_offset_m: v.offset_m[0],
            y_offset_m: v.offset_m[1],
            z_offset_m: v.offset_m[2],
            yaw_deg: v.hpr_deg[0],
            pitch_deg: v.hpr_deg[1],
            roll_deg: v.hpr_deg[2],
            ..ViewControl::default()
        }));
        if let (true, Some(f)) = (restate, v.fov_deg) {
            packets.push(Packet::ViewDefinition(ViewDefinition {
                view_id: v.id,
                left_enable: true,
                right_enable: true,
                bottom_enable: true,
                top_enable: true,
                left_deg: f[0],
                right_deg: f[1],
                bottom_deg: f[2],
                top_deg: f[3],
                view_type: v.view_type,
                ..ViewDefinition::default()
            }));
        }
        if let (true, Some(sensor)) = (restate, &v.sensor) {
            packets.push(Packet::SensorControl(SensorControl {
                view_id: v.id,
                sensor_id: sensor.id,
                sensor_on: sensor.on,
                polarity_black_hot: sensor.black_hot,
                line_dropout_enable: sensor.line_dropout,
                automatic_gain: sensor.automatic_gain,
                gain: sensor.gain,
                level: sensor.level,
                noise: sensor.noise,
                ac_coupling_us: sensor.ac_coupling_us,
                track_mode: sensor.track_mode,
                track_black: sensor.track_black,
                response_type_extended: sensor.extended,
            }));
        }
    }
    for h in script.hat.iter().filter(|h| h.every_frame || frame == 0) {
        let request_type = match h.kind.as_str() {
            "hat" => 0,
            "hot" => 1,
            _ => 2,
        };
        packets.push(Packet::HatHotRequest(match h.entity {
            Some(id) => HatHotRequest {
                hat_hot_id: h.id,
                request_type,
                coordinate_system_entity: true,
                entity_id: id,
                ..HatHotRequest::default()
            },
            None => HatHotRequest {
                hat_hot_id: h.id,
                request_type,
                lat_deg_or_x_m: h.lat_deg,
                lon_deg_or_y_m: h.lon_deg,
                alt_m_or_z_m: h.alt_m,
                ..HatHotRequest::default()
            },
        }));
    }
    for l in script.los.iter().filter(|l| l.every_frame || frame == 0) {
        packets.push(Packet::LosSegmentRequest(LosSegmentRequest {
            los_id: l.id,
            request_type_extended: l.extended,
            alpha_threshold: l.alpha_threshold,
            source_lat_deg_or_x_m: l.from[0],
            source_lon_deg_or_y_m: l.from[1],
            source_alt_m_or_z_m: l.from[2],
            destination_lat_deg_or_x_m: l.to[0],
            destination_lon_deg_or_y_m: l.to[1],
            destination_alt_m_or_z_m: l.to[2],
            ..LosSegmentRequest::default()
        }));
    }
    Ok(Message::new(version, order, packets))
}

/// What the IG sent the host: counters, and each packet described as JSON.
#[derive(Clone, Debug, Default)]
pub struct Replies {
    start_of_frames: u64,
    last_ig_frame: u32,
    answers: u64,
    bad: u64,
    latency_sum: u64,
    latency_max: u32,
}

impl Replies {
    /// Nothing received yet.
    #[must_use]
    pub fn new() -> Replies {
        Replies::default()
    }

    /// Reads one message of the IG, received during host frame `frame`: one JSON object per
    /// packet other than Start of Frame, with the host frame, the last IG frame and the
    /// answer's latency in host frames.
    ///
    /// # Errors
    /// When the message cannot be decoded (it is counted as bad).
    pub fn read(&mut self, bytes: &[u8], frame: u32) -> Result<Vec<serde_json::Value>, ToolError> {
        let message = decode_message(bytes).map_err(|e| {
            self.bad += 1;
            ToolError::Unreadable(e.to_string())
        })?;
        let mut values = Vec::new();
        for p in &message.packets {
            let lsn_latency = |lsn: u8| (frame.wrapping_sub(u32::from(lsn))) & 0xF;
            let line = match p {
                Packet::StartOfFrame(s) => {
                    self.start_of_frames += 1;
                    self.last_ig_frame = s.ig_frame_number;
                    None
                }
                Packet::HatHotResponse(r) => Some((
                    lsn_latency(r.host_frame_lsn),
                    serde_json::json!({"packet": "hat_hot", "id": r.hat_hot_id, "valid": r.valid,
                        "hot": r.response_type_hot, "height_m": r.height_m}),
                )),
                Packet::HatHotExtendedResponse(r) => Some((
                    lsn_latency(r.host_frame_lsn),
                    serde_json::json!({"packet": "hat_hot_extended", "id": r.hat_hot_id, "valid": r.valid,
                        "hat_m": r.hat_m, "hot_m": r.hot_m, "material": r.material_code,
                        "normal_azimuth_deg": r.normal_azimuth_deg, "normal_elevation_deg": r.normal_elevation_deg}),
                )),
                Packet::LosResponse(r) => Some((
                    lsn_latency(r.host_frame_lsn),
                    serde_json::json!({"packet": "los", "id": r.los_id, "valid": r.valid,
                        "visible": r.visible, "range_m": r.range_m}),
                )),
                Packet::LosExtendedResponse(r) => Some((
                    lsn_latency(r.host_frame_lsn),
                    serde_json::json!({"packet": "los_extended", "id": r.los_id, "valid": r.valid,
                        "visible": r.visible, "range_valid": r.range_valid, "range_m": r.range_m, "alpha": r.alpha,
                        "lat_deg": r.lat_deg_or_x_m, "lon_deg": r.lon_deg_or_y_m, "alt_m": r.alt_m_or_z_m}),
                )),
                Packet::SensorResponse(r) => Some((
                    0,
                    serde_json::json!({"packet": "sensor", "view": r.view_id, "sensor": r.sensor_id,
                        "status": r.sensor_status, "gate_px": [r.gate_x_size_px, r.gate_y_size_px],
                        "gate_deg": [r.gate_x_position_deg, r.gate_y_position_deg]}),
                )),
                Packet::SensorExtendedResponse(r) => Some((
                    0,
                    serde_json::json!({"packet": "sensor_extended", "view": r.view_id, "sensor": r.sensor_id,
                        "status": r.sensor_status, "gate_px": [r.gate_x_size_px, r.gate_y_size_px],
                        "gate_deg": [r.gate_x_position_deg, r.gate_y_position_deg],
                        "entity": r.entity_id_valid.then_some(r.entity_id),
                        "track": [r.track_latitude_deg, r.track_longitude_deg, r.track_altitude_m]}),
                )),
                Packet::ImageGeneratorMessage(m) => Some((
                    0,
                    serde_json::json!({"packet": "ig_message", "text": m.text}),
                )),
                other => Some((0, serde_json::json!({"packet": other.name()}))),
            };
            if let Some((latency, mut value)) = line {
                let is_answer = matches!(
                    p,
                    Packet::HatHotResponse(_)
                        | Packet::HatHotExtendedResponse(_)
                        | Packet::LosResponse(_)
                        | Packet::LosExtendedResponse(_)
                );
                if is_answer {
                    self.answers += 1;
                    self.latency_sum += u64::from(latency);
                    self.latency_max = self.latency_max.max(latency);
                }
                if let Some(obj) = value.as_object_mut() {
                    obj.insert("host_frame".into(), frame.into());
                    obj.insert("ig_frame".into(), self.last_ig_frame.into());
                    obj.insert("latency_frames".into(), latency.into());
                }
                values.push(value);
            }
        }
        Ok(values)
    }

    /// The last IG frame number received in a Start of Frame.
    #[must_use]
    pub fn last_ig_frame(&self) -> u32 {
        self.last_ig_frame
    }

    /// Start of Frame packets received.
    #[must_use]
    pub fn start_of_frames(&self) -> u64 {
        self.start_of_frames
    }

    fn latency_mean(&self) -> f64 {
        self.latency_sum as f64 / self.answers.max(1) as f64
    }

    /// The summary after `frames_sent` host frames, as JSON.
    #[must_use]
    pub fn summary_json(&self, frames_sent: u32) -> serde_json::Value {
        serde_json::json!({"summary": {
            "frames_sent": frames_sent,
            "start_of_frames": self.start_of_frames,
            "last_ig_frame": self.last_ig_frame,
            "answers": self.answers,
            "bad_messages": self.bad,
            "latency_frames_mean": self.latency_mean(),
            "latency_frames_max": self.latency_max,
        }})
    }

    /// The summary after `frames_sent` host frames, as one line.
    #[must_use]
    pub fn summary_line(&self, frames_sent: u32) -> String {
        format!(
            "sent {frames_sent} frames; {} Start of Frame, {} answers (latency mean {:.2}, max {} frames)",
            self.start_of_frames,
            self.answers,
            self.latency_mean(),
            self.latency_max
        )
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entities_fly_their_paths_at_their_speed() {
        let e = HostEntity {
            id: 0,
            entity_type: 0,
            clamp: "none".into(),
            alt_m: 0.0,
            speed_mps: 100.0,
            path: vec![[0.0, 0.0], [0.0, 0.1], [0.1, 0.1]],
            repeat: false,
        };
        let (lat, lon, heading) = entity_at(&e, 10.0);
        assert!(
            lat.abs() < 1e-9 && (lon - 1000.0 / 111_319.5).abs() < 1e-5,
            "{lat} {lon}"
        );
        assert!((heading - 90.0).abs() < 1e-6);
        let (_, _, heading) = entity_at(&e, 200.0);
        assert!(
            heading.abs() < 1e-3 || (heading - 360.0).abs() < 1e-3,
            "{heading}"
        );
        let (lat, lon, _) = entity_at(&e, 1.0e6);
        assert_eq!((lat, lon), (0.1, 0.1));
    }

    #[test]
    fn a_repeated_path_is_flown_round_and_round() {
        let e = HostEntity {
            id: 0,
            entity_type: 0,
            clamp: "none".into(),
            alt_m: 0.0,
            speed_mps: 100.0,
            path: vec![[0.0, 0.0], [0.0, 0.01], [0.01, 0.01], [0.01, 0.0]],
            repeat: true,
        };
        // Two sides of 0.01° of longitude and two of latitude on the equator: one lap in
        // about 44.4 s.
        let lap_s = 2.0 * 0.01 * (111_319.5 + 110_574.3) / 100.0;
        let (lat, lon, heading) = entity_at(&e, 10.0);
        let (lat2, lon2, heading2) = entity_at(&e, 10.0 + 7.0 * lap_s);
        assert!(
            (lat - lat2).abs() < 1e-4 && (lon - lon2).abs() < 1e-4,
            "{lat},{lon} {lat2},{lon2}"
        );
        assert!((heading - heading2).abs() < 1e-3);
        // The closing side, from the last point back to the first, flies south.
        let (_, _, closing) = entity_at(&e, 3.5 * lap_s / 4.0);
        assert!((closing - 180.0).abs() < 1.0, "{closing}");
        // Not repeated, the same path ends at its last point.
        let once = HostEntity { repeat: false, ..e };
        assert_eq!(entity_at(&once, 7.0 * lap_s).0, 0.01);
    }

    #[test]
    fn a_script_reads_and_builds_its_frames() {
        let script = HostScript::from_toml(
            "version = \"4.0\"\ntime = \"2026-06-21T10:00:00Z\"\n\
             [[entities]]\nid = 3\npath = [[51.0, -1.5]]\n[[hat]]\nid = 1\nentity = 3\n",
        )
        .unwrap();
        assert_eq!((script.rate_hz(), script.frames()), (60.0, 60));
        let first = script.frame(0, 0).unwrap();
        assert_eq!(first.version, Version::V4_0);
        assert!(matches!(first.packets[0], Packet::IgControl(_)));
        let has = |m: &Message, name: &str| m.packets.iter().any(|p| p.name() == name);
        let celestial = Packet::CelestialSphereControl(CelestialSphereControl::default()).name();
        let hat = Packet::HatHotRequest(HatHotRequest::default()).name();
        assert!(has(&first, celestial) && has(&first, hat));
        let later = script.frame(1, 7).unwrap();
        assert!(!has(&later, celestial) && !has(&later, hat), "once only");
        match &later.packets[0] {
            Packet::IgControl(c) => {
                assert_eq!((c.host_frame_number, c.last_ig_frame_number), (1, 7))
            }
            other => panic!("{other:?}"),
        }
        let e = HostScript::from_toml("version = \"5\"").unwrap_err();
        assert_eq!(e.to_string(), "version \"5\" is not 3.3 or 4.0");
        let e = HostScript::from_toml("frames = ").unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn replies_count_answers_and_their_latency() {
        let reply = Message::new(
            Version::V3_3,
            ByteOrder::LittleEndian,
            vec![
                Packet::StartOfFrame(cig_cigi::StartOfFrame {
                    ig_frame_number: 41,
                    ..Default::default()
                }),
                Packet::HatHotResponse(cig_cigi::HatHotResponse {
                    hat_hot_id: 1,
                    valid: true,
                    host_frame_lsn: 3,
                    ..Default::default()
                }),
            ],
        );
        let mut bytes = Vec::new();
        cig_cigi::encode_message(&reply, &mut bytes).unwrap();
        let mut replies = Replies::new();
        let values = replies.read(&bytes, 5).unwrap();
        assert_eq!(values.len(), 1);
        assert_eq!(values[0]["packet"], "hat_hot");
        assert_eq!(values[0]["latency_frames"], 2);
        assert_eq!(values[0]["ig_frame"], 41);
        assert_eq!(
            (replies.start_of_frames(), replies.last_ig_frame()),
            (1, 41)
        );
        assert!(replies.read(b"garbage", 6).is_err());
        let summary = replies.summary_json(6);
        assert_eq!(summary["summary"]["answers"], 1);
        assert_eq!(summary["summary"]["bad_messages"], 1);
        assert!(replies
            .summary_line(6)
            .starts_with("sent 6 frames; 1 Start of Frame, 1 answers"));
    }
}
