//! `cig bench channels`: three display channels of one eyepoint as three `cig serve`
//! processes on this machine, frame-locked to a scripted host (CIGI synchronous mode), and
//! what the issue asks of them: the spread of the host frames they show at any instant, a
//! slave's frame cost against a master's drawing the same view, and how long a killed slave
//! takes to show the current frame again.
//!
//! Method. The channels are real processes (the `cig` binary the caller names) with real
//! sockets: the master (centre view) answers the host, relays its datagrams to two slaves
//! (left and right views) and holds them in its frame lock (`--lock-port`, `--lock`); each
//! writes its timeline with `--frame-log` (wall-clock time and host frame of every frame
//! drawn). The host runs here as a synchronous CIGI host: it sends frame n + 1 when the
//! master's Start of Frame for frame n arrives (never faster than `rate_hz`; four a second
//! until the master first answers; after five seconds without an answer, anyway), flying the
//! eyepoint round the database's middle with a HAT request every frame, over a scenario with a
//! cloud layer and a smoke plume. After a warm-up (every channel has drawn a host frame, then
//! `warmup_s` more):
//! - *spread*: at every frame drawn by any channel, the newest host frame each channel has
//!   drawn; the spread is the largest minus the smallest. A channel drawing frame n while the
//!   others show n - 1 is a spread of 1, the least any set of processes can do;
//! - *restart*: the right slave is killed (SIGKILL, as a crash) and, once the master has
//!   dropped it from the lock, started again; the time from its start to its first frame
//!   within one host frame of the master's is its rejoin time (process start, database, GPU,
//!   first frame: all of it);
//! - *slave cost*: a second run, a master and a slave both drawing the centre view, compares
//!   their CPU time per frame (every thread of the process, from `/proc`: robust to which of
//!   the two the scheduler runs first), and their median frame times (from taking the host
//!   frame off the queue, after the master's wait for its slaves, to the frame drawn).
//!
//! Limits: all channels share this machine's cores and GPU (on lavapipe, its CPU), so a
//! channel's frame here costs more than on a machine of its own, and the spread is a bound for
//! channels competing for one CPU; the clocks compared are one machine's.

use crate::report::{cpu_time_s, date_utc, machine, median, percentile};
use crate::{require, BenchError, Report, Step};
use cig_net::{BindTarget, Datagram, Delivery, EndpointConfig, UdpEndpoint};
use cig_tools::host::{HostScript, Replies};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// What `cig bench channels` measures.
#[derive(Clone, Debug)]
pub struct ChannelsOptions {
    /// The `cig` binary the channels run (`cig serve`).
    pub cig_exe: PathBuf,
    /// Terrain database.
    pub db: PathBuf,
    /// Each channel's frame size, pixels.
    pub size_px: (u32, u32),
    /// Host frames a second.
    pub rate_hz: f64,
    /// Seconds from the host's first frame before measuring (start-up, paging).
    pub warmup_s: f64,
    /// Seconds measured (the spread; then as much again for the slave cost).
    pub seconds: f64,
    /// Keep the channels' frame logs, output and scenario in this folder (else a scratch
    /// folder, removed).
    pub keep_dir: Option<PathBuf>,
    pub commit: String,
}

/// The database's box, degrees: south, west, north, east.
pub(crate) fn database_box(db: &Path) -> Result<[f64; 4], BenchError> {
    let database = cig_terrain_io::store::open_database(db)?;
    let g = database.manifest().layout.grid;
    Ok([
        g.south_lat_deg,
        g.west_lon_deg,
        g.north_lat_deg(),
        g.east_lon_deg(),
    ])
}

/// The point `(u, v)` of the way across the box (0..1 each), as `[lat, lon]`.
pub(crate) fn inside(bx: [f64; 4], u: f64, v: f64) -> [f64; 2] {
    [bx[0] + (bx[2] - bx[0]) * v, bx[1] + (bx[3] - bx[1]) * u]
}

/// The seconds since 1970 now.
pub(crate) fn unix_now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// A free loopback UDP port.
pub(crate) fn free_port() -> Result<u16, BenchError> {
    Ok(cig_net::free_udp_port()?)
}

/// One frame of a channel's `--frame-log`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FrameRecord {
    pub unix_s: f64,
    pub host_frame: Option<u32>,
    pub frame_ms: f64,
}

/// Reads a frame log (a line cut short by a kill is skipped).
pub(crate) fn read_frame_log(path: &Path) -> Result<Vec<FrameRecord>, BenchError> {
    let text = std::fs::read_to_string(path)
        .step_with(|| format!("cannot read the frame log {}", path.display()))?;
    Ok(text
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| {
            Some(FrameRecord {
                unix_s: v["unix_s"].as_f64()?,
                host_frame: v["host_frame"].as_u64().and_then(|n| u32::try_from(n).ok()),
                frame_ms: v["frame_ms"].as_f64()?,
            })
        })
        .collect())
}

/// A `cig serve` process; killed when dropped.
pub(crate) struct ServeProcess {
    child: Child,
    label: String,
    stdout: PathBuf,
    stderr: PathBuf,
    /// Its `--frame-log`.
    pub frame_log: PathBuf,
    /// When it was started, seconds since 1970.
    pub spawned_unix_s: f64,
}

impl ServeProcess {
    /// Starts `cig serve ARGS --frame-log ... --json`, its output in files of `dir` named by
    /// `label`.
    pub fn spawn(
        exe: &Path,
        dir: &Path,
        label: &str,
        args: &[String],
    ) -> Result<ServeProcess, BenchError> {
        let frame_log = dir.join(format!("{label}.frames.jsonl"));
        let stdout = dir.join(format!("{label}.stdout"));
        let stderr = dir.join(format!("{label}.stderr"));
        let out = std::fs::File::create(&stdout).step("creating a channel's output file")?;
        let err = std::fs::File::create(&stderr).step("creating a channel's log file")?;
        let spawned_unix_s = unix_now_s();
        let child = Command::new(exe)
            .arg("serve")
            .args(args)
            .arg("--frame-log")
            .arg(&frame_log)
            .arg("--json")
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .spawn()
            .step_with(|| format!("cannot start {}", exe.display()))?;
        Ok(ServeProcess {
            child,
            label: label.to_string(),
            stdout,
            stderr,
            frame_log,
            spawned_unix_s,
        })
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Why it has ended, if it has (its exit status and the last line of its log).
    pub fn ended(&mut self) -> Option<String> {
        let status = self.child.try_wait().ok()??;
        let stderr = std::fs::read_to_string(&self.stderr).unwrap_or_default();
        Some(format!(
            "the channel {} ended ({status}): {}",
            self.label,
            stderr.lines().last().unwrap_or("no message")
        ))
    }

    /// Kills it (SIGKILL: as a crash) and reaps it.
    pub fn kill(&mut self) {
        // Errors: it has ended already.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Waits up to `timeout` for it to end by itself; its `--json` summary.
    pub fn finish(mut self, timeout: Duration) -> Result<serde_json::Value, BenchError> {
        let until = Instant::now() + timeout;
        let status = loop {
            if let Some(status) = self.child.try_wait().step("waiting for a channel")? {
                break status;
            }
            if Instant::now() > until {
                self.kill();
                return Err(BenchError::Scene(format!(
                    "the channel {} did not end within {} s of its host's last frame",
                    self.label,
                    timeout.as_secs()
                )));
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let stderr = std::fs::read_to_string(&self.stderr).unwrap_or_default();
        if !status.success() {
            let last = stderr.lines().last().unwrap_or("no message");
            return Err(BenchError::Scene(format!(
                "the channel {} failed ({status}): {last}",
                self.label
            )));
        }
        let stdout = std::fs::read_to_string(&self.stdout).step("reading a channel's output")?;
        stdout
            .lines()
            .rev()
            .find_map(|l| serde_json::from_str(l).ok())
            .ok_or_else(|| {
                BenchError::Scene(format!("the channel {} printed no summary", self.label))
            })
    }
}

impl Drop for ServeProcess {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            self.kill();
        }
    }
}

/// The scripted host: one message per host frame to the IG, the IG's answers read.
pub(crate) struct Host {
    endpoint: UdpEndpoint,
    script: HostScript,
    replies: Replies,
    inbox: Vec<Datagram>,
    bytes: Vec<u8>,
    /// The next host frame.
    pub frame: u32,
    /// Host frames the IG could not be sent (not listening yet).
    pub send_failures: u64,
}

impl Host {
    pub fn new(script_toml: &str, ig_port: u16) -> Result<Host, BenchError> {
        let script = HostScript::from_toml(script_toml).step("the benchmark's host script")?;
        let endpoint = UdpEndpoint::open(EndpointConfig {
            label: "bench host",
            bind: BindTarget::Loopback,
            port: 0,
            delivery: Delivery::Unicast,
            destination: Some(std::net::SocketAddr::from(([127, 0, 0, 1], ig_port))),
            queue_limit: 4096,
            reuse_port: false,
        })?;
        Ok(Host {
            endpoint,
            script,
            replies: Replies::new(),
            inbox: Vec::new(),
            bytes: Vec::with_capacity(4096),
            frame: 0,
            send_failures: 0,
        })
    }

    /// Sends the next host frame and reads what the IG sent since the last.
    pub fn send_frame(&mut self) -> Result<(), BenchError> {
        let message = self
            .script
            .frame(self.frame, self.replies.last_ig_frame())
            .step("the host's frame")?;
        self.bytes.clear();
        cig_cigi::encode_message(&message, &mut self.bytes)?;
        if self.endpoint.send(&self.bytes).is_err() {
            self.send_failures += 1;
        }
        self.inbox.clear();
        self.endpoint.drain(&mut self.inbox);
        self.read_inbox();
        self.frame += 1;
        Ok(())
    }

    fn read_inbox(&mut self) {
        for d in &self.inbox {
            // An answer the host cannot read is the IG's fault, counted by the summary.
            let _ = self.replies.read(&d.bytes, self.frame);
        }
    }

    /// Waits up to `timeout` for the IG's next Start of Frame (CIGI synchronous mode: the IG's
    /// frame starts the host's next); whether it came.
    pub fn wait_start_of_frame(&mut self, timeout: Duration) -> bool {
        let before = self.replies.start_of_frames();
        let until = Instant::now() + timeout;
        while self.replies.start_of_frames() == before {
            let Some(left) = until.checked_duration_since(Instant::now()) else {
                return false;
            };
            let Some(d) = self.endpoint.recv_timeout(left) else {
                return false;
            };
            self.inbox.clear();
            self.inbox.push(d);
            self.endpoint.drain(&mut self.inbox);
            self.read_inbox();
        }
        true
    }

    /// Start of Frame messages received from the IG.
    pub fn start_of_frames(&self) -> u64 {
        self.replies.start_of_frames()
    }
}

/// A synchronous host for `seconds`: each frame sent when the IG's Start of Frame for the last
/// arrives (its frame starts the host's next), never faster than `rate_hz`; before the IG first
/// answers, four frames a second; after five seconds without an answer (the IG is gone),
/// anyway. Host frames sent.
pub(crate) fn synchronous(host: &mut Host, rate_hz: f64, seconds: f64) -> Result<u32, BenchError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let start = Instant::now();
    let until = start + Duration::from_secs_f64(seconds);
    let mut sent = 0;
    while Instant::now() < until {
        let frame_began = Instant::now();
        host.send_frame()?;
        sent += 1;
        // A synchronous host waits for the IG, once it has heard it: five seconds without a
        // Start of Frame (the IG is gone) and it sends anyway. (A shorter wait sends frames the
        // IG then skips when its frames are slow, and a skip is a spread of two.) Until the IG
        // first answers, it sends a frame a quarter of a second.
        let wait = if host.start_of_frames() == 0 {
            Duration::from_millis(250)
        } else {
            Duration::from_secs(5)
        };
        host.wait_start_of_frame(wait);
        if let Some(rest) = period.checked_sub(frame_began.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    Ok(sent)
}

/// Runs the host in quarter seconds until `done` holds (true) or `limit` has passed (false);
/// a channel that ends on the way is an error with its reason.
fn host_until(
    host: &mut Host,
    rate_hz: f64,
    limit: Duration,
    channels: &mut [&mut ServeProcess],
    mut done: impl FnMut(&[&mut ServeProcess]) -> bool,
) -> Result<bool, BenchError> {
    let began = Instant::now();
    loop {
        synchronous(host, rate_hz, 0.25)?;
        for channel in channels.iter_mut() {
            if let Some(why) = channel.ended() {
                return Err(BenchError::Scene(why));
            }
        }
        if done(channels) {
            return Ok(true);
        }
        if began.elapsed() > limit {
            return Ok(false);
        }
    }
}

/// Whether every channel has drawn a host frame (started, paged in, its first frame done).
fn all_drawing(channels: &[&mut ServeProcess]) -> bool {
    channels.iter().all(|channel| {
        read_frame_log(&channel.frame_log)
            .is_ok_and(|log| log.iter().any(|r| r.host_frame.is_some()))
    })
}

/// Runs the host until every channel draws (at most a minute).
fn until_drawing(
    host: &mut Host,
    rate_hz: f64,
    channels: &mut [&mut ServeProcess],
) -> Result<(), BenchError> {
    if host_until(
        host,
        rate_hz,
        Duration::from_secs(60),
        channels,
        all_drawing,
    )? {
        Ok(())
    } else {
        Err(BenchError::Scene(
            "a channel drew no host frame within a minute of starting".into(),
        ))
    }
}

/// Paces `each` at `rate_hz` for `seconds` (frames late are sent at once, not dropped).
pub(crate) fn paced(
    rate_hz: f64,
    seconds: f64,
    mut each: impl FnMut() -> Result<(), BenchError>,
) -> Result<(), BenchError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let frames = (seconds * rate_hz).ceil() as u32;
    let start = Instant::now();
    for i in 0..frames {
        if let Some(wait) = (start + period * i).checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        each()?;
    }
    Ok(())
}

/// The host script of a flight across the box's middle at `speed_mps`, `clamp_alt_m` above
/// the terrain, with three adjacent views of 30° each on its eyepoint and a HAT request below
/// it every frame.
pub(crate) fn flight_script(
    bx: [f64; 4],
    rate_hz: f64,
    frames: u32,
    speed_mps: f64,
    clamp_alt_m: f64,
    views: &[(u16, [f64; 4])],
) -> String {
    let corners = [
        inside(bx, 0.3, 0.3),
        inside(bx, 0.7, 0.3),
        inside(bx, 0.7, 0.7),
        inside(bx, 0.3, 0.7),
    ];
    let path: Vec<String> = corners
        .iter()
        .map(|c| format!("[{:.6}, {:.6}]", c[0], c[1]))
        .collect();
    let mut text = format!(
        "rate_hz = {rate_hz}\nframes = {frames}\ntime = \"2026-06-21T16:00:00Z\"\nvisibility_m = 30000\n\
         [[entities]]\nid = 0\ntype = 1\nclamp = \"height\"\nalt_m = {clamp_alt_m}\nspeed_mps = {speed_mps}\n\
         path = [{}]\nrepeat = true\n\
         [[hat]]\nid = 1\nentity = 0\ntype = \"hat\"\nevery_frame = true\n",
        path.join(", ")
    );
    for (id, fov) in views {
        text.push_str(&format!(
            "[[views]]\nid = {id}\nentity = 0\noffset_m = [0, 0, -3]\nhpr_deg = [0, -4, 0]\n\
             fov_deg = [{}, {}, {}, {}]\n",
            fov[0], fov[1], fov[2], fov[3]
        ));
    }
    text
}

/// Three adjacent channels of 30° by 30° × 3/4 (320 x 240 each), left to right.
const THREE_VIEWS: [(u16, [f64; 4]); 3] = [
    (0, [-45.0, -15.0, -11.4, 11.4]),
    (1, [-15.0, 15.0, -11.4, 11.4]),
    (2, [15.0, 45.0, -11.4, 11.4]),
];

/// The scenario of the benchmark: a cloud layer and a smoke plume in view.
fn scenario_toml(bx: [f64; 4]) -> String {
    let smoke = inside(bx, 0.5, 0.45);
    format!(
        "start_time = \"2026-06-21T16:00:00Z\"\n\
         [[clouds]]\nbase_m = 1800\nthickness_m = 400\ncoverage = 0.4\n\
         [[smoke]]\nid = 1\nlat_deg = {:.6}\nlon_deg = {:.6}\nduration_s = 100000\n",
        smoke[0], smoke[1]
    )
}

/// The newest host frame each channel has drawn at each frame any of them drew in
/// `[from_s, to_s]`: the largest spread, and the frames drawn in the window.
fn frame_spread(logs: &[&[FrameRecord]], from_s: f64, to_s: f64) -> (u32, usize) {
    let mut events: Vec<(f64, usize, u32)> = logs
        .iter()
        .enumerate()
        .flat_map(|(c, log)| {
            log.iter()
                .filter_map(move |r| r.host_frame.map(|h| (r.unix_s, c, h)))
        })
        .collect();
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut newest: Vec<Option<u32>> = vec![None; logs.len()];
    let (mut spread_max, mut instants) = (0, 0);
    for (t, c, h) in events {
        newest[c] = Some(newest[c].map_or(h, |n| n.max(h)));
        if t < from_s || t > to_s {
            continue;
        }
        let known: Vec<u32> = newest.iter().flatten().copied().collect();
        if known.len() < logs.len() {
            continue;
        }
        instants += 1;
        let (lo, hi) = (
            known.iter().min().copied().unwrap_or(0),
            known.iter().max().copied().unwrap_or(0),
        );
        spread_max = spread_max.max(hi - lo);
    }
    (spread_max, instants)
}

/// The first frame of `log` within one host frame of `reference`'s newest at its time.
fn rejoined_at(log: &[FrameRecord], reference: &[FrameRecord]) -> Option<f64> {
    log.iter().find_map(|r| {
        let h = r.host_frame?;
        let newest = reference
            .iter()
            .filter(|m| m.unix_s <= r.unix_s)
            .filter_map(|m| m.host_frame)
            .max()?;
        cig_ig::frame_lock::at_or_after(h.wrapping_add(1), newest).then_some(r.unix_s)
    })
}

/// Frame costs of a log's host frames drawn in `[from_s, to_s]` (seconds since 1970).
pub(crate) fn costs(log: &[FrameRecord], from_s: f64, to_s: f64) -> Vec<f64> {
    log.iter()
        .filter(|r| r.unix_s >= from_s && r.unix_s <= to_s && r.host_frame.is_some())
        .map(|r| r.frame_ms)
        .collect()
}

/// A folder for the run's files: a scratch one removed at the end, or one kept.
pub(crate) enum Scratch {
    Temporary(tempfile::TempDir),
    Kept(PathBuf),
}

impl Scratch {
    pub fn new(keep: Option<&Path>) -> Result<Scratch, BenchError> {
        match keep {
            Some(dir) => {
                std::fs::create_dir_all(dir)
                    .step_with(|| format!("cannot create {}", dir.display()))?;
                Ok(Scratch::Kept(dir.to_path_buf()))
            }
            None => Ok(Scratch::Temporary(
                tempfile::tempdir().step("a scratch folder")?,
            )),
        }
    }

    pub fn path(&self) -> &Path {
        match self {
            Scratch::Temporary(t) => t.path(),
            Scratch::Kept(p) => p,
        }
    }
}

/// `cig serve` off-screen over `db` and `scenario`, frames of `size` at `rate_hz`, the host on
/// `port`, ending three seconds after the host's last frame.
pub(crate) fn serve_args(
    db: &Path,
    scenario: &Path,
    (w, h): (u32, u32),
    rate_hz: f64,
    port: u16,
) -> Vec<String> {
    [
        "--db",
        &db.display().to_string(),
        "--scenario",
        &scenario.display().to_string(),
        "--headless",
        "--size",
        &format!("{w}x{h}"),
        "--rate-hz",
        &rate_hz.to_string(),
        "--idle-exit-s",
        "3",
        "--cigi-port",
        &port.to_string(),
    ]
    .iter()
    .map(ToString::to_string)
    .collect()
}

/// Arguments every channel of the benchmark shares: synchronous mode.
fn channel_args(options: &ChannelsOptions, scenario: &Path, port: u16) -> Vec<String> {
    with(
        serve_args(
            &options.db,
            scenario,
            options.size_px,
            options.rate_hz,
            port,
        ),
        &["--sync"],
    )
}

fn with(mut args: Vec<String>, more: &[&str]) -> Vec<String> {
    args.extend(more.iter().map(ToString::to_string));
    args
}

pub fn run(options: &ChannelsOptions) -> Result<Report, BenchError> {
    require(
        options.rate_hz.is_finite() && (1.0..=240.0).contains(&options.rate_hz),
        || format!("--rate-hz {} must lie between 1 and 240", options.rate_hz),
    )?;
    require(
        options.seconds.is_finite() && (2.0..=3600.0).contains(&options.seconds),
        || format!("--seconds {} must lie between 2 and 3600", options.seconds),
    )?;
    require(
        options.warmup_s.is_finite() && (1.0..=600.0).contains(&options.warmup_s),
        || format!("--warmup-s {} must lie between 1 and 600", options.warmup_s),
    )?;
    let (w, h) = options.size_px;
    require((16..=4096).contains(&w) && (16..=4096).contains(&h), || {
        format!("--size {w}x{h} must be 16 to 4096 pixels a side")
    })?;
    let bx = database_box(&options.db)?;
    let dir = Scratch::new(options.keep_dir.as_deref())?;
    let scenario = dir.path().join("scenario.toml");
    std::fs::write(&scenario, scenario_toml(bx)).step("writing the scenario")?;
    let script = flight_script(bx, options.rate_hz, u32::MAX, 120.0, 150.0, &THREE_VIEWS);
    let exe = &options.cig_exe;

    // Three channels: slaves left and right, the master in the centre relaying to them and
    // holding them in its frame lock.
    let ports = [free_port()?, free_port()?, free_port()?];
    let lock_port = free_port()?;
    let lock_to = format!("127.0.0.1:{lock_port}");
    let relay = format!("127.0.0.1:{},127.0.0.1:{}", ports[0], ports[2]);
    let slave = |view: u16, port: u16, label: &str| {
        ServeProcess::spawn(
            exe,
            dir.path(),
            label,
            &with(
                channel_args(options, &scenario, port),
                &[
                    "--role",
                    "slave",
                    "--view",
                    &view.to_string(),
                    "--lock",
                    &lock_to,
                ],
            ),
        )
    };
    let mut left = slave(0, ports[0], "left")?;
    let mut right = slave(2, ports[2], "right")?;
    let mut master = ServeProcess::spawn(
        exe,
        dir.path(),
        "centre",
        &with(
            channel_args(options, &scenario, ports[1]),
            &[
                "--view",
                "1",
                "--relay",
                &relay,
                "--lock-port",
                &lock_port.to_string(),
            ],
        ),
    )?;
    let mut host = Host::new(&script, ports[1])?;
    until_drawing(
        &mut host,
        options.rate_hz,
        &mut [&mut left, &mut master, &mut right],
    )?;
    synchronous(&mut host, options.rate_hz, options.warmup_s)?;
    let measure_from = unix_now_s();
    synchronous(&mut host, options.rate_hz, options.seconds)?;
    let measure_to = unix_now_s();
    // Half a second later (so that no frame of the window is cut from its log), the right
    // slave crashes; the host goes on, and the master drops the dead slave from its lock (at
    // most a second); then the slave is started again, as a supervisor would.
    synchronous(&mut host, options.rate_hz, 0.5)?;
    right.kill();
    let killed_log = right.frame_log.clone();
    synchronous(&mut host, options.rate_hz, 1.5)?;
    let mut right = slave(2, ports[2], "right-restarted")?;
    let restarted_at = right.spawned_unix_s;
    // The host goes on until the restarted slave is back on the master's frame (at most half a
    // minute), and a second more.
    host_until(
        &mut host,
        options.rate_hz,
        Duration::from_secs(30),
        &mut [&mut right, &mut master],
        |c| {
            let log = |i: usize| read_frame_log(&c[i].frame_log).unwrap_or_default();
            rejoined_at(&log(0), &log(1)).is_some()
        },
    )?;
    synchronous(&mut host, options.rate_hz, 1.0)?;
    let host_frames = host.frame;
    let start_of_frames = host.start_of_frames();
    drop(host);
    let timeout = Duration::from_secs(30);
    let frame_logs = [
        left.frame_log.clone(),
        master.frame_log.clone(),
        killed_log,
        right.frame_log.clone(),
    ];
    let centre_summary = master.finish(timeout)?;
    let left_summary = left.finish(timeout)?;
    let restarted_summary = right.finish(timeout)?;

    let logs = [
        read_frame_log(&frame_logs[0])?,
        read_frame_log(&frame_logs[1])?,
        read_frame_log(&frame_logs[2])?,
    ];
    let restarted_log = read_frame_log(&frame_logs[3])?;
    let (spread_max, instants) =
        frame_spread(&[&logs[0], &logs[1], &logs[2]], measure_from, measure_to);
    if instants == 0 {
        return Err(BenchError::Scene(format!(
            "the three channels drew no host frame together in {} s (host frames sent {host_frames}, Start of Frame received {start_of_frames})",
            options.seconds
        )));
    }
    let rejoin_s = rejoined_at(&restarted_log, &logs[1]).map(|t| t - restarted_at);
    let spread_after = rejoin_s.map(|r| {
        frame_spread(
            &[&logs[0], &logs[1], &restarted_log],
            restarted_at + r,
            f64::INFINITY,
        )
        .0
    });
    let channel_json =
        |name: &str, role: &str, log: &[FrameRecord], summary: &serde_json::Value| {
            let c = costs(log, measure_from, measure_to);
            serde_json::json!({
                "channel": name,
                "role": role,
                "frames_measured": c.len(),
                "frame_ms_median": median(&c),
                "frame_ms_p99": percentile(&c, 0.99),
                "host_frames_skipped": summary["channel"]["host_frames_skipped"],
                "latency_ms_mean": summary["channel"]["latency_ms_mean"],
            })
        };

    // The slave's cost: a master and a slave drawing the same (centre) view (the slave reports
    // to the first run's lock port, which the new master takes over).
    let ports = [free_port()?, free_port()?];
    let mut same_slave = slave(1, ports[1], "same-view-slave")?;
    let mut same_master = ServeProcess::spawn(
        exe,
        dir.path(),
        "same-view-master",
        &with(
            channel_args(options, &scenario, ports[0]),
            &[
                "--view",
                "1",
                "--relay",
                &format!("127.0.0.1:{}", ports[1]),
                "--lock-port",
                &lock_port.to_string(),
            ],
        ),
    )?;
    let mut host = Host::new(&script, ports[0])?;
    until_drawing(
        &mut host,
        options.rate_hz,
        &mut [&mut same_master, &mut same_slave],
    )?;
    synchronous(&mut host, options.rate_hz, options.warmup_s)?;
    // The processes' CPU time (every thread: the world, the renderer, lavapipe's) over the
    // window, and their frames drawn in it.
    let cpu = |p: &ServeProcess| cpu_time_s(&p.pid().to_string());
    let cpu_from = (cpu(&same_master), cpu(&same_slave));
    let cost_from = unix_now_s();
    synchronous(&mut host, options.rate_hz, options.seconds)?;
    let cost_to = unix_now_s();
    let cpu_to = (cpu(&same_master), cpu(&same_slave));
    drop(host);
    let same_logs = [same_master.frame_log.clone(), same_slave.frame_log.clone()];
    same_master.finish(timeout)?;
    same_slave.finish(timeout)?;
    let master_ms = costs(&read_frame_log(&same_logs[0])?, cost_from, cost_to);
    let slave_ms = costs(&read_frame_log(&same_logs[1])?, cost_from, cost_to);
    if master_ms.is_empty() || slave_ms.is_empty() {
        return Err(BenchError::Scene(format!(
            "the master and slave of one view drew {} and {} frames in {} s: no cost to compare",
            master_ms.len(),
            slave_ms.len(),
            options.seconds
        )));
    }
    let wall_ratio = median(&slave_ms) / median(&master_ms);
    let cpu_ms_per_frame = |from: Option<f64>, to: Option<f64>, frames: usize| {
        Some((to? - from?) * 1000.0 / frames.max(1) as f64)
    };
    let master_cpu_ms = cpu_ms_per_frame(cpu_from.0, cpu_to.0, master_ms.len());
    let slave_cpu_ms = cpu_ms_per_frame(cpu_from.1, cpu_to.1, slave_ms.len());
    // The cost is the CPU time a frame takes (robust to which process the scheduler runs
    // first); where /proc is missing, the median wall time of the frames.
    let cost_ratio = match (slave_cpu_ms, master_cpu_ms) {
        (Some(s), Some(m)) if m > 0.0 => s / m,
        _ => wall_ratio,
    };

    let json = serde_json::json!({
        "benchmark": "channels",
        "machine": machine(),
        "date": date_utc(),
        "commit": options.commit,
        "db": options.db.display().to_string(),
        "size": [w, h],
        "rate_hz": options.rate_hz,
        "warmup_s": options.warmup_s,
        "seconds": options.seconds,
        "frame_spread_max": spread_max,
        "frame_spread_instants": instants,
        "frame_spread_max_after_restart": spread_after,
        "channels": [
            channel_json("left", "slave", &logs[0], &left_summary),
            channel_json("centre", "master", &logs[1], &centre_summary),
            channel_json("right", "slave", &logs[2], &restarted_summary),
        ],
        "slave_cost": {
            "master_frame_ms_median": median(&master_ms),
            "slave_frame_ms_median": median(&slave_ms),
            "master_cpu_ms_per_frame": master_cpu_ms,
            "slave_cpu_ms_per_frame": slave_cpu_ms,
            "slave_over_master_wall": wall_ratio,
            "slave_over_master": cost_ratio,
            "frames": [master_ms.len(), slave_ms.len()],
        },
        "restart": {
            "rejoin_s": rejoin_s,
            // From its start of serving (database open, GPU and renderer ready) to its first
            // frame of the host's drawn, and that first frame's cost alone.
            "joined_after_ms": restarted_summary["channel"]["joined_after_ms"],
            "first_frame_ms": restarted_log.first().map(|r| r.frame_ms),
        },
        "host": { "frames_sent": host_frames, "start_of_frames_received": start_of_frames },
        "lock": centre_summary["channel"]["lock"],
        "targets": {
            "frame_spread_max": 1,
            "slave_over_master_max": 1.05,
            "rejoin_s_max": 1.0,
        },
    });
    let summary = format!(
        "three channels at {w}x{h}, host at {} Hz: frame spread at most {spread_max} over {instants} instants \
         (target 1); slave/master frame cost {cost_ratio:.3} (CPU per frame; wall medians {:.2} / {:.2} ms; target <= 1.05); \
         restarted slave on the current frame after {} (target 1 s)",
        options.rate_hz,
        median(&slave_ms),
        median(&master_ms),
        rejoin_s.map_or_else(|| "never".to_string(), |s| format!("{s:.2} s")),
    );
    Ok(Report { json, summary })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(unix_s: f64, host_frame: u32) -> FrameRecord {
        FrameRecord {
            unix_s,
            host_frame: Some(host_frame),
            frame_ms: 1.0,
        }
    }

    #[test]
    fn the_spread_is_the_newest_frames_difference_at_each_instant() {
        // Two channels in step; a third that draws frame 2 again at 3.5 and is two behind the
        // first at 4.0.
        let a = [
            record(1.0, 1),
            record(2.0, 2),
            record(3.0, 3),
            record(4.0, 4),
        ];
        let b = [
            record(1.1, 1),
            record(2.1, 2),
            record(3.1, 3),
            record(4.1, 4),
        ];
        let c = [
            record(1.2, 1),
            record(2.2, 2),
            record(3.5, 2),
            record(4.2, 4),
        ];
        // Instants count once every channel has drawn a frame.
        assert_eq!(frame_spread(&[&a, &b], 0.0, 10.0), (1, 7));
        assert_eq!(frame_spread(&[&a, &b, &c], 0.0, 10.0), (2, 10));
        // Outside the window the instant does not count (but the frames drawn are known).
        assert_eq!(frame_spread(&[&a, &b, &c], 4.15, 10.0), (0, 1));
    }

    #[test]
    fn a_restarted_channel_rejoins_at_its_first_frame_near_the_reference() {
        let master = [record(1.0, 10), record(2.0, 20), record(3.0, 30)];
        let restarted = [record(2.5, 12), record(2.9, 17), record(3.2, 29)];
        assert_eq!(rejoined_at(&restarted, &master), Some(3.2));
        assert_eq!(rejoined_at(&restarted[..2], &master), None);
    }

    #[test]
    fn a_flight_script_reads_as_a_host_script() {
        let script = flight_script(
            [35.0, -121.0, 35.1, -120.9],
            30.0,
            100,
            300.0,
            200.0,
            &THREE_VIEWS,
        );
        let host = HostScript::from_toml(&script).expect("script");
        assert_eq!((host.rate_hz(), host.frames()), (30.0, 100));
        assert!(cig_ig::Scenario::from_toml(&scenario_toml([35.0, -121.0, 35.1, -120.9])).is_ok());
    }
}
