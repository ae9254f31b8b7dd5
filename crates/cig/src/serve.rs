//! `cig serve`: the image generator driven by a CIGI host and joined to a DIS exercise.
//!
//! Glue only: the world (CIGI session, scenario, DIS exercise, clock, effects) is `cig-ig`'s
//! `IgWorld`; sockets are `cig-net`'s endpoints; frames are `cig-render`'s. Each frame: drain the
//! host's and the exercise's datagrams into the world, step it, send the frame's message
//! (Start of Frame and the answers) and the exercise's PDUs, and draw. Bad datagrams are
//! counted and logged at a limited rate; the loop keeps going.
//!
//! Channels (docs/channels.md): a process draws the host's views `--view` names; the master
//! answers the host, publishes to the exercise and forwards the host's datagrams to its
//! slaves (`--relay`); a slave draws only and never sends a datagram. In synchronous mode
//! (`--sync`) each channel draws one frame per host frame, its world stepped on the host's
//! clock, so every channel draws frame n from the host's frame n; a channel behind applies
//! every queued host message and draws only the newest.

use crate::cli::{ChannelRole, ExposureMode, ServeArgs};
use crate::config::Config;
use crate::render::{parse_size, parse_time, write_png};
use anyhow::{bail, Context};
use cig_cigi::encode_message;
use cig_effects::EffectsConfig;
use cig_environment::UtcTime;
use cig_geo::Geodetic;
use cig_ig::frame_lock::{FrameDrawn, FrameLock, LockEvent};
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_net::{
    parse_delivery, resolve, BindTarget, Delivery, EndpointConfig, RateLimitedLog, UdpEndpoint,
};
use cig_scene::lighting::FogMode;
use cig_scene::{FovDeg, Hpr, View};
use cig_terrain::{QuerySession, TileCache};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Reads and checks a scenario file.
pub fn read_scenario(path: &Path) -> anyhow::Result<Scenario> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the scenario {}", path.display()))?;
    Scenario::from_toml(&text).with_context(|| format!("scenario {}", path.display()))
}

/// glTF models the scenario's table names, loaded relative to the scenario's folder.
fn scenario_models(
    scenario: &Scenario,
    scenario_path: Option<&Path>,
) -> anyhow::Result<Vec<cig_scene::models::Model>> {
    let base = scenario_path
        .and_then(Path::parent)
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let table = cig_ig::ModelTable::from_scenario(scenario);
    table
        .gltf_files()
        .iter()
        .map(|(name, path)| {
            let full = base.join(path);
            cig_render::load_gltf_model(&full, name)
                .with_context(|| format!("model {name:?} of the scenario"))
        })
        .collect()
}

/// The database's geographic box, widened by `margin_deg`.
fn database_area(cache: &TileCache, margin_deg: f64) -> cig_effects::system::ServedArea {
    let g = cache.database().manifest().layout.grid;
    cig_effects::system::ServedArea {
        south_deg: g.south_lat_deg - margin_deg,
        north_deg: g.north_lat_deg() + margin_deg,
        west_deg: g.west_lon_deg - margin_deg,
        east_deg: g.east_lon_deg() + margin_deg,
    }
}

/// How the frames are shown.
enum Output {
    None,
    Offscreen {
        renderer: Box<cig_render::Renderer>,
        out_dir: Option<PathBuf>,
    },
}

/// Totals of a run, printed at the end.
#[derive(Default)]
struct Totals {
    frames: u64,
    cigi_datagrams: u64,
    cigi_bad: u64,
    dis_datagrams: u64,
    messages_sent: u64,
    overframes: u64,
    frame_ms_sum: f64,
    frame_ms_max: f64,
    /// Problems noted on the sockets (bad datagrams, failed sends) and warning lines logged.
    problems_noted: u64,
    warnings_logged: u64,
    /// Entities and obscurant puffs in the last frame drawn.
    entities_drawn: u32,
    puffs_drawn: u32,
    /// Light points in the last frame's snapshot (entity lamps, fires, flares, the scenario's
    /// lamps), and the most in any frame.
    lights: usize,
    lights_max: usize,
    /// Synchronous mode: host frames applied without being drawn (the channel was behind),
    /// the most in one frame, and the latency from a host frame's arrival to its frame drawn.
    host_frames_skipped: u64,
    lag_frames_max: u64,
    latency_ms_sum: f64,
    latency_ms_max: f64,
    /// The host frame number the last frame drew.
    drawn_host_frame: Option<u32>,
    /// From the start of serving to the first frame drawn from the host's data, ms.
    joined_after_ms: Option<f64>,
    /// Host datagrams forwarded to slave channels.
    relayed: u64,
}

pub fn run(args: &ServeArgs, config: &Config) -> anyhow::Result<()> {
    let (width_px, height_px) = parse_size(&args.size)?;
    if !(args.rate_hz.is_finite() && (1.0..=1000.0).contains(&args.rate_hz)) {
        bail!("--rate-hz {} must lie between 1 and 1000", args.rate_hz);
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    if args.out_dir.is_some() && !args.headless {
        bail!("--out-dir needs --headless (a window shows the frames otherwise)");
    }
    if args.json && !args.headless && !args.no_render {
        bail!("--json needs --headless or --no-render (a window's run ends with a summary line)");
    }
    if args.frame_log.is_some() && !args.headless && !args.no_render {
        bail!("--frame-log needs --headless or --no-render (a window paces its own frames)");
    }
    let channel = Channel::from_args(args)?;
    let correction =
        crate::display::read_display_correction(args.warp.as_deref(), args.blend.as_deref())?;
    if !correction.is_none() && args.no_render {
        bail!("--warp and --blend correct drawn frames (not with --no-render)");
    }
    let scenario = match &args.scenario {
        Some(path) => read_scenario(path)?,
        None => Scenario::from_toml("").context("the empty scenario")?,
    };
    let start = match (&args.time, scenario.start()) {
        (Some(t), _) => parse_time(t).and_then(|s| {
            UtcTime::from_unix_seconds(s).map_err(|e| anyhow::anyhow!("--time: {e}"))
        })?,
        (None, Some(t)) => t,
        (None, None) => UtcTime::from_unix_seconds(
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
        )
        .context("the system clock")?,
    };
    let fog_mode = scenario.fog_mode().unwrap_or(FogMode::Exponential);
    let cigi_bind: BindTarget = args.cigi_bind.parse().context("--cigi-bind")?;
    let host = args
        .cigi_host
        .as_deref()
        .map(|h| resolve(h, "--cigi-host"))
        .transpose()?;
    let models = scenario_models(&scenario, args.scenario.as_deref())?;
    let cache = crate::dynterrain::open_cache(&args.db, &config.paging)?;
    let mut query = QuerySession::new(Arc::clone(&cache));
    let mut journal = args
        .edits
        .as_deref()
        .map(|path| crate::dynterrain::EditJournal::open(path, &cache))
        .transpose()?;

    let mut dis_settings = scenario.dis.clone();
    if let Some(port) = args.dis_port {
        let settings = dis_settings.get_or_insert_with(Default::default);
        settings.port = port;
    }
    if let Some(bind) = &args.dis_bind {
        if let Some(settings) = dis_settings.as_mut() {
            settings.bind = bind.clone();
        }
    }
    let mut scenario = scenario;
    scenario.dis = dis_settings.clone();
    let dis = match &dis_settings {
        Some(settings) => {
            let (delivery, destination) =
                parse_delivery(&settings.delivery, settings.port).context("the DIS delivery")?;
            let bind: BindTarget = settings.bind.parse().context("the DIS bind target")?;
            Some(UdpEndpoint::open(EndpointConfig {
                label: "DIS",
                bind,
                port: settings.port,
                delivery,
                destination,
                queue_limit: 8192,
                reuse_port: true,
            })?)
        }
        None => None,
    };
    let cigi = UdpEndpoint::open(EndpointConfig {
        label: "CIGI",
        bind: cigi_bind,
        port: args.cigi_port,
        delivery: Delivery::Unicast,
        destination: host,
        queue_limit: 256,
        reuse_port: false,
    })
    .with_context(|| match channel.role {
        ChannelRole::Master => format!(
            "one master per host port: another channel of this IG runs as --role slave on a \
             --cigi-port of its own, fed by the master's --relay (port {})",
            args.cigi_port
        ),
        ChannelRole::Slave => format!("the slave's --cigi-port {}", args.cigi_port),
    })?;
    let lock = FrameLockSide::open(args, &channel)?;
    let mut world = IgWorld::new(
        scenario,
        WorldConfig {
            session: SessionConfig {
                database_number: args.database_number,
                answers_host: channel.role == ChannelRole::Master,
                ..SessionConfig::default()
            },
            start,
            fog_mode,
            // Effects are served over the database (a 0.05° margin round it); one started
            // further out is refused with a message.
            effects: EffectsConfig {
                area: Some(database_area(&cache, 0.05)),
                ..EffectsConfig::default()
            },
            join_exercise: dis.is_some(),
        },
    )?;
    world.set_channel_views(channel.views.clone());
    let eye = crate::view::default_eye(&cache);
    let fallback = View {
        eye,
        orientation: Hpr {
            heading_deg: 0.0,
            pitch_deg: -10.0,
            roll_deg: 0.0,
        },
        fov: FovDeg::from_horizontal(60.0, width_px, height_px),
        width_px,
        height_px,
    };
    cache.update(&[eye]);
    cache.wait_idle();
    tracing::info!(
        "serving {} on CIGI {}{}",
        args.db.display(),
        cigi.local_addr(),
        dis.as_ref()
            .map(|d| format!(", DIS {}", d.local_addr()))
            .unwrap_or_default()
    );

    if !args.headless && !args.no_render {
        return run_windowed(
            args,
            (channel, lock),
            cache,
            world,
            query,
            cigi,
            dis,
            fallback,
            (models, correction),
            config.overload()?,
        );
    }
    let mut output = if args.no_render {
        Output::None
    } else {
        let gpu = cig_render::Gpu::headless()?;
        let mut renderer = cig_render::Renderer::new(gpu, &cache, cig_render::FRAME_FORMAT);
        config.configure_renderer(&mut renderer)?;
        renderer.set_display_correction(Some(correction));
        if !models.is_empty() {
            renderer.set_models(models);
        }
        if let Some(dir) = &args.out_dir {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        Output::Offscreen {
            renderer: Box::new(renderer),
            out_dir: args.out_dir.clone(),
        }
    };
    let adaptation = channel.adaptation(1.0 / args.rate_hz as f32);
    let mut loop_state = LoopState::new(args.rate_hz, !args.no_render, channel, lock);
    let mut frame_log = args
        .frame_log
        .as_deref()
        .map(FrameLog::create)
        .transpose()?;
    let mut totals = Totals::default();
    // Since the last host frame drawn, or the loop's start.
    let mut idle_since = Instant::now();
    loop {
        if args.frames.is_some_and(|n| totals.frames >= n) {
            break;
        }
        if let Some(limit_s) = args.idle_exit_s {
            if idle_since.elapsed().as_secs_f64() > limit_s {
                tracing::info!("no host frame for {limit_s} s: stopping");
                break;
            }
        }
        let began = Instant::now();
        let Some(snapshot) = loop_state.tick(
            &mut world,
            &mut query,
            &cigi,
            dis.as_ref(),
            &mut totals,
            (width_px, height_px, &fallback),
        ) else {
            // Synchronous mode and no host frame within a period: nothing new to draw.
            continue;
        };
        if let Some(j) = journal.as_mut() {
            // A disk that fails does not stop the IG: the edits stay in memory, and the journal
            // is dropped with one message.
            if let Err(e) = j.record(&cache) {
                tracing::error!("terrain edits journal stopped: {e:#}");
                journal = None;
            }
        }
        totals.lights = snapshot.lights.len();
        totals.lights_max = totals.lights_max.max(totals.lights);
        if let Output::Offscreen { renderer, out_dir } = &mut output {
            let eyes: Vec<Geodetic> = snapshot.views.iter().map(|v| v.eye).collect();
            cache.update(&eyes);
            // Sensor views' trackers read their gates from the frames drawn.
            let gates = world.track_gates([width_px, height_px]);
            for index in 0..snapshot.views.len() {
                let (image, stats) = cig_render::render_image_with(
                    renderer,
                    &cache,
                    &snapshot,
                    index,
                    cig_render::FrameOptions {
                        adaptation,
                        ..cig_render::FrameOptions::default()
                    },
                )?;
                for (_, gate) in gates.iter().filter(|g| g.0 == index) {
                    let values = renderer.read_scene_region(*gate)?;
                    world.feed_track(&snapshot, index, *gate, &values);
                }
                totals.entities_drawn = stats.entities_drawn;
                totals.puffs_drawn = stats.puffs_drawn;
                if let Some(dir) = out_dir {
                    // In synchronous mode frames are named by the host frame they draw, so the
                    // channels' files of one frame have the same number.
                    let number = match (loop_state.channel.sync, totals.drawn_host_frame) {
                        (true, Some(n)) => u64::from(n),
                        _ => totals.frames,
                    };
                    let name = match (snapshot.views.len(), loop_state.view_ids.get(index)) {
                        (1, _) => format!("frame_{number:05}.png"),
                        (_, Some(Some(id))) => format!("frame_{number:05}_view{id}.png"),
                        _ => format!("frame_{number:05}_view{index}.png"),
                    };
                    write_png(&image, &dir.join(name))?;
                }
            }
        }
        // The frame is done: its time for the log, before the frame lock's report (which lets
        // the master go on).
        let drawn_unix_s = unix_now_s();
        loop_state.frame_drawn(&mut totals);
        if loop_state.host_frames_in_tick > 0 {
            idle_since = Instant::now();
        }
        // The frame's cost: from the end of the wait for the host's frame (synchronous mode)
        // to the frame drawn.
        let frame_ms = loop_state.work_began.elapsed().as_secs_f64() * 1000.0;
        if let Some(log) = &mut frame_log {
            log.write(&FrameLogLine {
                unix_s: drawn_unix_s,
                frame: totals.frames,
                host_frame: totals.drawn_host_frame,
                host_frames_applied: loop_state.host_frames_in_tick,
                frame_ms,
            })?;
        }
        totals.frames += 1;
        totals.frame_ms_sum += frame_ms;
        totals.frame_ms_max = totals.frame_ms_max.max(frame_ms);
        let period = Duration::from_secs_f64(1.0 / args.rate_hz);
        match period.checked_sub(began.elapsed()) {
            // In synchronous mode the host's next frame paces the loop.
            Some(rest) if !loop_state.channel.sync => std::thread::sleep(rest),
            Some(_) => {}
            None => {
                totals.overframes += 1;
                loop_state.overframing = true;
            }
        }
    }
    report(
        &totals,
        &world,
        &cigi,
        dis.as_ref(),
        (&loop_state.channel, loop_state.lock.as_ref()),
        args.json,
    )
}

/// What this process is among the channels of one IG.
#[derive(Clone, Debug)]
struct Channel {
    role: ChannelRole,
    /// The host's views drawn here (`None`: all).
    views: Option<std::collections::BTreeSet<u16>>,
    relay: Vec<SocketAddr>,
    sync: bool,
    exposure: ExposureMode,
}

impl Channel {
    fn from_args(args: &ServeArgs) -> anyhow::Result<Channel> {
        let mut views = std::collections::BTreeSet::new();
        for id in &args.views {
            if !views.insert(*id) {
                bail!("--view {id} is given twice");
            }
        }
        if args.role == ChannelRole::Slave {
            if !args.relay.is_empty() {
                bail!("--relay is the master's (a slave forwards nothing)");
            }
            if args.cigi_host.is_some() {
                bail!("--cigi-host: a slave never sends to the host");
            }
        }
        let relay = args
            .relay
            .iter()
            .map(|r| resolve(r, "--relay"))
            .collect::<Result<Vec<_>, _>>()?;
        if (args.lock_port.is_some() || args.lock.is_some()) && !args.sync {
            bail!("--lock-port and --lock need --sync (the frame lock is synchronous mode's)");
        }
        if args.lock_port.is_some() && args.role == ChannelRole::Slave {
            bail!("--lock-port is the master's (a slave reports to it with --lock)");
        }
        if args.lock.is_some() && args.role == ChannelRole::Master {
            bail!("--lock is a slave's (the master takes the reports on --lock-port)");
        }
        if !(1..=60_000).contains(&args.lock_timeout_ms) {
            bail!(
                "--lock-timeout-ms {} must lie between 1 and 60000",
                args.lock_timeout_ms
            );
        }
        let exposure =
            args.exposure
                .unwrap_or(if !views.is_empty() || args.role == ChannelRole::Slave {
                    ExposureMode::Natural
                } else {
                    ExposureMode::View
                });
        Ok(Channel {
            role: args.role,
            views: (!views.is_empty()).then_some(views),
            relay,
            sync: args.sync,
            exposure,
        })
    }

    /// The renderer's adaptation for frames `frame_s` apart.
    fn adaptation(&self, frame_s: f32) -> cig_render::Adaptation {
        match self.exposure {
            // The eye adapts over the frame period.
            ExposureMode::View => cig_render::Adaptation::Step(frame_s),
            ExposureMode::Natural => cig_render::Adaptation::Off,
        }
    }

    fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "role": match self.role { ChannelRole::Master => "master", ChannelRole::Slave => "slave" },
            "views": self.views.as_ref().map(|v| v.iter().copied().collect::<Vec<_>>()),
            "sync": self.sync,
            "relay": self.relay.iter().map(ToString::to_string).collect::<Vec<_>>(),
            "exposure": match self.exposure { ExposureMode::View => "view", ExposureMode::Natural => "natural" },
        })
    }
}

/// Per-frame work shared by the headless and windowed loops.
struct LoopState {
    started: Instant,
    last: Instant,
    bad_cigi: RateLimitedLog,
    inbox: Vec<cig_net::Datagram>,
    reply_to: Option<SocketAddr>,
    overframing: bool,
    period_s: f64,
    /// The frame's encoded message, its allocation kept from frame to frame.
    outgoing: Vec<u8>,
    /// Views whose eye is below the terrain (warned once until it comes back above).
    below_terrain: std::collections::BTreeSet<usize>,
    /// Whether the snapshots are drawn (eyes inside the terrain are lifted only for drawing).
    drawn: bool,
    channel: Channel,
    /// The host's view identifiers of the last snapshot's views.
    view_ids: Vec<Option<u16>>,
    /// The arrival of the oldest host datagram the frame being drawn applies.
    frame_data_arrived: Option<Instant>,
    /// The channel views the host has not defined, as last warned.
    warned_missing: Vec<u16>,
    /// Host frames (IG Control packets) the last tick applied.
    host_frames_in_tick: u64,
    /// When the last tick's work began (after the wait for the host's frame in synchronous
    /// mode).
    work_began: Instant,
    /// The frame lock: a master's wait for its slaves, or a slave's reports.
    lock: Option<FrameLockSide>,
}

impl LoopState {
    fn new(rate_hz: f64, drawn: bool, channel: Channel, lock: Option<FrameLockSide>) -> LoopState {
        let now = Instant::now();
        LoopState {
            started: now,
            last: now,
            bad_cigi: RateLimitedLog::new("CIGI"),
            inbox: Vec::new(),
            reply_to: None,
            overframing: false,
            period_s: 1.0 / rate_hz,
            outgoing: Vec::with_capacity(4096),
            below_terrain: std::collections::BTreeSet::new(),
            drawn,
            channel,
            view_ids: Vec::new(),
            frame_data_arrived: None,
            warned_missing: Vec::new(),
            host_frames_in_tick: 0,
            work_began: now,
            lock,
        }
    }

    /// Starts the frame clock now.
    fn start_clock(&mut self) {
        let now = Instant::now();
        self.started = now;
        self.last = now;
    }

    /// Notes a frame drawn: in synchronous mode, its latency from the host's data.
    fn frame_drawn(&mut self, totals: &mut Totals) {
        match (&mut self.lock, totals.drawn_host_frame) {
            (Some(FrameLockSide::Slave(slave)), Some(host_frame)) => {
                slave.frame_drawn(host_frame);
            }
            (Some(FrameLockSide::Master(master)), Some(_)) => master.frame_done(),
            _ => {}
        }
        if let Some(arrived) = self.frame_data_arrived.take() {
            let ms = arrived.elapsed().as_secs_f64() * 1000.0;
            totals.latency_ms_sum += ms;
            totals.latency_ms_max = totals.latency_ms_max.max(ms);
        }
        if totals.joined_after_ms.is_none() && totals.drawn_host_frame.is_some() {
            let ms = self.started.elapsed().as_secs_f64() * 1000.0;
            totals.joined_after_ms = Some(ms);
            tracing::info!("drawing the host's frames {ms:.0} ms after starting");
        }
    }

    /// One frame of the world; returns what to draw (in synchronous mode `None` when no host
    /// frame came within a frame period: nothing new to draw).
    fn tick(
        &mut self,
        world: &mut IgWorld,
        query: &mut QuerySession,
        cigi: &UdpEndpoint,
        dis: Option<&UdpEndpoint>,
        totals: &mut Totals,
        (width_px, height_px, fallback): (u32, u32, &View),
    ) -> Option<cig_scene::FrameSnapshot> {
        self.inbox.clear();
        match &mut self.lock {
            // No frame starts (and no Start of Frame lets the host go on) while a slave still
            // draws an older one.
            Some(FrameLockSide::Master(master)) => master.wait_for_slaves(totals.drawn_host_frame),
            // A window's last frame has been shown by now.
            Some(FrameLockSide::Slave(slave)) => slave.frame_starts(),
            None => {}
        }
        if self.channel.sync {
            // The host's next frame paces the channel.
            let period = Duration::from_secs_f64(self.period_s);
            if let Some(d) = cigi.recv_timeout(period) {
                self.inbox.push(d);
            }
        }
        cigi.drain(&mut self.inbox);
        let now = Instant::now();
        self.work_began = now;
        let dt_s = (now - self.last).as_secs_f64();
        self.overframing |= dt_s > self.period_s * 1.5;
        let mut host_frames = 0u64;
        for d in &self.inbox {
            totals.cigi_datagrams += 1;
            for to in &self.channel.relay {
                match cigi.send_to(&d.bytes, *to) {
                    Ok(()) => totals.relayed += 1,
                    Err(e) => {
                        self.bad_cigi.note(now, "relay", &format!("{to}: {e}"));
                    }
                }
            }
            let frames_before = world.session().counters().host_frames;
            match world.receive_cigi(&d.bytes) {
                Ok(()) => self.reply_to = Some(d.from),
                Err(e) => {
                    totals.cigi_bad += 1;
                    self.bad_cigi.note(now, &d.from.to_string(), &e.to_string());
                }
            }
            if world.session().counters().host_frames > frames_before {
                host_frames += 1;
                self.frame_data_arrived.get_or_insert(d.received);
            }
        }
        self.host_frames_in_tick = host_frames;
        if self.channel.sync && host_frames == 0 {
            if self.channel.role == ChannelRole::Master && dt_s >= self.period_s {
                // No host frame: the master still tells the host it runs (Start of Frame), as
                // a synchronous host waits for it.
                self.last = now;
                self.send_frame_message(world, query, cigi, totals, now);
            }
            return None;
        }
        self.last = now;
        if host_frames > 1 {
            totals.host_frames_skipped += host_frames - 1;
            totals.lag_frames_max = totals.lag_frames_max.max(host_frames - 1);
        }
        if host_frames > 0 {
            totals.drawn_host_frame = Some(world.session().last_host_frame_number());
        }
        if let Some(dis) = dis {
            self.inbox.clear();
            dis.drain(&mut self.inbox);
            for d in &self.inbox {
                totals.dis_datagrams += 1;
                world.receive_dis(&d.bytes, query);
            }
        }
        if self.channel.sync {
            world.step_to_host_clock(self.period_s, query);
        } else {
            world.step(dt_s, query);
        }
        self.send_frame_message(world, query, cigi, totals, now);
        if let Some(dis) = dis {
            let outgoing = world.take_dis_outgoing();
            // A slave publishes nothing: the master speaks for the IG.
            if self.channel.role == ChannelRole::Master {
                for pdu in outgoing {
                    if let Err(e) = dis.send(&pdu) {
                        self.bad_cigi.note(now, "DIS send", &e.to_string());
                    }
                }
            }
        }
        let missing = world.channel_views_missing();
        if missing != self.warned_missing {
            if !missing.is_empty() && !world.session().views().is_empty() {
                let defined: Vec<String> = world
                    .session()
                    .views()
                    .keys()
                    .map(ToString::to_string)
                    .collect();
                tracing::warn!(
                    "the host defines no view {} (its views: {}): drawing the default view",
                    missing
                        .iter()
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join(", "),
                    defined.join(", ")
                );
                self.warned_missing = missing;
            } else if missing.is_empty() {
                self.warned_missing = missing;
            }
        }
        totals.problems_noted = self.bad_cigi.count();
        totals.warnings_logged = self.bad_cigi.lines_logged();
        let mut snapshot = world.snapshot(width_px, height_px, fallback);
        self.view_ids = world.drawn_view_ids();
        if !self.drawn {
            return Some(snapshot);
        }
        // An eye inside the terrain is drawn from its surface, with one warning.
        let lifted = cig_scene::lift_eyes_above_terrain(query, &mut snapshot.views);
        for below in &lifted {
            if self.below_terrain.insert(below.view) {
                tracing::warn!("{below}");
            }
        }
        self.below_terrain
            .retain(|view| lifted.iter().any(|b| b.view == *view));
        Some(snapshot)
    }

    /// Ends the IG's frame with the host: Start of Frame and the answers (a master's; a slave
    /// sends nothing, and its session answers nothing).
    fn send_frame_message(
        &mut self,
        world: &mut IgWorld,
        query: &mut QuerySession,
        cigi: &UdpEndpoint,
        totals: &mut Totals,
        now: Instant,
    ) {
        let ticks = ((now - self.started).as_micros() / 10) as u32;
        let mut message = world.host_message(query, ticks);
        if self.channel.role == ChannelRole::Slave {
            return;
        }
        if let Some(cig_cigi::Packet::StartOfFrame(sof)) = message.packets.first_mut() {
            sof.overframing = std::mem::take(&mut self.overframing);
        }
        let bytes = &mut self.outgoing;
        bytes.clear();
        match encode_message(&message, bytes) {
            Ok(()) => {
                let sent = match (cigi.destination(), self.reply_to) {
                    (Some(_), _) => Some(cigi.send(bytes)),
                    (None, Some(to)) => Some(cigi.send_to(bytes, to)),
                    // No host yet: nobody to tell.
                    (None, None) => None,
                };
                match sent {
                    None => {}
                    Some(Ok(())) => totals.messages_sent += 1,
                    Some(Err(e)) => {
                        self.bad_cigi.note(now, "send", &e.to_string());
                    }
                }
            }
            Err(e) => tracing::error!("CIGI: the frame's message cannot be encoded: {e}"),
        }
    }
}

#[allow(
    clippy::too_many_arguments,
    reason = "hands the whole serving state to the window's loop"
)]
fn run_windowed(
    args: &ServeArgs,
    (channel, lock): (Channel, Option<FrameLockSide>),
    cache: Arc<TileCache>,
    mut world: IgWorld,
    mut query: QuerySession,
    cigi: UdpEndpoint,
    dis: Option<UdpEndpoint>,
    fallback: View,
    (models, correction): (
        Vec<cig_scene::models::Model>,
        cig_scene::display::DisplayCorrection,
    ),
    overload: Option<cig_scene::overload::OverloadSettings>,
) -> anyhow::Result<()> {
    let mut options = cig_render::ViewerOptions::new(fallback.eye, fallback.orientation);
    options.overload = overload;
    options.title = format!("cig serve: {}", args.db.display());
    options.width_px = fallback.width_px;
    options.height_px = fallback.height_px;
    options.exit_after_frames = args.frames;
    options.models = models;
    options.natural_exposure = channel.exposure == ExposureMode::Natural;
    options.display_correction = Some(correction);
    let shared = Arc::new(std::sync::Mutex::new(Totals::default()));
    let totals = Arc::clone(&shared);
    // Its clock starts at the first frame, so the window's opening is not a late frame.
    let mut loop_state = LoopState::new(args.rate_hz, true, channel, lock);
    let mut clock_started = false;
    let dis_out = dis.as_ref().map(UdpEndpoint::local_addr);
    let mut operator_strikes: u64 = 0;
    // In synchronous mode a frame without a new host frame shows the last one again.
    let mut last_snapshot: Option<cig_scene::FrameSnapshot> = None;
    let driver: cig_render::FrameDriver = Box::new(move |tick: &cig_render::ViewerTick| {
        let (width_px, height_px) = (tick.width_px, tick.height_px);
        // The trackers see the frame the window drew last.
        if let Some(last) = &last_snapshot {
            for (index, gate, values) in &tick.track_patches {
                world.feed_track(last, *index, *gate, values);
            }
        }
        for order in &tick.orders {
            match *order {
                cig_render::ObscurantOrder::StartPlume {
                    at,
                    flame,
                    heat_release_w,
                } => {
                    if let Err(e) = world.start_operator_plume(at, flame, heat_release_w) {
                        tracing::warn!("the operator's plume cannot start: {e}");
                    }
                }
                cig_render::ObscurantOrder::StopPlumes => world.stop_operator_plumes(),
                cig_render::ObscurantOrder::SetWind {
                    speed_mps,
                    from_deg,
                } => world.set_operator_wind(speed_mps, from_deg),
                cig_render::ObscurantOrder::SetPrecipitation(p) => {
                    world.set_operator_precipitation(p);
                }
                cig_render::ObscurantOrder::StrikeLightning { at } => {
                    operator_strikes += 1;
                    world.strike_lightning_now(at, 0x4f50_4c47_0000_0000 | operator_strikes);
                }
                cig_render::ObscurantOrder::SetStorm {
                    centre,
                    strikes_per_minute,
                } => world.set_lightning_storm((strikes_per_minute > 0.0).then_some(
                    cig_ig::weather::LightningStorm {
                        centre_lat_deg: centre.lat_deg,
                        centre_lon_deg: centre.lon_deg,
                        radius_m: 10_000.0,
                        cloud_base_m: 1500.0,
                        strikes_per_minute:
                            strikes_per_minute.min(cig_ig::weather::MAX_STRIKES_PER_MINUTE),
                        seed: operator_strikes ^ 0x5354_4f52_4d00_0000,
                    },
                )),
                cig_render::ObscurantOrder::SetClouds(layer) => {
                    if let Err(e) = world.set_operator_clouds(layer.map(|l| vec![l])) {
                        tracing::warn!("the operator's cloud layer is refused: {e}");
                    }
                }
                cig_render::ObscurantOrder::SetSensor(sensor) => world.set_operator_sensor(sensor),
                cig_render::ObscurantOrder::SetNvg(nvg) => world.set_operator_nvg(nvg),
            }
        }
        let mut t = totals
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if !clock_started {
            clock_started = true;
            loop_state.start_clock();
        }
        let state = &mut loop_state;
        let snapshot = state.tick(
            &mut world,
            &mut query,
            &cigi,
            dis.as_ref(),
            &mut t,
            (width_px, height_px, &fallback),
        );
        match snapshot {
            Some(mut snapshot) => {
                state.frame_drawn(&mut t);
                t.frames += 1;
                snapshot.track_gates = world.track_gates([width_px, height_px]);
                last_snapshot = Some(snapshot.clone());
                snapshot
            }
            None => last_snapshot.clone().unwrap_or_else(|| {
                cig_scene::FrameSnapshot::new(world.unix_time_s(), vec![fallback])
            }),
        }
    });
    let report = match cig_render::run_viewer_driven(cache, options, Some(driver)) {
        Ok(report) => report,
        Err(cig_render::ViewerError::NoDisplay(reason)) => {
            bail!("cig serve needs a display unless --headless is given ({reason})")
        }
        Err(e) => return Err(e.into()),
    };
    let t = shared
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    eprintln!(
        "served {} frames in a window ({}), {} host datagrams ({} bad){}",
        report.frames,
        report.adapter,
        t.cigi_datagrams,
        t.cigi_bad,
        dis_out.map(|a| format!(", DIS on {a}")).unwrap_or_default()
    );
    Ok(())
}

/// This channel's side of the frame lock (`cig_ig::frame_lock`).
enum FrameLockSide {
    Master(Box<LockMaster>),
    Slave(LockSlave),
}

/// The master's: the slaves' reports and the wait for them.
struct LockMaster {
    endpoint: UdpEndpoint,
    lock: FrameLock,
    timeout: Duration,
    inbox: Vec<cig_net::Datagram>,
    bad: RateLimitedLog,
    /// Slaves taken out of the lock, logged at a limited rate.
    drops: RateLimitedLog,
    waits: u64,
    wait_ms_sum: f64,
    wait_ms_max: f64,
    timeouts: u64,
    /// The master's frames: when the last was done, and the smoothed time between them.
    last_frame_done: Option<Instant>,
    frame_interval_s: Option<f64>,
}

/// A slave's: one report a frame drawn.
struct LockSlave {
    endpoint: UdpEndpoint,
    channel: u32,
    sent: u64,
    failures: u64,
    /// In a window the frame is drawn and shown after the driver returns: its report waits
    /// for the next frame's start.
    deferred: Option<u32>,
    defer: bool,
}

impl FrameLockSide {
    fn open(args: &ServeArgs, channel: &Channel) -> anyhow::Result<Option<FrameLockSide>> {
        let bind: BindTarget = args.cigi_bind.parse().context("--cigi-bind")?;
        if let Some(port) = args.lock_port {
            let endpoint = UdpEndpoint::open(EndpointConfig {
                label: "frame lock",
                bind,
                port,
                delivery: Delivery::Unicast,
                destination: None,
                queue_limit: 1024,
                reuse_port: false,
            })
            .with_context(|| format!("--lock-port {port}"))?;
            return Ok(Some(FrameLockSide::Master(Box::new(LockMaster {
                endpoint,
                lock: FrameLock::new(),
                timeout: Duration::from_millis(args.lock_timeout_ms),
                inbox: Vec::new(),
                bad: RateLimitedLog::new("frame lock"),
                drops: RateLimitedLog::new("frame lock"),
                waits: 0,
                wait_ms_sum: 0.0,
                wait_ms_max: 0.0,
                timeouts: 0,
                last_frame_done: None,
                frame_interval_s: None,
            }))));
        }
        let Some(master) = &args.lock else {
            return Ok(None);
        };
        let to = resolve(master, "--lock")?;
        let endpoint = UdpEndpoint::open(EndpointConfig {
            label: "frame lock",
            bind,
            port: 0,
            delivery: Delivery::Unicast,
            destination: Some(to),
            queue_limit: 16,
            reuse_port: false,
        })
        .context("the frame lock's socket")?;
        let first_view = channel
            .views
            .as_ref()
            .and_then(|v| v.first().copied())
            .unwrap_or(0);
        Ok(Some(FrameLockSide::Slave(LockSlave {
            endpoint,
            channel: u32::from(first_view),
            sent: 0,
            failures: 0,
            deferred: None,
            defer: !args.headless && !args.no_render,
        })))
    }

    fn json(&self) -> serde_json::Value {
        match self {
            FrameLockSide::Master(m) => serde_json::json!({
                "side": "master",
                "address": m.endpoint.local_addr().to_string(),
                "slaves_known": m.lock.slaves().len(),
                "slaves_in_lock": m.lock.in_lock(),
                "waits": m.waits,
                "wait_ms_mean": m.wait_ms_sum / (m.waits.max(1) as f64),
                "wait_ms_max": m.wait_ms_max,
                "timeouts": m.timeouts,
                "bad_datagrams": m.bad.count(),
            }),
            FrameLockSide::Slave(s) => serde_json::json!({
                "side": "slave",
                "to": s.endpoint.destination().map(|a| a.to_string()),
                "reports_sent": s.sent,
                "send_failures": s.failures,
            }),
        }
    }
}

impl LockMaster {
    /// Notes a frame of its own done (the lock's timeout follows the IG's frame rate).
    fn frame_done(&mut self) {
        let now = Instant::now();
        if let Some(last) = self.last_frame_done.replace(now) {
            let dt = (now - last).as_secs_f64();
            self.frame_interval_s = Some(match self.frame_interval_s {
                Some(s) => 0.9 * s + 0.1 * dt,
                None => dt,
            });
        }
    }

    /// How long to wait for a late slave: eight of the IG's frames, at least 250 ms, at most
    /// `--lock-timeout-ms` (a dead channel stalls the others that long, once).
    fn timeout(&self) -> Duration {
        let frames = self
            .frame_interval_s
            .map_or(self.timeout, |s| Duration::from_secs_f64(8.0 * s));
        frames.clamp(Duration::from_millis(250).min(self.timeout), self.timeout)
    }

    fn read(&mut self, master_frame: Option<u32>) {
        let now = Instant::now();
        for d in self.inbox.drain(..) {
            match FrameDrawn::decode(&d.bytes) {
                Ok(drawn) => match self.lock.note(d.from, drawn, master_frame) {
                    Some(LockEvent::Joined(from, drawn)) => tracing::info!(
                        "frame lock: channel {} at {from} joins on host frame {}",
                        drawn.channel,
                        drawn.host_frame
                    ),
                    Some(LockEvent::Dropped(..)) | None => {}
                },
                Err(e) => {
                    self.bad.note(now, &d.from.to_string(), &e.to_string());
                }
            }
        }
    }

    /// Reads the reports, then waits until every slave in the lock has drawn `master_frame`,
    /// or the timeout has passed (the late are taken out).
    fn wait_for_slaves(&mut self, master_frame: Option<u32>) {
        self.endpoint.drain(&mut self.inbox);
        self.read(master_frame);
        let Some(frame) = master_frame else {
            return;
        };
        if self.lock.all_drawn(frame) {
            return;
        }
        let began = Instant::now();
        let timeout = self.timeout();
        let deadline = began + timeout;
        while !self.lock.all_drawn(frame) {
            let left = deadline.saturating_duration_since(Instant::now());
            // Datagrams still queued come back after the deadline too: a flood of the lock's
            // port must not hold the master.
            match self.endpoint.recv_timeout(left).filter(|_| !left.is_zero()) {
                Some(d) => {
                    self.inbox.push(d);
                    self.read(master_frame);
                }
                None => {
                    self.timeouts += 1;
                    let now = Instant::now();
                    for event in self.lock.drop_late(frame) {
                        if let LockEvent::Dropped(from, drawn) = event {
                            // At a limited rate: a slave slower than the timeout every frame
                            // is dropped every frame.
                            self.drops.note(
                                now,
                                &from.to_string(),
                                &format!(
                                    "channel {} is still on host frame {} after {} ms: going on without it until it draws another",
                                    drawn.channel,
                                    drawn.host_frame,
                                    timeout.as_millis()
                                ),
                            );
                        }
                    }
                    break;
                }
            }
        }
        let ms = began.elapsed().as_secs_f64() * 1000.0;
        self.waits += 1;
        self.wait_ms_sum += ms;
        self.wait_ms_max = self.wait_ms_max.max(ms);
    }
}

impl LockSlave {
    /// Notes a frame drawn: reported now, or (in a window) at the next frame's start.
    fn frame_drawn(&mut self, host_frame: u32) {
        if self.defer {
            self.deferred = Some(host_frame);
        } else {
            self.report(host_frame);
        }
    }

    /// At a frame's start: the last frame's deferred report.
    fn frame_starts(&mut self) {
        if let Some(host_frame) = self.deferred.take() {
            self.report(host_frame);
        }
    }

    fn report(&mut self, host_frame: u32) {
        let datagram = FrameDrawn {
            host_frame,
            channel: self.channel,
        }
        .encode();
        match self.endpoint.send(&datagram) {
            Ok(()) => self.sent += 1,
            // The master is not up yet, or gone: the lock is its business.
            Err(_) => self.failures += 1,
        }
    }
}

/// The seconds since 1970 now.
pub fn unix_now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// One frame of `--frame-log`.
struct FrameLogLine {
    /// When the frame was done, seconds since 1970.
    unix_s: f64,
    frame: u64,
    host_frame: Option<u32>,
    host_frames_applied: u64,
    frame_ms: f64,
}

/// `--frame-log`: one JSON line per frame, flushed as written (a channel killed keeps its
/// timeline).
struct FrameLog {
    file: std::io::BufWriter<std::fs::File>,
    path: PathBuf,
}

impl FrameLog {
    fn create(path: &Path) -> anyhow::Result<FrameLog> {
        let file = std::fs::File::create(path)
            .with_context(|| format!("cannot create the frame log {}", path.display()))?;
        Ok(FrameLog {
            file: std::io::BufWriter::new(file),
            path: path.to_path_buf(),
        })
    }

    fn write(&mut self, line: &FrameLogLine) -> anyhow::Result<()> {
        use std::io::Write;
        let value = serde_json::json!({
            "frame": line.frame,
            "host_frame": line.host_frame,
            "host_frames_applied": line.host_frames_applied,
            "unix_s": line.unix_s,
            "frame_ms": line.frame_ms,
        });
        writeln!(self.file, "{value}")
            .and_then(|()| self.file.flush())
            .with_context(|| format!("cannot write the frame log {}", self.path.display()))
    }
}

fn report(
    totals: &Totals,
    world: &IgWorld,
    cigi: &UdpEndpoint,
    dis: Option<&UdpEndpoint>,
    (channel, lock): (&Channel, Option<&FrameLockSide>),
    json: bool,
) -> anyhow::Result<()> {
    let c = world.session().counters();
    let requests = world.session().edit_requests().counters();
    let mean_ms = totals.frame_ms_sum / (totals.frames.max(1) as f64);
    let exercise = world.exercise().map(|x| {
        let e = x.counters();
        serde_json::json!({
            "datagrams": e.datagrams,
            "pdus": e.pdus,
            "bad_pdus": e.bad_pdus,
            "entity_states_applied": e.entity_states_applied,
            "ignored": e.ignored,
            "detonations": e.detonations,
            "impacts_started": e.impacts_started,
            "environmental_processes": e.environmental_processes,
            "pdus_sent": e.pdus_sent,
            "craters_made": e.craters_made,
            "terrain_edits_received": e.terrain_edits_received,
            "terrain_edits_healed": e.terrain_edits_healed,
            "terrain_edits_refused": e.terrain_edits_refused,
            "terrain_edits_sent": e.terrain_edits_sent,
            "remote_entities": x.remote_len(),
            "time_role": format!("{:?}", x.time_role()),
        })
    });
    let value = serde_json::json!({
        "frames": totals.frames,
        "ig_frame_number": world.session().ig_frame_number(),
        "last_host_frame_number": world.session().last_host_frame_number(),
        "frame_ms_mean": mean_ms,
        "frame_ms_max": totals.frame_ms_max,
        "overframes": totals.overframes,
        "cigi": {
            "datagrams": totals.cigi_datagrams,
            "bad_datagrams": totals.cigi_bad,
            "messages_sent": totals.messages_sent,
            "packets_applied": c.packets_applied,
            "packets_ignored": c.packets_ignored,
            "hat_hot_answered": c.hat_hot_answered,
            "los_answered": c.los_answered,
            "position_answered": c.position_answered,
            "environment_answered": c.environment_answered,
            "collisions_reported": c.collisions_reported,
            "queue_dropped": cigi.stats().dropped_queue_full,
            "problems_noted": totals.problems_noted,
            "user_defined_packets": c.user_defined_packets,
            "terrain_edit_requests": {
                "received": requests.received,
                "craters_made": requests.craters_made,
                "healed": requests.healed,
                "refused": requests.refused,
                "malformed": requests.malformed,
            },
            "warnings_logged": totals.warnings_logged,
            "entities": world.session().entities().len(),
            "address": cigi.local_addr().to_string(),
        },
        "dis": exercise.map(|mut e| {
            if let (Some(obj), Some(d)) = (e.as_object_mut(), dis) {
                obj.insert("queue_dropped".into(), d.stats().dropped_queue_full.into());
                obj.insert("address".into(), d.local_addr().to_string().into());
            }
            e
        }),
        "effects_live": world.effects().stats().live_effects,
        "last_frame": {
            "entities_drawn": totals.entities_drawn,
            "puffs_drawn": totals.puffs_drawn,
            "lights": totals.lights,
        },
        "lights_max": totals.lights_max,
        "channel": {
            "setup": channel.json(),
            "host_frame_drawn": totals.drawn_host_frame,
            "host_frames_skipped": totals.host_frames_skipped,
            "lag_frames_max": totals.lag_frames_max,
            "latency_ms_mean": totals.latency_ms_sum / (totals.frames.max(1) as f64),
            "latency_ms_max": totals.latency_ms_max,
            "joined_after_ms": totals.joined_after_ms,
            "relayed": totals.relayed,
            "views_missing": world.channel_views_missing(),
            "lock": lock.map(FrameLockSide::json),
        },
        "sim_time": UtcTime::from_unix_seconds(world.unix_time_s()).map(|t| t.to_iso8601_seconds()).unwrap_or_default(),
    });
    if json {
        println!("{}", serde_json::to_string(&value)?);
    } else {
        eprintln!(
            "served {} frames ({:.1} ms mean, {} overframes): {} host datagrams ({} bad), {} HAT/HOT, {} LOS answered",
            totals.frames,
            mean_ms,
            totals.overframes,
            totals.cigi_datagrams,
            totals.cigi_bad,
            c.hat_hot_answered,
            c.los_answered
        );
    }
    Ok(())
}
