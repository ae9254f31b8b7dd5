//! The IG's world for one run: the CIGI session, the scenario's scripted entities, the DIS
//! exercise, the simulation clock and the obscurant effects, stepped once per frame and read
//! into the renderer's plain snapshot.
//!
//! Algorithm, per frame (the order `cig serve` follows):
//! 1. host messages and DIS datagrams received since the last frame are applied as they come
//!    ([`IgWorld::receive_cigi`], [`IgWorld::receive_dis`]);
//! 2. [`IgWorld::step`] advances the clock (the exercise's shared world time when the IG is in
//!    one; a time the host set through Celestial Sphere Control wins and is announced), moves
//!    scripted entities along their paths and host entities by their rates, resolves every
//!    pose (clamping, attachments), advances the effects and publishes owned entities, and
//!    lights the lightning storm's strikes due by the new time ([`crate::weather`]: the
//!    scenario's or operator's storm, else the host's random lightning; strikes received over
//!    DIS are lit too and this IG's own are announced);
//! 3. [`IgWorld::host_message`] is the frame's message to the host: Start of Frame and the
//!    answers to the requests received in step 1;
//! 4. [`IgWorld::snapshot`] is what the renderer draws: with the bolts lit now, the flash's
//!    illuminance at the first eye, and the rain or snow over it (the operator's, else the
//!    host's precipitation layer, else the scenario's), whose extinction is added to the
//!    visibility unless the host's layer states its own.
//!
//! Time: scripted entities move on their own forward-only time (elapsed seconds × the clock's
//! rate), so a time of day set by the host or the exercise does not make them jump. Effects run
//! on the shared world time; when it goes back (a host or master sets an earlier time) the
//! effect system starts over from the new time (scenario smoke restarts, other effects start
//! again with their next event). The DIS velocity of an owned entity is its script's, else the
//! difference of positions at least 0.2 s apart.
//!
//! Limits: scripted entities follow straight segments at constant speed; a host entity with
//! the same ID as a scripted one takes it over for good (it stops following its script); effect
//! time is world time since 2020-01-01 and the effect system accepts ±1e9 s of it, so worlds
//! before 1988 or after 2051 cannot be built.

use crate::exercise::{Exercise, OwnedProcess, OwnedTruth};
use crate::model_table::{CigiEntityType, ModelTable};
use crate::pose::{azimuth_elevation_deg, child_pose, wrap_deg, BodyOffset, Pose};
use crate::scenario::{DisTypePattern, Scenario, ScenarioEntity, SmokeSource};
use crate::session::{EntityLife, IgEntity, IgSession, Placement, SessionConfig};
use cig_cigi::{decode_message, CigiError, Message};
use cig_effects::effect_time_s;
use cig_effects::{
    EffectHandle, EffectId, EffectSystem, EffectsConfig, EffectsError, PlumeKind, PlumeSource,
    PlumeSpec,
};
use cig_environment::clouds::{CloudKind, CloudLayer, CloudOrigin};
use cig_environment::{SimClock, UtcTime};
use cig_geo::{EnuFrame, Geodetic};
use cig_scene::lighting::{Fog, FogMode};
use cig_scene::snapshot::EntityInstance;
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::QuerySession;
use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet};

/// Why a world cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("clock: {0}")]
    Clock(#[from] cig_environment::EnvironmentError),
    #[error("effects: {0}")]
    Effects(#[from] EffectsError),
}

/// How the world is set up.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldConfig {
    pub session: SessionConfig,
    /// Simulation start (the scenario's, else the caller's choice).
    pub start: UtcTime,
    pub fog_mode: FogMode,
    pub effects: EffectsConfig,
    /// Join the scenario's DIS exercise (the caller opens the sockets).
    pub join_exercise: bool,
}

/// A scenario entity's path, in a tangent frame at its start.
struct Script {
    frame: EnuFrame,
    /// Polyline vertices (east, north) and cumulative lengths.
    points: Vec<DVec3>,
    cumulative_m: Vec<f64>,
    speed_mps: f64,
    loop_path: bool,
    heading_deg: f64,
}

impl Script {
    fn new(e: &ScenarioEntity) -> Script {
        let origin = Geodetic::new(e.lat_deg, e.lon_deg, 0.0);
        let frame = EnuFrame::new(origin);
        let mut points = vec![DVec3::ZERO];
        for p in &e.path {
            let v = frame.geodetic_to_enu(Geodetic::new(p[0], p[1], 0.0));
            points.push(DVec3::new(v.x, v.y, 0.0));
        }
        if e.loop_path && points.len() > 1 {
            points.push(DVec3::ZERO);
        }
        let mut cumulative_m = vec![0.0];
        for w in points.windows(2) {
            let last = cumulative_m.last().copied().unwrap_or(0.0);
            cumulative_m.push(last + (w[1] - w[0]).length());
        }
        Script {
            frame,
            points,
            cumulative_m,
            speed_mps: e.speed_mps,
            loop_path: e.loop_path,
            heading_deg: e.heading_deg,
        }
    }

    /// Latitude, longitude, heading and east-north velocity after `t_s` seconds.
    fn at(&self, t_s: f64) -> (f64, f64, f64, DVec3) {
        let total = self.cumulative_m.last().copied().unwrap_or(0.0);
        if total <= 0.0 || self.speed_mps <= 0.0 {
            let o = self.frame.origin();
            return (o.lat_deg, o.lon_deg, self.heading_deg, DVec3::ZERO);
        }
        let mut s = self.speed_mps * t_s.max(0.0);
        let moving = self.loop_path || s < total;
        s = if self.loop_path {
            s.rem_euclid(total)
        } else {
            s.min(total)
        };
        let i = self
            .cumulative_m
            .windows(2)
            .position(|w| s <= w[1])
            .unwrap_or(self.points.len().saturating_sub(2));
        let (a, b) = (self.points[i], self.points[i + 1]);
        let len = self.cumulative_m[i + 1] - self.cumulative_m[i];
        let dir = if len > 0.0 {
            (b - a) / len
        } else {
            DVec3::ZERO
        };
        let p = a + dir * (s - self.cumulative_m[i]);
        let g = self.frame.enu_to_geodetic(p);
        let heading = wrap_deg(dir.x.atan2(dir.y).to_degrees());
        let velocity = if moving {
            dir * self.speed_mps
        } else {
            DVec3::ZERO
        };
        (g.lat_deg, g.lon_deg, heading, velocity)
    }
}

/// Time constant with which a view's drawn area-of-interest point follows the host's, seconds
/// (a saccade of about 30 ms moves it a sixth of the way; a fixation of half a second, most).
pub const POINT_OF_INTEREST_LAG_S: f64 = 0.15;

/// The DIS exercise's ships are floated on the sea within this distance of an eye or of the
/// database's centre, metres (beyond it they are below the horizon of any eye near the sea).
const REMOTE_SHIPS_FLOATED_WITHIN_M: f64 = 400_000.0;

/// A ship's last sampled place and the speed and course it made good between samples.
#[derive(Clone, Copy, Debug)]
struct MadeGood {
    /// Monotonic time of the sample, seconds.
    at_s: f64,
    position: Geodetic,
    speed_mps: f64,
    course_deg: f64,
}

impl MadeGood {
    /// This sample making good `velocity_enu_mps` (east, north): its course, or (nearly still)
    /// the heading it had at rest.
    fn moving(self, velocity_enu_mps: [f64; 2]) -> MadeGood {
        let [east, north] = velocity_enu_mps;
        let speed_mps = east.hypot(north);
        MadeGood {
            speed_mps,
            course_deg: if speed_mps > 0.1 {
                east.atan2(north).to_degrees().rem_euclid(360.0)
            } else {
                self.course_deg
            },
            ..self
        }
    }
}

/// The horizontal velocity (east, north), m/s, the host's Rate Control gives a geodetic
/// entity, if it gives one.
fn host_velocity_enu_mps(e: &IgEntity) -> Option<[f64; 2]> {
    let rates = e.rates?;
    if !matches!(e.placement, Placement::Geodetic { .. }) {
        return None;
    }
    let enu = rates.velocity_enu_mps(e.orientation);
    Some([enu.x, enu.y])
}

/// This IG's ships' speed is sampled over at least this long, seconds (unless the host's
/// Rate Control gives it).
const SHIP_SPEED_SAMPLE_S: f64 = 0.5;
/// A ship's last place older than this starts its speed over (a jump, a pause), seconds.
const SHIP_SPEED_STALE_S: f64 = 5.0;

/// Everything the IG simulates.
pub struct IgWorld {
    session: IgSession,
    scenario: Scenario,
    clock: SimClock,
    start_unix_s: f64,
    exercise: Option<Exercise>,
    effects: EffectSystem,
    monotonic_s: f64,
    scripts: BTreeMap<u16, Script>,
    /// Per entity: the last position sample (time, place) and the velocity it gave.
    previous_owned: BTreeMap<u16, (f64, Geodetic, DVec3)>,
    fog_mode: FogMode,
    cigi_rejected: u64,
    smoke: Vec<SmokeState>,
    last_process_publish_s: f64,
    /// Seconds of scripted motion since the start (forward only, at the clock's rate).
    script_time_s: f64,
    /// The host's clock at the last [`IgWorld::step_to_host_clock`].
    host_clock_stepped_s: Option<f64>,
    /// The host's views this IG draws (a display channel's); `None`: all of them.
    channel_views: Option<BTreeSet<u16>>,
    /// Appearance effects of the scenario's entities, by (entity, effect).
    owned_effects: BTreeMap<(u16, cig_dis::EntityEffect), cig_effects::EffectHandle>,
    /// The first view's eye after the last step, and the geoid undulation there.
    first_eye: Option<Geodetic>,
    /// Each host view's area-of-interest point as drawn, degrees right and up of its centre:
    /// the host's point followed with a lag ([`POINT_OF_INTEREST_LAG_S`]).
    points_of_interest: BTreeMap<u16, [f64; 2]>,
    eye_geoid_m: f64,
    /// Geoid undulation at the scenario's fixed eye, if it has one.
    fixed_eye_geoid_m: f64,
    last_air_update_s: f64,
    operator_wind: Option<cig_effects::system::Wind>,
    operator_plumes: Vec<cig_effects::EffectHandle>,
    operator_plumes_started: u32,
    /// Dust trails of the ground vehicles this IG moves, by entity.
    dust_trails: BTreeMap<u16, cig_effects::EffectHandle>,
    /// Ruts behind the ground vehicles this IG moves.
    ruts: crate::terrain_edits::RutTracker,
    /// The effects could not advance to the world time (told once until they can again).
    effects_stalled: bool,
    /// This frame's cloud layers (bases above MSL): the operator's, else the host's (CIGI
    /// weather layers 1-3), else the scenario's.
    clouds: Vec<CloudLayer>,
    /// The operator's cloud layers, when set (they win over the host's and the scenario's).
    operator_clouds: Option<Vec<CloudLayer>>,
    /// The clouds' world-fixed noise origin: the database centre's whole degrees, kept for the run.
    cloud_origin: Option<CloudOrigin>,
    /// Lightning: the scenario's storm and the bolts lit now.
    lightning: crate::weather::Lightning,
    /// Strikes received over DIS since `take_lightning` was last called (kept for callers).
    received_strikes: Vec<cig_dis::LightningStrike>,
    /// The operator's precipitation (wins over the scenario's and the host's), or `Some(None)`
    /// when the operator stopped it.
    operator_precipitation: Option<Option<cig_environment::Precipitation>>,
    /// The host's precipitation told (clamped values reported once).
    precipitation_told: bool,
    /// Strikes received over DIS and drawn.
    lightning_received: u64,
    /// The operator's or the scenario's storm (wins over the host's random lightning).
    own_storm: Option<crate::weather::LightningStorm>,
    /// The thermal sensors' state (spun up when a sensor view first needs it).
    thermal: crate::thermal::ThermalWorld,
    /// The thermal model failed (told once).
    thermal_told: bool,
    /// Each tracking sensor's tracker, by (view, sensor).
    trackers: BTreeMap<(u16, u8), crate::tracker::Tracker>,
    /// The operator's sensor for every view (the panel's switch), over the host's.
    operator_sensor: Option<cig_scene::thermal::SensorView>,
    /// The operator's night-vision goggle for every view (the panel's switch), over the
    /// host's; a thermal sensor on the same view wins.
    operator_nvg: Option<cig_scene::nvg::NvgView>,
    /// The scenario's flares and the surface under each (above the ellipsoid) once the
    /// terrain query answered there.
    flares: Vec<(cig_scene::lights::Flare, Option<f64>)>,
    /// The sea (the scenario's and the host's).
    sea: crate::sea::WorldSea,
    /// The DIS exercise's ships afloat this frame, by draw id (their dead-reckoned place on
    /// the waves at the world time: the same on every IG).
    remote_afloat: BTreeMap<u32, crate::pose::Pose>,
    /// This IG's ships' speed and course made good, by entity.
    ship_motion: BTreeMap<u16, MadeGood>,
    /// The wakes of the ships under way on the sea this frame.
    wakes: Vec<cig_scene::sea::WakeDraw>,
    /// The ships' sterns' past places, for their wakes to follow: this IG's ships by entity id,
    /// the exercise's by `REMOTE_WAKE | remote_instance_id`.
    wake_tracks: BTreeMap<u64, cig_scene::sea::WakeTrack>,
}

/// The exercise's ships' keys among the wakes' tracks.
const REMOTE_WAKE: u64 = 1 << 32;

/// A scenario smoke source and the plume it runs.
struct SmokeState {
    source: SmokeSource,
    /// Source position once placed on the terrain, and its plume.
    started: Option<(Geodetic, EffectHandle)>,
    /// Placing it failed (off the database): reported once, never retried.
    failed: bool,
}

fn model_for_scenario_entity(e: &ScenarioEntity, table: &ModelTable) -> String {
    if let Some(m) = &e.model {
        return m.clone();
    }
    match e
        .dis_type
        .as_deref()
        .and_then(DisTypePattern::parse)
        .and_then(|p| p.exact())
    {
        Some(t) => table.model_for_dis(&t).to_string(),
        None => table.model_for_cigi(CigiEntityType::Short(0)).to_string(),
    }
}

impl IgWorld {
    pub fn new(scenario: Scenario, config: WorldConfig) -> Result<IgWorld, WorldError> {
        let thermal = crate::thermal::ThermalWorld::new(scenario.thermal.as_ref());
        let models = ModelTable::from_scenario(&scenario);
        let mut session = IgSession::new(config.session.clone(), models.clone());
        session.set_scenario_water(crate::sea::Water::of_scenario(scenario.sea.as_ref()));
        let sea = crate::sea::WorldSea::new(scenario.sea.as_ref());
        let mut scripts = BTreeMap::new();
        for e in &scenario.entities {
            let mut entity = IgEntity::new(
                e.id,
                CigiEntityType::Short(0),
                model_for_scenario_entity(e, &models),
            );
            entity.placement = Placement::Geodetic {
                lat_deg: e.lat_deg,
                lon_deg: e.lon_deg,
                alt_m: e.alt_m,
            };
            entity.orientation = Hpr {
                heading_deg: e.heading_deg,
                ..Hpr::default()
            };
            entity.clamp = e.clamp;
            entity.scripted = true;
            session.insert_entity(entity);
            scripts.insert(e.id, Script::new(e));
        }
        let clock = SimClock::new(config.start, scenario.time_rate)?;
        let start_unix_s = config.start.unix_seconds();
        let exercise = match (&scenario.dis, config.join_exercise) {
            (Some(settings), true) => Some(Exercise::join(
                settings,
                &scenario,
                0.0,
                start_unix_s,
                scenario.time_rate,
            )),
            _ => None,
        };
        let smoke = scenario
            .smoke
            .iter()
            .map(|source| SmokeState {
                source: source.clone(),
                started: None,
                failed: false,
            })
            .collect();
        let mut effects = EffectSystem::new(config.effects)?;
        effects.advance_to(effect_time_s(start_unix_s))?;
        let clouds = scenario.cloud_layers();
        let scenario_storm = scenario.lightning.as_ref().and_then(|l| l.storm());
        let flares = scenario
            .flares
            .iter()
            .filter_map(|f| f.flare(start_unix_s))
            .map(|f| (f, None))
            .collect();
        Ok(IgWorld {
            session,
            scenario,
            clock,
            start_unix_s,
            exercise,
            effects,
            monotonic_s: 0.0,
            scripts,
            previous_owned: BTreeMap::new(),
            fog_mode: config.fog_mode,
            cigi_rejected: 0,
            smoke,
            last_process_publish_s: f64::NEG_INFINITY,
            script_time_s: 0.0,
            host_clock_stepped_s: None,
            channel_views: None,
            owned_effects: BTreeMap::new(),
            first_eye: None,
            points_of_interest: BTreeMap::new(),
            eye_geoid_m: 0.0,
            fixed_eye_geoid_m: 0.0,
            last_air_update_s: f64::NEG_INFINITY,
            operator_wind: None,
            clouds,
            operator_clouds: None,
            cloud_origin: None,
            operator_plumes: Vec::new(),
            operator_plumes_started: 0,
            dust_trails: BTreeMap::new(),
            ruts: crate::terrain_edits::RutTracker::default(),
            effects_stalled: false,
            lightning: crate::weather::Lightning::new(scenario_storm),
            received_strikes: Vec::new(),
            operator_precipitation: None,
            precipitation_told: false,
            lightning_received: 0,
            own_storm: scenario_storm,
            thermal,
            thermal_told: false,
            trackers: BTreeMap::new(),
            operator_sensor: None,
            operator_nvg: None,
            flares,
            sea,
            remote_afloat: BTreeMap::new(),
            ship_motion: BTreeMap::new(),
            wakes: Vec::new(),
            wake_tracks: BTreeMap::new(),
        })
    }

    pub fn session(&self) -> &IgSession {
        &self.session
    }
    pub fn session_mut(&mut self) -> &mut IgSession {
        &mut self.session
    }
    pub fn exercise(&self) -> Option<&Exercise> {
        self.exercise.as_ref()
    }
    pub fn exercise_mut(&mut self) -> Option<&mut Exercise> {
        self.exercise.as_mut()
    }
    /// Lightning strikes other nodes announced since the last call (they are drawn too).
    pub fn take_lightning(&mut self) -> Vec<cig_dis::LightningStrike> {
        let mut strikes = std::mem::take(&mut self.received_strikes);
        if let Some(x) = self.exercise.as_mut() {
            strikes.extend(x.take_lightning());
        }
        strikes
    }
    /// The world's lightning (storm, statistics).
    pub fn lightning(&self) -> &crate::weather::Lightning {
        &self.lightning
    }
    /// Sets or ends the storm (the operator's).
    pub fn set_lightning_storm(&mut self, storm: Option<crate::weather::LightningStorm>) {
        self.own_storm = storm;
        self.lightning.set_storm(storm);
    }
    /// Strikes received over DIS and drawn.
    pub fn lightning_received(&self) -> u64 {
        self.lightning_received
    }
    /// Strikes now at `ground` (the operator's "strike now"), announced to the exercise.
    pub fn strike_lightning_now(&mut self, ground: Geodetic, seed: u64) {
        let now = self.unix_time_s();
        let base = self.lightning.storm().map_or(1500.0, |s| s.cloud_base_m);
        if self.lightning.strike(now, ground, base, seed, 1.0) {
            if let Some(x) = self.exercise.as_mut() {
                x.announce_lightning(self.monotonic_s, ground.to_ecef(), seed, 1.0);
            }
        }
    }
    /// Sets the operator's precipitation (`None` stops it); it wins over the scenario's and
    /// the host's.
    pub fn set_operator_precipitation(
        &mut self,
        precipitation: Option<cig_environment::Precipitation>,
    ) {
        self.operator_precipitation = Some(precipitation);
    }
    /// The precipitation falling at the first eye now (the operator's, else the host's rain,
    /// snow or sleet layer over the eye, else the scenario's).
    pub fn precipitation(&self) -> Option<cig_environment::Precipitation> {
        if let Some(p) = self.operator_precipitation {
            return p;
        }
        let eye_msl = self
            .first_eye
            .map(|e| Geodetic::new(e.lat_deg, e.lon_deg, e.alt_m - self.eye_geoid_m));
        if let Some(p) = eye_msl.and_then(|e| self.session.environment().precipitation_at(e)) {
            return Some(p);
        }
        self.scenario
            .precipitation
            .as_ref()
            .and_then(|p| p.precipitation())
    }
    pub fn effects(&self) -> &EffectSystem {
        &self.effects
    }
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }
    /// Simulation time, seconds since 1970 UTC.
    pub fn unix_time_s(&self) -> f64 {
        self.clock.now().unix_seconds()
    }
    /// Seconds of the IG's own (monotonic) time since it started.
    pub fn monotonic_s(&self) -> f64 {
        self.monotonic_s
    }
    /// Host messages refused as a whole (not CIGI, wrong version, truncated).
    pub fn cigi_rejected(&self) -> u64 {
        self.cigi_rejected
    }

    /// Applies one datagram from the host.
    pub fn receive_cigi(&mut self, datagram: &[u8]) -> Result<(), CigiError> {
        match decode_message(datagram) {
            Ok(message) => {
                self.session.apply(&message);
                Ok(())
            }
            Err(e) => {
                self.cigi_rejected += 1;
                Err(e)
            }
        }
    }

    /// Advances the world to the host's clock (CIGI synchronous mode: the host's IG Control
    /// timestamps, [`IgSession::host_clock_s`]), so every channel stepped with the same host
    /// messages reaches the same state whatever its own timing. The first time, and after a jump
    /// of the host's clock (back, or more than 10 s on: a channel that started late or
    /// restarted, a host that restarted), the world is placed on the host's clock: the time of
    /// day the start plus the host's clock at the clock's rate, the scripts at that time (the
    /// host's next time of day, and the exercise's time, override it as usual). Without a host
    /// clock it advances by `fallback_dt_s` (a host that sends no timestamp: one frame period).
    pub fn step_to_host_clock(&mut self, fallback_dt_s: f64, query: &mut QuerySession) {
        let Some(host_s) = self.session.host_clock_s() else {
            self.step(fallback_dt_s, query);
            return;
        };
        match self.host_clock_stepped_s {
            Some(last) if (0.0..=10.0).contains(&(host_s - last)) => {
                self.host_clock_stepped_s = Some(host_s);
                self.step(host_s - last, query);
            }
            _ => {
                self.host_clock_stepped_s = Some(host_s);
                let rate = self.clock.rate();
                // Out of the supported years (a host clock of centuries): the clock stays.
                if let Ok(t) = UtcTime::from_unix_seconds(self.start_unix_s + host_s * rate) {
                    self.clock.set_time(t);
                }
                self.script_time_s = host_s.max(0.0) * rate.max(0.0);
                self.step(0.0, query);
            }
        }
    }

    /// Draws only the host's views with these identifiers (a display channel of a
    /// multi-channel IG); `None` draws every view the host defines. The world is the same in
    /// every channel: only what is drawn differs.
    pub fn set_channel_views(&mut self, views: Option<BTreeSet<u16>>) {
        self.channel_views = views;
    }

    /// The channel's view identifiers the host has not defined (with a pose) yet.
    pub fn channel_views_missing(&self) -> Vec<u16> {
        self.channel_views.as_ref().map_or_else(Vec::new, |ids| {
            ids.iter()
                .copied()
                .filter(|id| {
                    self.session
                        .views()
                        .get(id)
                        .is_none_or(|v| self.session.view_pose(v).is_none())
                })
                .collect()
        })
    }

    /// The host's identifiers of the views [`IgWorld::snapshot`] draws, in its order (`None`
    /// for the scenario's or the fallback view, drawn when the host gives none).
    pub fn drawn_view_ids(&self) -> Vec<Option<u16>> {
        let ids: Vec<Option<u16>> = self
            .session
            .views()
            .values()
            .filter(|v| self.draws_view(v.id) && self.session.view_pose(v).is_some())
            .map(|v| Some(v.id))
            .collect();
        if ids.is_empty() {
            vec![None]
        } else {
            ids
        }
    }

    /// Whether the channel draws the host's view `id`.
    fn draws_view(&self, id: u16) -> bool {
        self.channel_views
            .as_ref()
            .is_none_or(|ids| ids.contains(&id))
    }

    /// Applies one DIS datagram.
    pub fn receive_dis(&mut self, datagram: &[u8], query: &mut QuerySession) {
        if let Some(x) = self.exercise.as_mut() {
            x.receive(self.monotonic_s, datagram, &mut self.effects, query);
        }
    }

    /// Advances the world by `real_dt_s` seconds of the IG's own time.
    pub fn step(&mut self, real_dt_s: f64, query: &mut QuerySession) {
        let dt = if real_dt_s.is_finite() {
            real_dt_s.clamp(0.0, 10.0)
        } else {
            0.0
        };
        self.monotonic_s += dt;
        let now = self.monotonic_s;
        // A host repeating the current time every frame changes nothing and announces nothing.
        // Stepped on the host's clock (a display channel), the world takes the host's time of
        // day exactly, so channels started seconds apart agree to the frame.
        let tolerance_s = if self.host_clock_stepped_s.is_some() {
            1e-3
        } else {
            1.0
        };
        let set = self.session.take_time_set().and_then(|set| {
            set.time_to_take(
                self.clock.now().unix_seconds(),
                self.host_clock_stepped_s,
                self.clock.rate(),
                tolerance_s,
            )
        });
        if let Some(t) = set {
            self.clock.set_time(t);
            if let Some(x) = self.exercise.as_mut() {
                x.set_time(now, t.unix_seconds(), self.clock.rate());
            }
        } else if let Some(x) = &self.exercise {
            let t = UtcTime::clamped_from_seconds_since_j2000(
                UtcTime::from_unix_seconds(x.world_time_unix_s(now))
                    .map_or(self.clock.now().seconds_since_j2000(), |t| {
                        t.seconds_since_j2000()
                    }),
            );
            self.clock.set_time(t);
        } else if let Err(e) = self.clock.advance(dt) {
            tracing::warn!("the simulation clock stops: {e}");
        }
        // Scripts run on their own time, which only moves forward at the clock's rate: a time
        // of day the host or the exercise sets does not make entities jump along their paths.
        let rate = self
            .exercise
            .as_ref()
            .map_or(self.clock.rate(), Exercise::rate);
        self.script_time_s += dt * rate.max(0.0);
        self.follow_points_of_interest(dt);
        let mut script_velocity = BTreeMap::new();
        for (id, script) in &self.scripts {
            let Some(e) = self.session.entity_mut(*id) else {
                continue;
            };
            if !e.scripted {
                continue;
            }
            let (lat_deg, lon_deg, heading_deg, velocity) = script.at(self.script_time_s);
            let alt_m = match e.placement {
                Placement::Geodetic { alt_m, .. } => alt_m,
                Placement::Attached { .. } => 0.0,
            };
            e.placement = Placement::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            };
            e.orientation.heading_deg = heading_deg;
            script_velocity.insert(*id, velocity);
        }
        self.session.advance(dt, query);
        self.update_sea(query);
        // Ships whose velocity the script or the host gives ride the sea with it this frame.
        let known_velocities = self.known_ship_velocities(&script_velocity);
        for (id, velocity) in &known_velocities {
            self.session.set_ship_velocity(*id, *velocity);
        }
        self.session.resolve_poses(query);
        self.float_remote_ships(query);
        self.track_own_ships(query, &known_velocities);
        let effect_time_s = effect_time_s(self.clock.now().unix_seconds());
        if self
            .effects
            .time_s()
            .is_some_and(|t| effect_time_s < t - 1.0)
        {
            // The world went back in time (a host or master set an earlier time): the effects
            // start over from the new time.
            match EffectSystem::new(*self.effects.config()) {
                Ok(fresh) => {
                    self.effects = fresh;
                    for s in &mut self.smoke {
                        s.started = None;
                        s.failed = false;
                    }
                    self.owned_effects.clear();
                    self.operator_plumes.clear();
                    self.dust_trails.clear();
                    if let Some(x) = self.exercise.as_mut() {
                        x.forget_effects();
                    }
                    self.last_air_update_s = f64::NEG_INFINITY;
                    // Told once: the host hears each problem once.
                    self.session
                        .tell_host("the simulation time went back: obscurants start over".into());
                }
                Err(e) => tracing::warn!("effects cannot start over: {e}"),
            }
        }
        if now - self.last_air_update_s >= 1.0 {
            self.last_air_update_s = now;
            self.update_effects_air();
        }
        if let Err(e) = self.effects.advance_to(effect_time_s) {
            if !self.effects_stalled {
                self.effects_stalled = true;
                self.session
                    .tell_host(format!("obscurants stop advancing: {e}"));
                tracing::warn!("effects stop advancing: {e}");
            }
        } else {
            self.effects_stalled = false;
        }
        self.start_smoke(query);
        self.update_thermal(query);
        self.place_flares(query);
        // Velocities: the script's where there is one, else positions at least 0.2 s apart.
        let mut velocities = BTreeMap::new();
        let poses: Vec<(u16, Pose)> = self.session.poses().iter().map(|(k, v)| (*k, *v)).collect();
        self.previous_owned
            .retain(|id, _| self.session.poses().contains_key(id));
        for (id, pose) in &poses {
            // Velocities are per second of the IG's own (real) time, as DIS dead reckoning runs;
            // a script moves `rate` world seconds a real second.
            let velocity = match script_velocity.get(id) {
                Some(v) => *v * rate.max(0.0),
                None => {
                    let sample =
                        self.previous_owned
                            .entry(*id)
                            .or_insert((now, pose.position, DVec3::ZERO));
                    let span = now - sample.0;
                    if span >= 0.2 {
                        let v = EnuFrame::new(sample.1).geodetic_to_enu(pose.position) / span;
                        // A jump (a teleport, an id reused) is not a velocity.
                        *sample = (
                            now,
                            pose.position,
                            if v.length() < 3000.0 { v } else { DVec3::ZERO },
                        );
                    }
                    sample.2
                }
            };
            velocities.insert(*id, velocity);
        }
        // Effects run on world time: velocities per world second.
        let world_velocities: BTreeMap<u16, DVec3> = velocities
            .iter()
            .map(|(id, v)| (*id, if rate > 0.0 { *v / rate } else { DVec3::ZERO }))
            .collect();
        self.run_owned_effects(query, effect_time_s, &world_velocities);
        self.run_vehicle_dust(query, effect_time_s, &world_velocities);
        self.run_vehicle_ruts(query, now);
        self.run_host_terrain_edits(query, now);
        if let Some(x) = self.exercise.as_mut() {
            if now - self.last_process_publish_s >= 1.0 && !self.smoke.is_empty() {
                self.last_process_publish_s = now;
                let processes =
                    smoke_processes(&self.smoke, &self.effects, effect_time_s, self.start_unix_s);
                x.publish_processes(now, &processes);
            }
            let truths: BTreeMap<u16, OwnedTruth> = poses
                .iter()
                .map(|(id, pose)| {
                    (
                        *id,
                        OwnedTruth {
                            position: pose.position,
                            orientation: pose.orientation,
                            velocity_enu_mps: velocities.get(id).copied().unwrap_or(DVec3::ZERO),
                        },
                    )
                })
                .collect();
            x.tick(now, &truths, &mut self.effects, query);
        }
        if let Some(eye) = self.scenario.view.as_ref().and_then(|v| v.eye) {
            self.fixed_eye_geoid_m = query.geoid_undulation_m(eye[0], eye[1]);
        }
        // The eye of the world's first view (none when only the caller's fallback is drawn).
        self.first_eye = self.world_views(1, 1).first().map(|v| v.eye);
        self.eye_geoid_m = self
            .first_eye
            .map_or(0.0, |e| query.geoid_undulation_m(e.lat_deg, e.lon_deg));
        if self.cloud_origin.is_none() {
            // The clouds' pattern is anchored at the database's centre (whole degrees): every
            // channel and IG on this database draws the same clouds, wherever its eye starts.
            let grid = query.cache().database().layout().grid;
            self.cloud_origin = Some(CloudOrigin {
                lat_deg: (0.5 * (grid.south_lat_deg + grid.north_lat_deg())).round(),
                lon_deg: (0.5 * (grid.west_lon_deg + grid.east_lon_deg())).round(),
            });
        }
        self.update_clouds();
        self.step_lightning(query);
        self.report_host_precipitation();
    }

    /// This frame's cloud layers: the operator's, else the host's CIGI cloud layers over the
    /// first eye (values clamped into range, each correction told to the host; a Cloud Type of
    /// 0 means no cloud), else the scenario's. A layer that was there last frame (same seed
    /// and kind) carries on its drift, so a change of its wind does not move the pattern.
    fn update_clouds(&mut self) {
        let wanted = self.wanted_clouds();
        let now_unix_s = self.clock.now().unix_seconds();
        let previous = std::mem::take(&mut self.clouds);
        self.clouds = wanted
            .into_iter()
            .map(|layer| {
                match previous
                    .iter()
                    .find(|p| p.seed == layer.seed && p.kind == layer.kind)
                {
                    Some(p) => layer.continuing(p, now_unix_s),
                    None => layer,
                }
            })
            .collect();
    }

    /// The cloud layers the operator, the host or the scenario state now (see `update_clouds`).
    fn wanted_clouds(&mut self) -> Vec<CloudLayer> {
        if let Some(layers) = &self.operator_clouds {
            return layers.clone();
        }
        let eye_msl = self.first_eye.map_or(Geodetic::new(0.0, 0.0, 0.0), |e| {
            Geodetic::new(e.lat_deg, e.lon_deg, e.alt_m - self.eye_geoid_m)
        });
        let host = self.session.environment().cloud_layers_at(eye_msl);
        if host.is_empty() {
            return self.scenario.cloud_layers();
        }
        let mut clouds = Vec::new();
        for w in host {
            let Some(kind) = CloudKind::from_cigi(w.cloud_type) else {
                continue;
            };
            let (layer, notes) = CloudLayer {
                base_m: f64::from(w.base_elevation_m),
                thickness_m: f64::from(w.thickness_m),
                coverage: f64::from(w.coverage_pct) / 100.0,
                kind,
                wind_speed_mps: f64::from(w.horizontal_wind_speed_mps),
                wind_from_deg: f64::from(w.wind_direction_deg),
                seed: u64::from(w.layer_id),
                drift: cig_environment::CloudDrift::default(),
            }
            .clamped();
            for note in notes {
                self.session
                    .tell_host(format!("Weather Control layer {}: {note}", w.layer_id));
            }
            clouds.push(layer);
        }
        clouds
    }

    /// Sets the operator's cloud layers (bases above MSL), or gives the clouds back to the
    /// host and the scenario (`None`).
    ///
    /// # Errors
    /// The first invalid layer or too many layers; nothing changes then.
    pub fn set_operator_clouds(
        &mut self,
        layers: Option<Vec<CloudLayer>>,
    ) -> Result<(), cig_environment::EnvironmentError> {
        if let Some(layers) = &layers {
            cig_environment::CloudField::new(layers)?;
        }
        self.operator_clouds = layers;
        self.update_clouds();
        Ok(())
    }

    /// This frame's cloud layers (bases above MSL).
    pub fn cloud_layers(&self) -> &[CloudLayer] {
        &self.clouds
    }

    /// The storm's strikes since the last step lit (and announced), received ones lit.
    fn step_lightning(&mut self, query: &mut QuerySession) {
        let now_unix_s = self.clock.now().unix_seconds();
        // The host's random lightning (CIGI Weather Control) where this IG has no storm of its
        // own: a storm around the eye's 0.1° cell, so IGs near each other share it.
        let host = self.first_eye.and_then(|eye| {
            let eye_msl = Geodetic::new(eye.lat_deg, eye.lon_deg, eye.alt_m - self.eye_geoid_m);
            self.session.environment().random_lightning_at(eye_msl).map(
                |(strikes_per_minute, layer)| {
                    let (cell_lat, cell_lon) =
                        ((eye.lat_deg * 10.0).round(), (eye.lon_deg * 10.0).round());
                    // The cell is in the seed: IGs in different cells must not strike the same
                    // bolt seed at the same moment (each would drop the other's as a repeat).
                    let cell = ((cell_lat as i64 as u64 & 0xffff) << 16)
                        | (cell_lon as i64 as u64 & 0xffff);
                    crate::weather::LightningStorm {
                        centre_lat_deg: cell_lat / 10.0,
                        centre_lon_deg: cell_lon / 10.0,
                        radius_m: 15_000.0,
                        cloud_base_m: 1500.0,
                        strikes_per_minute,
                        seed: 0x4349_4749_0000_0000 ^ (cell << 8) ^ u64::from(layer),
                    }
                },
            )
        });
        let storm = self.own_storm.or(host);
        if self.lightning.storm() != storm.as_ref() {
            self.lightning.set_storm(storm);
        }
        let scheduled = self.lightning.advance(now_unix_s, |lat, lon| {
            query.hot(lat, lon).map_or(0.0, |g| g.height_ellipsoid_m())
        });
        if let Some(x) = self.exercise.as_mut() {
            for (s, ground) in &scheduled {
                x.announce_lightning(self.monotonic_s, ground.to_ecef(), s.bolt_seed, s.intensity);
            }
            let base = self.lightning.storm().map_or(1500.0, |s| s.cloud_base_m);
            for strike in x.take_lightning() {
                let ground = Geodetic::from_ecef(strike.position_ecef_m);
                if self
                    .lightning
                    .strike(now_unix_s, ground, base, strike.seed, strike.intensity)
                {
                    self.lightning_received += 1;
                }
                if self.received_strikes.len() < 64 {
                    self.received_strikes.push(strike);
                }
            }
        }
    }

    /// Tells the host once when its rain or snow layer's values were clamped.
    fn report_host_precipitation(&mut self) {
        if self.precipitation_told {
            return;
        }
        if let Some(reason) = self.session.environment().precipitation_clamped() {
            self.precipitation_told = true;
            self.session.tell_host(reason);
        }
    }

    /// Whether any view this IG draws is a thermal sensor's (the scenario's view, or a host's by
    /// its view type or Sensor Control).
    fn sensor_views_wanted(&self) -> bool {
        let scenario = self
            .scenario
            .view
            .as_ref()
            .and_then(|v| v.sensor.as_deref())
            .and_then(|s| cig_scene::thermal::sensor_of_name(s).ok().flatten())
            .is_some();
        scenario || self.drawn_sensors().iter().any(Option::is_some)
    }

    /// The operator's sensor for every drawn view (the panel's switch), or `None` to give the
    /// views back to the host and the scenario.
    pub fn set_operator_sensor(&mut self, sensor: Option<cig_scene::thermal::SensorView>) {
        self.operator_sensor = sensor;
        if sensor.is_some() {
            self.operator_nvg = None;
        }
    }

    /// The operator's night-vision goggle for every drawn view (the panel's switch), or `None`
    /// to give the views back to the host and the scenario.
    pub fn set_operator_nvg(&mut self, nvg: Option<cig_scene::nvg::NvgView>) {
        self.operator_nvg = nvg;
        if nvg.is_some() {
            self.operator_sensor = None;
        }
    }

    /// Each drawn view's night-vision goggle, in the order of [`IgWorld::drawn_view_ids`]:
    /// the operator's, else the host's (View Definition view type 3 with its Sensor Control,
    /// `crate::thermal::host_nvg`), else the scenario's; none where the view shows a thermal
    /// sensor.
    pub fn drawn_nvg(&self) -> Vec<Option<cig_scene::nvg::NvgView>> {
        // The operator's choice is every drawn view's, whatever the host set.
        if let Some(nvg) = self.operator_nvg {
            return vec![Some(nvg); self.drawn_view_ids().len()];
        }
        let sensors = self.drawn_sensors();
        self.drawn_view_ids()
            .into_iter()
            .enumerate()
            .map(|(index, id)| {
                if sensors.get(index).is_some_and(Option::is_some) {
                    return None;
                }
                match id {
                    Some(id) => {
                        let view_type = self.session.views().get(&id).map_or(0, |v| v.view_type);
                        // A sensor turned on wins over one turned off on the same view.
                        let control = self
                            .session
                            .sensors()
                            .values()
                            .filter(|s| s.view_id == id)
                            .max_by_key(|s| s.on);
                        crate::thermal::host_nvg(view_type, control)
                    }
                    None => self.scenario.nvg_view(),
                }
            })
            .collect()
    }

    /// Finds the surface under each scenario flare (once the terrain query answers there), so a
    /// flare goes out when it reaches the ground.
    fn place_flares(&mut self, query: &mut QuerySession) {
        for (flare, ground) in self.flares.iter_mut().filter(|(_, g)| g.is_none()) {
            if let Ok(h) = query.hot(flare.start.lat_deg, flare.start.lon_deg) {
                *ground = Some(h.height_ellipsoid_m());
            }
        }
    }

    /// Each drawn view's thermal sensor, in the order of [`IgWorld::drawn_view_ids`].
    fn drawn_sensors(&self) -> Vec<Option<cig_scene::thermal::SensorView>> {
        if let Some(sensor) = self.operator_sensor {
            return vec![Some(sensor); self.drawn_view_ids().len()];
        }
        // The operator's goggles take every view from a host's thermal sensor too.
        if self.operator_nvg.is_some() {
            return vec![None; self.drawn_view_ids().len()];
        }
        self.drawn_view_ids()
            .into_iter()
            .map(|id| match id {
                Some(id) => {
                    let view_type = self.session.views().get(&id).map_or(0, |v| v.view_type);
                    let control = self
                        .session
                        .sensors()
                        .values()
                        .find(|s| s.view_id == id && s.on);
                    crate::thermal::host_sensor(view_type, control)
                }
                None => self
                    .scenario
                    .view
                    .as_ref()
                    .and_then(|v| v.sensor.as_deref())
                    .and_then(|name| cig_scene::thermal::sensor_of_name(name).ok().flatten()),
            })
            .collect()
    }

    /// The gates the trackers of the drawn sensor views want read from the frame of `frame_px`
    /// pixels just drawn: (view index in the snapshot, gate `[x, y, width, height]`).
    pub fn track_gates(&mut self, frame_px: [u32; 2]) -> Vec<(usize, crate::tracker::Rect)> {
        let mut out = Vec::new();
        let ids = self.drawn_view_ids();
        let sensors = self.drawn_sensors();
        for (index, id) in ids.iter().enumerate() {
            let (Some(id), Some(Some(_))) = (id, sensors.get(index)) else {
                continue;
            };
            let Some(s) = self
                .session
                .sensors()
                .values()
                .find(|s| s.view_id == *id && s.on && s.track_mode != 0)
            else {
                continue;
            };
            let tracker = self
                .trackers
                .entry((s.view_id, s.sensor_id))
                .or_insert_with(|| crate::tracker::Tracker::new(frame_px));
            out.push((index, tracker.gate(frame_px)));
        }
        // Trackers of sensors no longer tracking are dropped.
        let wanted: BTreeSet<(u16, u8)> = self
            .session
            .sensors()
            .values()
            .filter(|s| s.on && s.track_mode != 0)
            .map(|s| (s.view_id, s.sensor_id))
            .collect();
        self.trackers.retain(|k, _| wanted.contains(k));
        out
    }

    /// Feeds a tracker the band radiance of its gate (`values`, row by row) from view
    /// `view_index` of `snapshot`, and reports what it tracks to the host (the next frame's
    /// Sensor Response): the status, the gate, and the host's entity nearest the target's
    /// direction within the gate, with its position as the track point.
    pub fn feed_track(
        &mut self,
        snapshot: &FrameSnapshot,
        view_index: usize,
        gate: crate::tracker::Rect,
        values: &[f32],
    ) {
        let Some(Some(id)) = self.drawn_view_ids().get(view_index).copied() else {
            return;
        };
        let Some(view) = snapshot.views.get(view_index) else {
            return;
        };
        let Some(s) = self
            .session
            .sensors()
            .values()
            .find(|s| s.view_id == id && s.on && s.track_mode != 0)
            .copied()
        else {
            return;
        };
        let frame_px = [view.width_px, view.height_px];
        let Some(tracker) = self.trackers.get_mut(&(s.view_id, s.sensor_id)) else {
            return;
        };
        tracker.update(gate, values, frame_px, s.track_black);
        // The gate's centre as a direction: tangents across the frustum.
        let [tl, tr, td, tu] = view.fov.tangents();
        let tan_x = -tl + (tl + tr) * tracker.centre_px[0] / f64::from(view.width_px);
        let tan_y = tu - (tu + td) * tracker.centre_px[1] / f64::from(view.height_px);
        let camera = view.camera();
        let ray = (camera.forward + camera.right * tan_x + camera.up * tan_y).normalize();
        // Within the gate's half-width, the nearest host entity in angle.
        let half_gate = f64::from(tracker.gate_px[0]) / 2.0 * (tl + tr) / f64::from(view.width_px);
        let mut best: Option<(f64, u16, Geodetic)> = None;
        if tracker.status == crate::tracker::STATUS_TRACKING
            || tracker.status == crate::tracker::STATUS_IMPENDING_BREAKLOCK
        {
            for e in &snapshot.entities {
                let Ok(entity_id) = u16::try_from(e.id) else {
                    continue;
                };
                let to = e.position.to_ecef() - camera.eye_ecef;
                let angle = to.normalize().angle_between(ray);
                // In front of the sensor and inside the gate.
                if to.dot(ray) > 0.0
                    && angle <= half_gate.atan()
                    && best.is_none_or(|b| angle < b.0)
                {
                    best = Some((angle, entity_id, e.position));
                }
            }
        }
        let report = crate::session::TrackReport {
            status: tracker.status,
            gate_px: tracker.gate_px.map(|g| g.min(u32::from(u16::MAX)) as u16),
            gate_deg: [
                tan_x.atan().to_degrees() as f32,
                tan_y.atan().to_degrees() as f32,
            ],
            entity_id: best.map(|b| b.1),
            point: best.map(|b| b.2),
        };
        self.session.set_track(s.view_id, s.sensor_id, report);
    }

    /// Advances the thermal state (surfaces and the drawn entities' engines) to the world time,
    /// once a sensor view or the scenario's `[thermal]` asks for it.
    fn update_thermal(&mut self, query: &mut QuerySession) {
        if !(self.thermal.is_running()
            || self.scenario.thermal.is_some()
            || self.sensor_views_wanted())
        {
            return;
        }
        // The table's place: the first eye, else the scenario's; none yet, no table (the sun's
        // hours depend on it).
        let Some(place) = self.first_eye.or_else(|| {
            self.scenario
                .view
                .as_ref()
                .and_then(|v| v.eye)
                .map(|e| Geodetic::new(e[0], e[1], e[2]))
        }) else {
            return;
        };
        // The ground under it: the infrared paths count heights from there.
        let ground_m = query
            .hot(place.lat_deg, place.lon_deg)
            .map_or(0.0, |h| h.height_ellipsoid_m());
        let host_air =
            self.session
                .environment()
                .atmosphere
                .as_ref()
                .map(|a| crate::thermal::HostAir {
                    air_temperature_c: f64::from(a.air_temperature_c),
                    humidity_pct: f64::from(a.humidity_pct),
                    wind_mps: f64::from(a.horizontal_wind_speed_mps),
                });
        let cover = self.clouds.iter().map(|l| l.coverage).fold(0.0, f64::max);
        let mut entities = Vec::new();
        for (id, e) in self.session.entities() {
            if e.life != EntityLife::Active {
                continue;
            }
            let Some(pose) = self.session.poses().get(id) else {
                continue;
            };
            let own = self.scenario.entities.iter().find(|s| s.id == *id);
            let appearance = own
                .and_then(|s| s.appearance.as_deref())
                .and_then(crate::scenario::parse_hex_u32);
            let (power, burning, destroyed) =
                appearance.map_or((true, false, false), crate::thermal::appearance_heat);
            entities.push(crate::thermal::ThermalEntity {
                id: u32::from(*id),
                position_ecef_m: pose.position.to_ecef(),
                engine_on: own.and_then(|s| s.engine).unwrap_or(power) && !destroyed,
                burning,
                destroyed,
            });
        }
        if let (Some(x), Some(eye)) = (&self.exercise, self.first_eye) {
            for r in x.remote_entities_near(self.monotonic_s, &[eye.to_ecef()], 50_000.0) {
                let (power, burning, destroyed) = crate::thermal::appearance_heat(r.appearance);
                entities.push(crate::thermal::ThermalEntity {
                    id: remote_instance_id(r.key),
                    position_ecef_m: r.position_ecef_m,
                    engine_on: power && !destroyed,
                    burning,
                    destroyed,
                });
            }
        }
        if let Some(x) = &self.exercise {
            self.thermal.set_impacts(x.recent_impacts());
        }
        let edits = query.cache().edits();
        self.thermal
            .follow_craters(&edits, query, self.unix_time_s());
        // The air's visibility at the eye (the host's weather, else the scenario's).
        let visibility_m =
            self.first_eye
                .map_or(self.scenario.visibility_m.unwrap_or(23_000.0), |eye| {
                    self.session.view_visibility_m(Geodetic::new(
                        eye.lat_deg,
                        eye.lon_deg,
                        eye.alt_m - self.eye_geoid_m,
                    ))
                });
        if let Err(e) = self.thermal.step(
            self.clock.now(),
            Geodetic::new(place.lat_deg, place.lon_deg, ground_m),
            host_air,
            cover,
            visibility_m,
            &entities,
        ) {
            if !self.thermal_told {
                self.thermal_told = true;
                self.session
                    .tell_host(format!("the thermal sensors cannot be drawn: {e}"));
            }
        }
    }

    /// The air the effects drift in: the host's wind, temperature and cloud (CIGI Atmosphere and
    /// Weather Control) at the first eye, with the Pasquill class from wind, sun elevation and
    /// cloud (Turner's key); the effects' defaults where the host set nothing.
    fn update_effects_air(&mut self) {
        let environment = self.session.environment();
        let Some(a) = environment.atmosphere.as_ref() else {
            if let Some(w) = self.operator_wind {
                let mut air = *self.effects.atmosphere();
                air.wind = w;
                if let Err(e) = self.effects.set_atmosphere(air) {
                    tracing::warn!("the operator's wind cannot be used: {e}");
                }
            }
            return;
        };
        let wind = self.operator_wind.unwrap_or(cig_effects::system::Wind {
            speed_mps: f64::from(a.horizontal_wind_speed_mps).clamp(0.0, 100.0),
            from_deg: f64::from(a.wind_direction_deg).rem_euclid(360.0),
        });
        let at = self.first_eye.unwrap_or(Geodetic::new(0.0, 0.0, 0.0));
        // Cloud cover and ceiling from this frame's cloud layers (the operator's, the host's
        // CIGI cloud layers over the eye, or the scenario's; clamped, "no cloud" types left out).
        // The ceiling is the lowest broken or overcast layer (5/8 or more; Turner's key), its
        // base above MSL (the terrain under the eye is not subtracted).
        let (cover, ceiling_m) = self
            .clouds
            .iter()
            .map(|l| {
                let ceiling = if l.coverage >= 0.625 {
                    l.base_m
                } else {
                    10_000.0
                };
                (l.coverage, ceiling)
            })
            .fold((0.0, 10_000.0), |(c, b), (c2, b2)| {
                (f64::max(c, c2), f64::min(b, b2))
            });
        let (_, sun_elevation_deg) = self.sun_az_el_deg(at);
        let temperature_k = f64::from(a.air_temperature_c) + 273.15;
        match cig_effects::system::Atmosphere::from_weather(
            wind,
            if temperature_k.is_finite() {
                temperature_k.clamp(180.0, 340.0)
            } else {
                288.15
            },
            sun_elevation_deg,
            cover,
            ceiling_m.max(0.0),
        )
        .and_then(|air| self.effects.set_atmosphere(air))
        {
            Ok(()) => {}
            Err(e) => self
                .session
                .tell_host(format!("the weather cannot drive the obscurants: {e}")),
        }
    }

    /// Starts an operator's plume (panel or command) at a point on the ground; returns its
    /// number, or why it cannot start.
    pub fn start_operator_plume(
        &mut self,
        position: Geodetic,
        flame: bool,
        heat_release_w: f64,
    ) -> Result<u32, EffectsError> {
        self.operator_plumes_started += 1;
        let number = self.operator_plumes_started;
        let t = effect_time_s(self.clock.now().unix_seconds());
        let handle = self.effects.start_plume(&PlumeSpec {
            id: EffectId(cig_dis::detonation::splitmix64(
                0x4f50_0000_0000 | u64::from(number),
            )),
            kind: if flame {
                PlumeKind::Flame
            } else {
                PlumeKind::Smoke
            },
            position,
            size_m: 5.0,
            source: PlumeSource::HeatReleaseW(heat_release_w),
            start_time_s: t,
            duration_s: 3600.0,
        })?;
        self.operator_plumes.push(handle);
        Ok(number)
    }

    /// Stops every operator plume (their puffs age out).
    pub fn stop_operator_plumes(&mut self) {
        let t = effect_time_s(self.clock.now().unix_seconds());
        for h in self.operator_plumes.drain(..) {
            let _ = self.effects.stop(h, t);
        }
    }

    /// Sets the wind the obscurants drift in (the operator's; it wins over the host's).
    pub fn set_operator_wind(&mut self, speed_mps: f64, from_deg: f64) {
        if speed_mps.is_finite() && from_deg.is_finite() {
            self.operator_wind = Some(cig_effects::system::Wind {
                speed_mps: speed_mps.clamp(0.0, 100.0),
                from_deg: from_deg.rem_euclid(360.0),
            });
            self.last_air_update_s = f64::NEG_INFINITY;
        }
    }

    /// Dust trails behind the ground vehicles this IG moves (its scenario's and its host's),
    /// while they move on the ground faster than 1 m/s; the trail's size comes from the speed
    /// and the soil and road under the vehicle (thesis appendix D, `cig_effects::dust`), so a
    /// vehicle on a paved road or in water raises none. Remote entities raise dust by their
    /// appearance bits instead (§VI.E.3).
    fn run_vehicle_dust(
        &mut self,
        query: &mut QuerySession,
        t_s: f64,
        velocities: &BTreeMap<u16, DVec3>,
    ) {
        let mut moving = Vec::new();
        for (id, e) in self.session.entities() {
            let wants = self
                .scenario
                .entities
                .iter()
                .find(|s| s.id == *id && e.scripted)
                .and_then(|s| s.dust)
                .unwrap_or_else(|| self.session.models().raises_dust(&e.model));
            // An entity whose own appearance asks for dust has that trail already.
            let by_appearance = self.owned_effects.keys().any(|(owner, effect)| {
                *owner == *id && matches!(effect, cig_dis::EntityEffect::DustCloud(_))
            });
            if !wants || by_appearance || e.life != EntityLife::Active {
                continue;
            }
            let Some(pose) = self.session.poses().get(id) else {
                continue;
            };
            let velocity = velocities.get(id).copied().unwrap_or(DVec3::ZERO);
            let on_ground = query.hat(pose.position).is_ok_and(|(hat, _)| hat < 3.0);
            moving.push((
                *id,
                pose.position,
                velocity,
                on_ground && velocity.truncate().length() > 1.0,
            ));
        }
        let kept: std::collections::BTreeSet<u16> =
            moving.iter().filter(|m| m.3).map(|m| m.0).collect();
        for (id, handle) in std::mem::take(&mut self.dust_trails) {
            if kept.contains(&id) {
                self.dust_trails.insert(id, handle);
            } else {
                let _ = self.effects.stop(handle, t_s);
            }
        }
        for (id, position, velocity, raising) in moving {
            if !raising {
                continue;
            }
            let effect = cig_dis::EntityEffect::DustCloud(cig_dis::DustCloudSize::Medium);
            match self.dust_trails.get(&id) {
                Some(h) if self.effects.is_live(*h) => crate::exercise::follow_entity_effect(
                    &mut self.effects,
                    query,
                    effect,
                    *h,
                    position,
                    velocity,
                    t_s,
                ),
                _ => {
                    let seed = 0x4455_5354_0000_0000 | u64::from(id);
                    if let Some(h) = crate::exercise::start_entity_effect(
                        &mut self.effects,
                        query,
                        effect,
                        seed,
                        position,
                        velocity,
                        t_s,
                    ) {
                        self.dust_trails.insert(id, h);
                    }
                }
            }
        }
    }

    /// Ruts behind the ground vehicles this IG moves (its scenario's and its host's), and the
    /// exercise's that fall to it, on the ground (`crate::terrain_edits::RutTracker`), added to the terrain's edits and announced
    /// to the exercise; the soil is wet while it rains or snows.
    fn run_vehicle_ruts(&mut self, query: &mut QuerySession, now_s: f64) {
        let mut vehicles = Vec::new();
        for (id, e) in self.session.entities() {
            if e.life != EntityLife::Active {
                continue;
            }
            let Some(load) = self.session.models().vehicle_load(&e.model) else {
                continue;
            };
            let Some(pose) = self.session.poses().get(id) else {
                continue;
            };
            if query.hat(pose.position).is_ok_and(|(hat, _)| hat < 1.5) {
                vehicles.push(crate::terrain_edits::RutVehicle {
                    id: u64::from(*id),
                    position: pose.position,
                    load,
                });
            }
        }
        // The exercise's ground vehicles whose own nodes lay no ruts, while this IG keeps the
        // exercise's time (`Exercise::remote_rut_vehicles`).
        if let Some(x) = &self.exercise {
            for r in x.remote_rut_vehicles(self.monotonic_s) {
                let model = self.session.models().model_for_dis(&r.entity_type);
                let Some(load) = self.session.models().vehicle_load(model) else {
                    continue;
                };
                if query.hat(r.geodetic).is_ok_and(|(hat, _)| hat < 1.5) {
                    vehicles.push(crate::terrain_edits::RutVehicle {
                        id: crate::terrain_edits::remote_rut_id(
                            r.key.site,
                            r.key.application,
                            r.key.entity,
                        ),
                        position: r.geodetic,
                        load,
                    });
                }
            }
        }
        let author = self.exercise.as_ref().map_or(
            cig_terrain::edits::EditAuthor {
                site: 0,
                application: 1,
            },
            |x| x.address(),
        );
        let moisture = if self.precipitation().is_some_and(|p| p.rate_mm_per_h > 0.5) {
            cig_dynterrain::soil::SoilMoisture::Wet
        } else {
            cig_dynterrain::soil::SoilMoisture::Dry
        };
        let time_s = self.unix_time_s();
        let ruts = self
            .ruts
            .advance(&vehicles, author, time_s, moisture, query);
        if ruts.is_empty() {
            return;
        }
        // One change of the edits a frame, whatever the number of ruts.
        let added: Vec<bool> = query.cache().update_edits(|layer| {
            ruts.iter()
                .map(|rut| {
                    matches!(
                        layer.apply(rut.clone()),
                        Ok(cig_terrain::edits::Applied::Added)
                    )
                })
                .collect()
        });
        if let Some(x) = self.exercise.as_mut() {
            for (rut, added) in ruts.iter().zip(added) {
                if added {
                    x.announce_edit(now_s, rut, query);
                }
            }
        }
    }

    /// The host's Terrain Edit Requests of this frame (cig's user-defined CIGI packet,
    /// `crate::terrain_edits::TerrainEditRequest`): craters made or healed in one change of
    /// the terrain's edits, authored by this IG, problems told to the host, new craters
    /// announced to the exercise. Other user-defined packets are dropped (the session counts
    /// them).
    fn run_host_terrain_edits(&mut self, query: &mut QuerySession, now_s: f64) {
        let packets = self.session.take_user_packets();
        if packets.is_empty() {
            return;
        }
        let author = self
            .exercise
            .as_ref()
            .map_or(crate::terrain_edits::LOCAL_AUTHOR, Exercise::address);
        let time_s = self.unix_time_s();
        let done = self
            .session
            .edit_requests_mut()
            .apply(&packets, author, time_s, query);
        for problem in done.problems {
            self.session.tell_host(problem);
        }
        if let Some(x) = self.exercise.as_mut() {
            for edit in &done.added {
                x.announce_edit(now_s, edit, query);
            }
            for edit in &done.healed {
                x.announce_heal(now_s, edit, query);
            }
        }
    }

    /// The appearance effects of the scenario's own entities (smoke, flames, dust), started,
    /// stopped and moved with them as on every other node that sees them.
    fn run_owned_effects(
        &mut self,
        query: &mut QuerySession,
        t_s: f64,
        velocities: &BTreeMap<u16, DVec3>,
    ) {
        let mut wanted_now = std::collections::BTreeSet::new();
        for e in &self.scenario.entities {
            let Some(appearance) = e
                .appearance
                .as_deref()
                .and_then(crate::scenario::parse_hex_u32)
            else {
                continue;
            };
            // Only an active entity that exists and can be placed smokes.
            let active = self
                .session
                .entities()
                .get(&e.id)
                .is_some_and(|x| x.life == EntityLife::Active);
            let Some(pose) = self.session.poses().get(&e.id).copied().filter(|_| active) else {
                continue;
            };
            let (kind, domain) = e
                .dis_type
                .as_deref()
                .and_then(DisTypePattern::parse)
                .and_then(|p| p.exact())
                .map_or((1, 1), |t| (t.kind, t.domain));
            let wanted =
                cig_dis::EffectsRequested::from_appearance(appearance, kind, domain).active();
            let velocity = velocities.get(&e.id).copied().unwrap_or(DVec3::ZERO);
            let seed = e
                .dis_id
                .as_deref()
                .and_then(crate::scenario::parse_dis_id)
                .map_or(u64::from(e.id), |(s, a, n)| {
                    (u64::from(s) << 32) | (u64::from(a) << 16) | u64::from(n)
                });
            for effect in wanted {
                let key = (e.id, effect);
                wanted_now.insert(key);
                match self.owned_effects.get(&key) {
                    // A live effect follows its entity; one that ran its course starts again.
                    Some(handle) if self.effects.is_live(*handle) => {
                        crate::exercise::follow_entity_effect(
                            &mut self.effects,
                            query,
                            effect,
                            *handle,
                            pose.position,
                            velocity,
                            t_s,
                        );
                    }
                    _ => {
                        self.owned_effects.remove(&key);
                        if let Some(handle) = crate::exercise::start_entity_effect(
                            &mut self.effects,
                            query,
                            effect,
                            seed,
                            pose.position,
                            velocity,
                            t_s,
                        ) {
                            self.owned_effects.insert(key, handle);
                        }
                    }
                }
            }
        }
        // Entities destroyed, hidden or no longer asking for an effect: it stops.
        let gone: Vec<_> = self
            .owned_effects
            .keys()
            .filter(|k| !wanted_now.contains(k))
            .copied()
            .collect();
        for key in gone {
            if let Some(h) = self.owned_effects.remove(&key) {
                let _ = self.effects.stop(h, t_s);
            }
        }
    }

    /// Places the scenario's smoke sources on the terrain and starts their plumes (once).
    fn start_smoke(&mut self, query: &mut QuerySession) {
        let (site, application) = self
            .scenario
            .dis
            .as_ref()
            .map_or((0, 0), |d| (d.site, d.application));
        let start_effect_s = effect_time_s(self.start_unix_s);
        for s in self
            .smoke
            .iter_mut()
            .filter(|s| s.started.is_none() && !s.failed)
        {
            let src = &s.source;
            let ground = match query.hot(src.lat_deg, src.lon_deg) {
                Ok(g) => g,
                Err(e) => {
                    tracing::warn!("smoke source {} cannot be placed: {e}", src.id);
                    s.failed = true;
                    continue;
                }
            };
            let position = Geodetic::new(
                src.lat_deg,
                src.lon_deg,
                ground.height_ellipsoid_m() + src.alt_m,
            );
            let seed = (u64::from(site) << 32) | (u64::from(application) << 16) | u64::from(src.id);
            let spec = PlumeSpec {
                id: EffectId(cig_dis::detonation::splitmix64(seed ^ 0x5052_4f43)),
                kind: if src.kind == "flame" {
                    PlumeKind::Flame
                } else {
                    PlumeKind::Smoke
                },
                position,
                size_m: src.size_m,
                source: PlumeSource::HeatReleaseW(src.heat_release_w),
                start_time_s: start_effect_s + src.start_s,
                duration_s: src.duration_s,
            };
            match self.effects.start_plume(&spec) {
                Ok(handle) => s.started = Some((position, handle)),
                Err(e) => {
                    tracing::warn!("smoke source {} cannot start: {e}", src.id);
                    s.failed = true;
                }
            }
        }
    }

    /// Computes the sea at the world time (before the poses: floating entities need it).
    fn update_sea(&mut self, query: &mut QuerySession) {
        let (lat_deg, lon_deg) = query.cache().database().layout().grid.centre_deg();
        let origin = cig_scene::sea::sea_origin(lat_deg, lon_deg);
        let eye_msl = self
            .first_eye
            .map(|e| Geodetic::new(e.lat_deg, e.lon_deg, e.alt_m - self.eye_geoid_m));
        // The session lets go of last frame's sea so that its surface is reused in place.
        self.session.set_sea(None);
        // Last frame's poses place the host's entity-scoped waves.
        let result = self.sea.update(
            self.session.environment(),
            eye_msl,
            origin,
            self.clock.now().unix_seconds(),
            self.session.poses(),
        );
        match result {
            Ok(told) => {
                for text in told {
                    self.session.tell_host(text);
                }
            }
            Err(e) => self.session.tell_host(e.to_string()),
        }
        self.session.set_sea(self.sea.now().cloned());
    }

    /// Floats the DIS exercise's surface ships that have a hull on the sea.
    fn float_remote_ships(&mut self, query: &mut QuerySession) {
        self.remote_afloat.clear();
        self.wakes.clear();
        let (Some(sea), Some(x)) = (self.session.sea(), &self.exercise) else {
            self.wake_tracks.retain(|key, _| *key < REMOTE_WAKE);
            return;
        };
        let mut tracked = BTreeSet::new();
        // Around the views' eyes and the database (a caller's own view lies near it).
        let (lat_deg, lon_deg) = query.cache().database().layout().grid.centre_deg();
        let centre = Geodetic::new(lat_deg, lon_deg, 0.0);
        let mut eyes: Vec<DVec3> = self
            .world_views(1, 1)
            .iter()
            .map(|v| v.eye.to_ecef())
            .collect();
        eyes.push(centre.to_ecef());
        for r in x.remote_entities_near(self.monotonic_s, &eyes, REMOTE_SHIPS_FLOATED_WITHIN_M) {
            // Surface platforms (DIS domain 3) float; others keep what their owner sends.
            if r.entity_type.kind != 1 || r.entity_type.domain != 3 {
                continue;
            }
            let model = self.session.models().model_for_dis(&r.entity_type);
            if cig_scene::sea::builtin_hull(model).is_none() {
                continue;
            }
            let (lat_deg, lon_deg) = (r.geodetic.lat_deg, r.geodetic.lon_deg);
            let Some(level) = self.session.sea_level_at(query, lat_deg, lon_deg) else {
                continue;
            };
            let [heading_deg, pitch_deg, roll_deg] = r.heading_pitch_roll_deg;
            // The velocity its owner sends: the ship's encounter with the waves, its wake.
            let v = EnuFrame::new(r.geodetic).ecef_vector_to_enu(r.velocity_ecef_mps);
            let pose = sea.float(
                query,
                model,
                Hpr {
                    heading_deg,
                    pitch_deg,
                    roll_deg,
                },
                cig_scene::snapshot::Clamp::HeightAndAttitude,
                [lat_deg, lon_deg, 0.0],
                [v.x, v.y],
                level,
                Some(crate::sea::ShipKey::Remote(remote_instance_id(r.key))),
            );
            // Its wake, from the same velocity, along the track it made.
            let course_deg = v.x.atan2(v.y).to_degrees().rem_euclid(360.0);
            let key = REMOTE_WAKE | u64::from(remote_instance_id(r.key));
            if let Some(wake) =
                cig_scene::sea::WakeDraw::of_ship(model, pose.position, course_deg, v.x.hypot(v.y))
            {
                let track = self.wake_tracks.entry(key).or_default();
                self.wakes.push(track.follow(self.monotonic_s, wake));
                tracked.insert(key);
            }
            self.remote_afloat.insert(remote_instance_id(r.key), pose);
        }
        self.wake_tracks
            .retain(|key, _| *key < REMOTE_WAKE || tracked.contains(key));
    }

    /// The horizontal velocities (east, north, m/s) the scenario's scripts (`scripted`) or the
    /// host's Rate Control give this IG's entities that are ships.
    fn known_ship_velocities(&self, scripted: &BTreeMap<u16, DVec3>) -> BTreeMap<u16, [f64; 2]> {
        self.session
            .entities()
            .iter()
            .filter(|(_, e)| {
                e.life == EntityLife::Active && cig_scene::sea::builtin_hull(&e.model).is_some()
            })
            .filter_map(|(id, e)| {
                let known = scripted
                    .get(id)
                    .map(|v| [v.x, v.y])
                    .or_else(|| host_velocity_enu_mps(e));
                known.map(|v| (*id, v))
            })
            .collect()
    }

    /// This IG's own ships on the sea: their speed and course made good, and their wakes.
    /// The velocity is the scenario script's or the host's Rate Control's where they give
    /// one (from the ship's first frame), else sampled from its places at least
    /// [`SHIP_SPEED_SAMPLE_S`] apart (the ship is taken at rest until the first sample; the
    /// change then rings down through its natural periods, `cig_sea::response::ShipRide`).
    fn track_own_ships(&mut self, query: &mut QuerySession, known: &BTreeMap<u16, [f64; 2]>) {
        if self.session.sea().is_none() {
            self.ship_motion.clear();
            self.wake_tracks.retain(|key, _| *key >= REMOTE_WAKE);
            self.session.set_ship_velocities(BTreeMap::new());
            return;
        }
        let now = self.monotonic_s;
        let mut seen = BTreeSet::new();
        for (id, e) in self.session.entities() {
            if e.life != EntityLife::Active || cig_scene::sea::builtin_hull(&e.model).is_none() {
                continue;
            }
            let Some(pose) = self.session.poses().get(id) else {
                continue;
            };
            let p = pose.position;
            if self
                .session
                .sea_level_at(query, p.lat_deg, p.lon_deg)
                .is_none()
            {
                continue;
            }
            seen.insert(*id);
            let at_rest = MadeGood {
                at_s: now,
                position: p,
                speed_mps: 0.0,
                course_deg: pose.orientation.heading_deg,
            };
            let entry = self.ship_motion.entry(*id).or_insert(at_rest);
            let dt_s = now - entry.at_s;
            if let Some(&velocity) = known.get(id) {
                // The script or the host's rates say it at once.
                *entry = at_rest.moving(velocity);
            } else if dt_s > SHIP_SPEED_STALE_S {
                *entry = at_rest;
            } else if dt_s >= SHIP_SPEED_SAMPLE_S {
                let moved = EnuFrame::new(entry.position).geodetic_to_enu(p) / dt_s;
                *entry = if moved.x.hypot(moved.y) > cig_scene::sea::SHIP_JUMP_MPS {
                    // The host moved it: a new start, not a speed (the wake's track and the
                    // ship's ride start again too).
                    at_rest
                } else {
                    at_rest.moving([moved.x, moved.y])
                };
            }
            if let Some(wake) =
                cig_scene::sea::WakeDraw::of_ship(&e.model, p, entry.course_deg, entry.speed_mps)
            {
                let track = self.wake_tracks.entry(u64::from(*id)).or_default();
                self.wakes.push(track.follow(now, wake));
            }
        }
        self.ship_motion.retain(|id, _| seen.contains(id));
        self.wake_tracks
            .retain(|key, _| *key >= REMOTE_WAKE || seen.contains(&(*key as u16)));
        let velocities = self
            .ship_motion
            .iter()
            .map(|(id, m)| {
                let course = m.course_deg.to_radians();
                (
                    *id,
                    [m.speed_mps * course.sin(), m.speed_mps * course.cos()],
                )
            })
            .collect();
        self.session.set_ship_velocities(velocities);
    }

    /// The sea at the world time, if there is one.
    pub fn sea(&self) -> Option<&std::sync::Arc<crate::sea::SeaNow>> {
        self.session.sea()
    }

    /// The frame's message to the host (Start of Frame and answers).
    pub fn host_message(&mut self, query: &mut QuerySession, timestamp_10us: u32) -> Message {
        self.session
            .end_frame(query, Some(&self.effects), timestamp_10us)
    }

    /// DIS PDUs to send, one datagram each.
    pub fn take_dis_outgoing(&mut self) -> Vec<Vec<u8>> {
        self.exercise
            .as_mut()
            .map(Exercise::take_outgoing)
            .unwrap_or_default()
    }

    /// Moves each host view's drawn area-of-interest point toward the host's (the view's centre
    /// when none is set) by a first-order lag, so a saccade of a tracked eye does not make the
    /// scene's detail flicker.
    fn follow_points_of_interest(&mut self, dt: f64) {
        let k = 1.0 - (-dt / POINT_OF_INTEREST_LAG_S).exp();
        let views = self.session.views();
        self.points_of_interest
            .retain(|id, _| views.contains_key(id));
        for (id, view) in views {
            let target = view.point_of_interest_deg.unwrap_or([0.0, 0.0]);
            let point = self.points_of_interest.entry(*id).or_insert([0.0, 0.0]);
            for (p, t) in point.iter_mut().zip(target) {
                // Within a thousandth of a degree it has arrived (the lag never would).
                *p = if (t - *p).abs() < 1e-3 {
                    t
                } else {
                    *p + (t - *p) * k
                };
            }
        }
    }

    /// The views to draw: the host's, else the scenario's, else `fallback`.
    pub fn views(&self, width_px: u32, height_px: u32, fallback: &View) -> Vec<View> {
        let mut views = self.world_views(width_px, height_px);
        if views.is_empty() {
            views.push(View {
                width_px,
                height_px,
                ..*fallback
            });
        }
        views
    }

    /// The host's views, else the scenario's; empty when neither gives one.
    fn world_views(&self, width_px: u32, height_px: u32) -> Vec<View> {
        let default_fov = FovDeg::from_horizontal(60.0, width_px, height_px);
        let mut views: Vec<View> = self
            .session
            .views()
            .values()
            .filter(|v| self.draws_view(v.id))
            .filter_map(|v| {
                let pose = self.session.view_pose(v)?;
                Some(View {
                    eye: pose.position,
                    orientation: pose.orientation,
                    fov: v.fov.unwrap_or(default_fov),
                    width_px,
                    height_px,
                })
            })
            .collect();
        if views.is_empty() {
            if let Some(v) = &self.scenario.view {
                let relative = Hpr {
                    heading_deg: v.hpr_deg[0],
                    pitch_deg: v.hpr_deg[1],
                    roll_deg: v.hpr_deg[2],
                };
                let offset = BodyOffset {
                    x_m: v.offset_m[0],
                    y_m: v.offset_m[1],
                    z_m: v.offset_m[2],
                };
                let pose = match (v.entity, v.eye) {
                    (Some(id), _) => self
                        .session
                        .poses()
                        .get(&id)
                        .map(|p| child_pose(*p, offset, relative)),
                    // The scenario gives the eye's altitude above MSL.
                    (None, Some(eye)) => Some(Pose {
                        position: Geodetic::new(eye[0], eye[1], eye[2] + self.fixed_eye_geoid_m),
                        orientation: relative,
                    }),
                    _ => None,
                };
                if let Some(pose) = pose {
                    views.push(View {
                        eye: pose.position,
                        orientation: pose.orientation,
                        fov: FovDeg::from_horizontal(v.fov_deg, width_px, height_px),
                        width_px,
                        height_px,
                    });
                }
            }
        }
        views
    }

    /// What the renderer draws this frame.
    pub fn snapshot(&self, width_px: u32, height_px: u32, fallback: &View) -> FrameSnapshot {
        let views = self.views(width_px, height_px, fallback);
        let mut snapshot = FrameSnapshot::new(self.unix_time_s(), views.clone());
        // The host's views are drawn in identifier order, those with a pose (as `world_views`).
        let host_views = self.drawn_view_ids();
        if host_views.len() == views.len() && host_views.iter().all(Option::is_some) {
            snapshot.points_of_interest_deg = host_views
                .iter()
                .flatten()
                .map(|id| {
                    self.points_of_interest
                        .get(id)
                        .copied()
                        .filter(|p| *p != [0.0, 0.0])
                })
                .collect();
        }
        snapshot.sky = self.scenario.sky_settings();
        snapshot.sea = self.session.sea().map(|s| std::sync::Arc::clone(s.draw()));
        if snapshot.sea.is_some() {
            snapshot.wakes.clone_from(&self.wakes);
        }
        snapshot.thermal = self.thermal.scene();
        if snapshot.thermal.is_some() {
            let sensors = self.drawn_sensors();
            if sensors.len() == views.len() {
                snapshot.sensors = sensors;
            }
        }
        let nvg = self.drawn_nvg();
        if nvg.len() == views.len() && nvg.iter().any(Option::is_some) {
            snapshot.nvg = nvg;
        }
        let mut visibility_m = 40_000.0;
        if let Some(first) = views.first() {
            // Weather layers are given above MSL.
            let eye_msl = Geodetic::new(
                first.eye.lat_deg,
                first.eye.lon_deg,
                first.eye.alt_m - self.eye_geoid_m,
            );
            visibility_m = self.session.view_visibility_m(eye_msl);
            // The host's ground fog layer (CIGI weather layer 0), else the scenario's.
            let layer = self
                .session
                .environment()
                .ground_fog_at(eye_msl)
                .or(self.scenario.ground_fog.map(|g| (g.top_m, g.visibility_m)));
            snapshot.ground_fog = layer.map(|(top_msl_m, v)| cig_scene::FogLayer {
                top_m: top_msl_m + self.eye_geoid_m,
                visibility_m: v,
            });
            if let Some(v) = self.scenario.visibility_m {
                if self.session.environment().atmosphere.is_none() {
                    visibility_m = visibility_m.min(v);
                }
            }
            // Rain and snow add their extinction to the air's (Koschmieder), unless the host's
            // precipitation layer states its own visibility, which already applies.
            if let Some(p) = self.precipitation() {
                if !self
                    .session
                    .environment()
                    .precipitation_sets_visibility(eye_msl)
                {
                    visibility_m = p.combined_visibility_m(visibility_m);
                }
                snapshot.precipitation = Some(cig_scene::PrecipitationDraw {
                    precipitation: p,
                    wind_en_mps: self.wind_en_mps(),
                    seed: self.scenario.precipitation.as_ref().map_or(1, |s| s.seed),
                });
            }
            snapshot.fog = Fog::from_visibility(self.fog_mode, visibility_m);
        }
        // The host's moon and star field switches and the star field's intensity.
        if let Some(c) = &self.session.environment().celestial {
            snapshot.moon_visible = c.moon_enable;
            snapshot.stars_visible = c.star_field_enable;
            snapshot.star_intensity =
                (f64::from(c.star_field_intensity_pct) / 100.0).clamp(0.0, 1.0);
        }
        // Cloud bases above MSL become heights above the ellipsoid at the first eye.
        snapshot.cloud_layers = self
            .clouds
            .iter()
            .map(|l| CloudLayer {
                base_m: l.base_m + self.eye_geoid_m,
                ..*l
            })
            .collect();
        // The sky condition counts the layers over the eye (an aircraft above an overcast
        // keeps its sun).
        let eye_msl_m = views
            .first()
            .map_or(f64::NEG_INFINITY, |v| v.eye.alt_m - self.eye_geoid_m);
        let overhead: Vec<CloudLayer> = self
            .clouds
            .iter()
            .filter(|l| l.base_m + l.thickness_m > eye_msl_m)
            .copied()
            .collect();
        snapshot.cloud_cover_fraction = cig_environment::cloud_cover_fraction(&overhead);
        snapshot.cloud_origin = self.cloud_origin.unwrap_or_else(|| {
            views
                .first()
                .map_or(CloudOrigin::default(), |v| CloudOrigin {
                    lat_deg: v.eye.lat_deg.round(),
                    lon_deg: v.eye.lon_deg.round(),
                })
        });
        let now_unix_s = self.unix_time_s();
        snapshot.bolts = self.lightning.draws(now_unix_s);
        if let Some(first) = views.first() {
            snapshot.flash_lux = self.lightning.flash_lux(now_unix_s, first.eye.to_ecef());
        }
        if let Some(first) = views.first() {
            let origin = first.eye.to_ecef();
            self.effects.snapshot(origin, &mut snapshot.puffs);
            snapshot.puff_origin_ecef_m = origin;
        }
        snapshot.lights = self.scenario.light_points();
        for (flare, ground) in &self.flares {
            snapshot.lights.extend(flare.light_at(now_unix_s, *ground));
        }
        self.smoke_fire_lights(now_unix_s, &mut snapshot.lights);
        for (id, e) in self.session.entities() {
            if e.life != EntityLife::Active {
                continue;
            }
            if let Some(pose) = self.session.poses().get(id) {
                let own = self.scenario.entities.iter().find(|s| s.id == *id);
                let burning = own
                    .and_then(|s| s.appearance.as_deref())
                    .and_then(crate::scenario::parse_hex_u32)
                    .is_some_and(|a| crate::thermal::appearance_heat(a).1);
                let switches = e.lights.unwrap_or_else(|| {
                    own.map_or_else(cig_scene::lights::LightSwitches::default, |s| {
                        crate::lights::switches_of_names(&s.lights)
                    })
                });
                let dis_kind_domain = own
                    .and_then(|s| s.dis_type.as_deref())
                    .and_then(DisTypePattern::parse)
                    .and_then(|p| p.exact())
                    .map(|t| (t.kind, t.domain));
                crate::lights::add_entity_lights(
                    &crate::lights::LitEntity {
                        id: u32::from(*id),
                        model: &e.model,
                        dis_kind_domain,
                        switches,
                        burning,
                        position: pose.position,
                        orientation: pose.orientation,
                    },
                    now_unix_s,
                    &mut snapshot.lights,
                );
                snapshot.entities.push(EntityInstance {
                    id: u32::from(*id),
                    model: e.model.clone(),
                    position: pose.position,
                    orientation: pose.orientation,
                    cue_important: self.session.models().is_cue_important(&e.model),
                    critical_radius_m: self.session.models().critical_radius_m(&e.model),
                });
            }
        }
        if let Some(x) = &self.exercise {
            // Entities far beyond the fog are not drawn: no need to convert them.
            let eyes: Vec<DVec3> = views.iter().map(|v| v.eye.to_ecef()).collect();
            let radius_m = (4.0 * visibility_m).clamp(10_000.0, 400_000.0);
            let near = x.remote_entities_near(self.monotonic_s, &eyes, radius_m);
            for r in near {
                let [heading_deg, pitch_deg, roll_deg] = r.heading_pitch_roll_deg;
                let models = self.session.models();
                let model = models.model_for_dis(&r.entity_type);
                let (kind, domain) = (r.entity_type.kind, r.entity_type.domain);
                let id = remote_instance_id(r.key);
                let (position, orientation) = self.remote_afloat.get(&id).map_or(
                    (
                        r.geodetic,
                        Hpr {
                            heading_deg,
                            pitch_deg,
                            roll_deg,
                        },
                    ),
                    |p| (p.position, p.orientation),
                );
                crate::lights::add_entity_lights(
                    &crate::lights::LitEntity {
                        id: remote_instance_id(r.key),
                        model,
                        dis_kind_domain: Some((kind, domain)),
                        switches: crate::lights::switches_of_dis(
                            cig_dis::LightsRequested::from_appearance(r.appearance, kind, domain),
                        ),
                        burning: crate::thermal::appearance_heat(r.appearance).1,
                        position,
                        orientation,
                    },
                    now_unix_s,
                    &mut snapshot.lights,
                );
                snapshot.entities.push(EntityInstance {
                    id,
                    model: model.to_string(),
                    cue_important: models.is_cue_important(model),
                    critical_radius_m: models.critical_radius_m(model),
                    position,
                    orientation,
                });
            }
        }
        snapshot
    }

    /// The fires of the scenario's flame sources while they burn, at their sources.
    fn smoke_fire_lights(&self, now_unix_s: f64, out: &mut Vec<cig_scene::lights::LightPoint>) {
        let since_start_s = now_unix_s - self.start_unix_s;
        for s in &self.smoke {
            let Some((position, _)) = s.started else {
                continue;
            };
            let src = &s.source;
            let burning = src.kind == "flame"
                && since_start_s >= src.start_s
                && since_start_s < src.start_s + src.duration_s;
            if burning {
                out.push(cig_scene::lights::fire_light(
                    position,
                    (src.heat_release_w * 1e-6) as f32,
                    src.size_m as f32,
                    u64::from(src.id),
                    now_unix_s,
                ));
            }
        }
    }

    /// The wind the effects drift in, as (east, north) m/s.
    fn wind_en_mps(&self) -> [f64; 2] {
        let w = self.effects.atmosphere().wind;
        // "From" a direction: the air moves the opposite way.
        let to = (w.from_deg + 180.0).to_radians();
        [w.speed_mps * to.sin(), w.speed_mps * to.cos()]
    }

    /// Azimuth and elevation of the sun at a point now, degrees (for the operator's display).
    pub fn sun_az_el_deg(&self, at: Geodetic) -> (f64, f64) {
        let d = cig_scene::lighting::sun_direction_ecef(self.unix_time_s(), at);
        azimuth_elevation_deg(EnuFrame::new(at).ecef_vector_to_enu(d))
    }
}

/// The scenario's processes as published: source, extent of their puffs, and whether they
/// still emit.
fn smoke_processes(
    smoke: &[SmokeState],
    effects: &EffectSystem,
    now_effect_s: f64,
    start_unix_s: f64,
) -> Vec<OwnedProcess> {
    let puffs = effects.puff_states();
    smoke
        .iter()
        .filter_map(|s| {
            let (position, handle) = s.started?;
            let frame = EnuFrame::new(position);
            let mut extent = [s.source.size_m, s.source.size_m, s.source.size_m];
            for p in puffs.iter().filter(|p| p.effect == handle.slot) {
                let v = frame.ecef_to_enu(DVec3::from_array(p.centre_ecef_m));
                let horizontal = v.truncate().length() + p.sigma_m;
                extent[0] = extent[0].max(horizontal);
                extent[1] = extent[1].max(4.0 * p.sigma_m);
                extent[2] = extent[2].max(v.z + 2.0 * p.sigma_m);
            }
            let begins = effect_time_s(start_unix_s) + s.source.start_s;
            let active = effects.is_live(handle)
                && now_effect_s >= begins
                && now_effect_s < begins + s.source.duration_s;
            Some(OwnedProcess {
                number: s.source.id,
                position,
                extent_m: extent,
                active,
            })
        })
        .collect()
}

/// A stable draw id for a remote entity, above the 16-bit CIGI id space (the renderer keys each
/// entity's level-of-detail hysteresis by it): 31 bits of a hash of its DIS id, top bit set.
fn remote_instance_id(key: cig_dis::EntityKey) -> u32 {
    let packed =
        (u64::from(key.site) << 32) | (u64::from(key.application) << 16) | u64::from(key.entity);
    0x8000_0000 | (cig_dis::detonation::splitmix64(packed) as u32 & 0x7FFF_FFFF)
}
