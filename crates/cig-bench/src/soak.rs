//! `cig bench soak` (and `scripts/soak.sh MINUTES`): a long run of `cig serve` under a full
//! load, watched from outside for drift: resident memory, frame time, open file descriptors
//! and threads.
//!
//! Method. One `cig serve --headless` process (the `cig` binary the caller names) over the
//! database, with a scenario of a cloud layer, three smoke plumes along the route and a
//! thunderstorm over the middle, joined to a DIS exercise. Here: a CIGI host at `rate_hz` flying
//! its eyepoint round a racetrack inside the database at `speed_mps` (300 m/s by default,
//! 150 m above the terrain, a HAT request every frame), and `remote_entities` dead-reckoned
//! DIS entities (Entity State PDUs once a second each, moving at 4 to 20 m/s, turning back every
//! two minutes so that they stay on the database). Every `sample_s` the process's VmRSS and
//! thread count (`/proc/PID/status`) and open descriptors (`/proc/PID/fd`) are read; its
//! `--frame-log` gives every frame's cost.
//!
//! Verdict. From the end of the warm-up (minute 5, or the first third of a run shorter than
//! 15 minutes) to the end, comparing the minute after the warm-up with the last minute (a
//! sixth of the run when shorter; single looks swing by a few percent): the median resident
//! memory grows by at most `rss_growth_max_pct`, the median frame time of the last third is at
//! most 1.25 times that of the first half of the time after the warm-up (frame time does not
//! grow), and the least descriptors and threads in the last minute are no more than the most
//! in the minute after the warm-up (none leaked; a file open for a moment is no leak). A
//! process that ends early ends the soak with its reason. The report carries each sample and each minute's
//! frame-time median.
//!
//! Limits: Linux (`/proc`); one process on the machine's shared cores (the frame times are
//! this machine's, overframing included); the host's clock is this process's.

use crate::channels::{
    costs, database_box, flight_script, free_port, inside, paced, read_frame_log, serve_args,
    unix_now_s, Host, Scratch, ServeProcess,
};
use crate::report::{date_utc, machine, median, percentile, ProcStatus};
use crate::{require, BenchError, Report, Step};
use cig_net::{BindTarget, Delivery, EndpointConfig, UdpEndpoint};
use cig_tools::dis::{EntitySender, SendSpec};
use rand::{Rng, SeedableRng};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What `cig bench soak` runs.
#[derive(Clone, Debug)]
pub struct SoakOptions {
    /// The `cig` binary (`cig serve`).
    pub cig_exe: PathBuf,
    pub db: PathBuf,
    /// Length of the run.
    pub minutes: f64,
    /// Frame size, pixels.
    pub size_px: (u32, u32),
    /// Host frames a second (and the IG's frame rate).
    pub rate_hz: f64,
    /// Dead-reckoned DIS entities of the exercise.
    pub remote_entities: u32,
    /// The eyepoint's speed, m/s.
    pub speed_mps: f64,
    /// Seconds between samples of the process.
    pub sample_s: f64,
    /// The largest growth of resident memory allowed after the warm-up, percent.
    pub rss_growth_max_pct: f64,
    /// Keep the process's frame log, output and scenario in this folder.
    pub keep_dir: Option<PathBuf>,
    pub commit: String,
}

/// One look at the process.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoakSample {
    /// Since the host's first frame, seconds.
    pub t_s: f64,
    pub rss_kib: u64,
    pub threads: u64,
    pub fds: u64,
}

/// The process's resident memory, threads and open descriptors (`None` off Linux or when it
/// has ended).
fn sample_process(pid: u32, t_s: f64) -> Option<SoakSample> {
    let status = ProcStatus::read(&pid.to_string())?;
    let fds = std::fs::read_dir(format!("/proc/{pid}/fd")).ok()?.count() as u64;
    Some(SoakSample {
        t_s,
        rss_kib: status.field("VmRSS:")?,
        threads: status.field("Threads:")?,
        fds,
    })
}

/// A remote entity going back and forth along one line: its two senders (there and back)
/// and the seconds of a leg.
struct RemoteEntity {
    there: EntitySender,
    back: EntitySender,
    leg_s: f64,
}

impl RemoteEntity {
    /// The Entity State at `t_s` seconds.
    fn pdu(&self, t_s: f64, utc_s: f64) -> Result<Vec<u8>, BenchError> {
        let leg = (t_s / self.leg_s).floor();
        let into_leg = t_s - leg * self.leg_s;
        let sender = if (leg as u64).is_multiple_of(2) {
            &self.there
        } else {
            &self.back
        };
        sender
            .pdu(into_leg, utc_s)
            .step("building a remote entity's Entity State")
    }
}

/// `count` entities scattered over the box's middle, seeded.
fn remote_entities(
    bx: [f64; 4],
    count: u32,
    exercise: u8,
) -> Result<Vec<RemoteEntity>, BenchError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x534f_414b);
    let leg_s = 120.0;
    (0..count)
        .map(|i| {
            let at = inside(bx, rng.gen_range(0.25..0.75), rng.gen_range(0.25..0.75));
            let speed = rng.gen_range(4.0..20.0);
            let heading = rng.gen_range(0.0..std::f64::consts::TAU);
            let (east, north) = (speed * heading.sin(), speed * heading.cos());
            let spec = |lat_deg: f64, lon_deg: f64, sign: f64| SendSpec {
                entity: format!("9:99:{}", i + 1),
                entity_type: "1:1:225:1:1:0:0".into(),
                lat_deg,
                lon_deg,
                alt_m: 0.0,
                velocity: Some(format!("{},{},0", sign * east, sign * north)),
                heading_deg: None,
                appearance: None,
                marking: format!("SOAK{i}"),
                force_id: 1,
                exercise,
                dr: 2,
                version: 7,
                count: 1,
                interval_s: 1.0,
            };
            let there = EntitySender::new(spec(at[0], at[1], 1.0)).step("a remote entity")?;
            // The far end of the leg (metres to degrees on the sphere; near enough for a turn).
            let far_lat = at[0] + north * leg_s / 111_320.0;
            let far_lon = at[1] + east * leg_s / (111_320.0 * at[0].to_radians().cos());
            let back = EntitySender::new(spec(far_lat, far_lon, -1.0)).step("a remote entity")?;
            Ok(RemoteEntity { there, back, leg_s })
        })
        .collect()
}

/// The soak's scenario: clouds, three plumes along the route, a storm, the exercise.
fn scenario_toml(bx: [f64; 4], minutes: f64, dis_port: u16, sink_port: u16) -> String {
    let mut text = format!(
        "start_time = \"2026-06-21T16:00:00Z\"\n\
         [[clouds]]\nbase_m = 1800\nthickness_m = 500\ncoverage = 0.5\nwind_speed_mps = 8\nwind_from_deg = 250\n\
         [lightning]\nlat_deg = {:.6}\nlon_deg = {:.6}\nradius_m = 8000\nstrikes_per_minute = 6\n\
         [dis]\nexercise = 1\nport = {dis_port}\ndelivery = \"unicast:127.0.0.1:{sink_port}\"\n",
        inside(bx, 0.5, 0.5)[0],
        inside(bx, 0.5, 0.5)[1],
    );
    for (id, (u, v)) in [(0.3, 0.5), (0.7, 0.4), (0.5, 0.7)].into_iter().enumerate() {
        let at = inside(bx, u, v);
        text.push_str(&format!(
            "[[smoke]]\nid = {}\nlat_deg = {:.6}\nlon_deg = {:.6}\nduration_s = {:.0}\n",
            id + 1,
            at[0],
            at[1],
            minutes * 60.0 + 600.0
        ));
    }
    text
}

/// Figures of one part of the run.
fn part_json(samples: &[SoakSample], frame_ms: &[f64]) -> serde_json::Value {
    let rss: Vec<f64> = samples.iter().map(|s| s.rss_kib as f64).collect();
    serde_json::json!({
        "rss_kib_mean": rss.iter().sum::<f64>() / rss.len().max(1) as f64,
        "frame_ms_median": median(frame_ms),
        "frame_ms_p99": percentile(frame_ms, 0.99),
        "frames": frame_ms.len(),
    })
}

pub fn run(
    options: &SoakOptions,
    progress: &mut dyn FnMut(&SoakSample),
) -> Result<Report, BenchError> {
    require(
        options.minutes.is_finite() && (0.25..=1440.0).contains(&options.minutes),
        || {
            format!(
                "--minutes {} must lie between 0.25 and 1440",
                options.minutes
            )
        },
    )?;
    require(
        options.rate_hz.is_finite() && (1.0..=240.0).contains(&options.rate_hz),
        || format!("--rate-hz {} must lie between 1 and 240", options.rate_hz),
    )?;
    require(options.remote_entities <= 10_000, || {
        format!(
            "--entities {} must be at most 10000",
            options.remote_entities
        )
    })?;
    require(
        options.speed_mps.is_finite() && (0.0..=2000.0).contains(&options.speed_mps),
        || {
            format!(
                "--speed-mps {} must lie between 0 and 2000",
                options.speed_mps
            )
        },
    )?;
    require(
        options.sample_s.is_finite() && (0.1..=600.0).contains(&options.sample_s),
        || {
            format!(
                "--sample-s {} must lie between 0.1 and 600",
                options.sample_s
            )
        },
    )?;
    require(cfg!(target_os = "linux"), || {
        "the soak reads the process from /proc: Linux only".to_string()
    })?;
    let (w, h) = options.size_px;
    let bx = database_box(&options.db)?;
    let dir = Scratch::new(options.keep_dir.as_deref())?;
    let (cigi_port, dis_port) = (free_port()?, free_port()?);
    // The exercise's other side: sends the remote entities, takes the IG's PDUs.
    let exercise = UdpEndpoint::open(EndpointConfig {
        label: "soak exercise",
        bind: BindTarget::Loopback,
        port: 0,
        delivery: Delivery::Unicast,
        destination: Some(std::net::SocketAddr::from(([127, 0, 0, 1], dis_port))),
        queue_limit: 4096,
        reuse_port: false,
    })?;
    let scenario = dir.path().join("soak.toml");
    std::fs::write(
        &scenario,
        scenario_toml(bx, options.minutes, dis_port, exercise.local_addr().port()),
    )
    .step("writing the soak's scenario")?;
    let entities = remote_entities(bx, options.remote_entities, 1)?;
    let script = flight_script(
        bx,
        options.rate_hz,
        u32::MAX,
        options.speed_mps,
        150.0,
        &[(0, [-30.0, 30.0, -22.5, 22.5])],
    );
    let args = serve_args(
        &options.db,
        &scenario,
        options.size_px,
        options.rate_hz,
        cigi_port,
    );
    let mut serve = ServeProcess::spawn(&options.cig_exe, dir.path(), "soak", &args)?;
    let pid = serve.pid();
    let mut host = Host::new(&script, cigi_port)?;
    let started = Instant::now();
    let started_unix_s = unix_now_s();
    let mut samples: Vec<SoakSample> = Vec::new();
    let mut next_sample_s = 0.0;
    let rate = options.rate_hz;
    let mut dis_sent = 0u64;
    let mut drained = Vec::new();
    paced(rate, options.minutes * 60.0, || {
        host.send_frame()?;
        let t_s = started.elapsed().as_secs_f64();
        // Each entity once a second, spread over the second's frames.
        let frame = u64::from(host.frame);
        let per_second = rate.round().max(1.0) as u64;
        for (i, e) in entities.iter().enumerate() {
            if (i as u64) % per_second == frame % per_second {
                let pdu = e.pdu(t_s, unix_now_s())?;
                if exercise.send(&pdu).is_ok() {
                    dis_sent += 1;
                }
            }
        }
        drained.clear();
        exercise.drain(&mut drained);
        if t_s >= next_sample_s {
            next_sample_s += options.sample_s;
            // A process that has ended ends the soak at once.
            if let Some(why) = serve.ended() {
                return Err(BenchError::Scene(why));
            }
            if let Some(s) = sample_process(pid, t_s) {
                progress(&s);
                samples.push(s);
            }
        }
        Ok(())
    })?;
    let host_frames = host.frame;
    drop(host);
    let summary = serve.finish(Duration::from_secs(60))?;
    let frames = read_frame_log(&dir.path().join("soak.frames.jsonl"))?;
    let total_s = options.minutes * 60.0;
    let warm_s = if options.minutes >= 15.0 {
        300.0
    } else {
        total_s / 3.0
    };
    // Frame costs between two times of the run (seconds from the host's first frame).
    let frame_ms_between =
        |from_s: f64, to_s: f64| costs(&frames, started_unix_s + from_s, started_unix_s + to_s);
    let samples_between = |from_s: f64, to_s: f64| -> Vec<SoakSample> {
        samples
            .iter()
            .filter(|s| s.t_s >= from_s && s.t_s < to_s)
            .copied()
            .collect()
    };
    // Memory is compared between windows (a minute, or a sixth of a short run): single looks
    // swing by a few percent with the frame's allocations.
    let window_s = (total_s / 6.0).min(60.0);
    let at_warm = samples_between(warm_s, warm_s + window_s);
    let at_end = samples_between(total_s - window_s, total_s + 1.0);
    if at_warm.is_empty() || at_end.is_empty() {
        return Err(BenchError::Scene(
            "the process could not be sampled after its warm-up and at the end (is --sample-s longer than a sixth of the run?)".into(),
        ));
    }
    let rss_median =
        |s: &[SoakSample]| median(&s.iter().map(|s| s.rss_kib as f64).collect::<Vec<_>>());
    let most = |s: &[SoakSample], f: fn(&SoakSample) -> u64| s.iter().map(f).max().unwrap_or(0);
    let least = |s: &[SoakSample], f: fn(&SoakSample) -> u64| s.iter().map(f).min().unwrap_or(0);
    let (rss_warm_kib, rss_end_kib) = (rss_median(&at_warm), rss_median(&at_end));
    let rss_growth_pct = (rss_end_kib - rss_warm_kib) / rss_warm_kib * 100.0;
    // A leak is more at the end's least than at the warm-up's most (a tile file open for a
    // moment is none).
    let fds = [most(&at_warm, |s| s.fds), least(&at_end, |s| s.fds)];
    let threads = [most(&at_warm, |s| s.threads), least(&at_end, |s| s.threads)];
    let third = total_s / 3.0;
    let after_warm = frame_ms_between(warm_s, warm_s + (total_s - warm_s) / 2.0);
    let last_third = frame_ms_between(total_s - third, total_s + 1.0);
    if after_warm.is_empty() || last_third.is_empty() {
        return Err(BenchError::Scene(format!(
            "the process drew no frame after its warm-up ({}) or in the last third ({})",
            after_warm.len(),
            last_third.len()
        )));
    }
    let frame_time_ratio = median(&last_third) / median(&after_warm);
    let fds_leaked = fds[1] as i64 - fds[0] as i64;
    let threads_leaked = threads[1] as i64 - threads[0] as i64;
    let minutes: Vec<serde_json::Value> = (0..options.minutes.ceil() as u32)
        .map(|m| {
            let ms = frame_ms_between(f64::from(m) * 60.0, f64::from(m + 1) * 60.0);
            serde_json::json!({"minute": m, "frame_ms_median": median(&ms), "frames": ms.len()})
        })
        .collect();
    let passed = rss_growth_pct <= options.rss_growth_max_pct
        && frame_time_ratio <= 1.25
        && fds_leaked <= 0
        && threads_leaked <= 0;
    let json = serde_json::json!({
        "benchmark": "soak",
        "machine": machine(),
        "date": date_utc(),
        "commit": options.commit,
        "db": options.db.display().to_string(),
        "minutes": options.minutes,
        "size": [w, h],
        "rate_hz": rate,
        "speed_mps": options.speed_mps,
        "remote_entities": options.remote_entities,
        "warm_s": warm_s,
        "window_s": window_s,
        "rss_kib_at_warm": rss_warm_kib,
        "rss_kib_end": rss_end_kib,
        "rss_kib_max": samples.iter().map(|s| s.rss_kib).max(),
        "rss_growth_pct": rss_growth_pct,
        "rss_growth_max_pct": options.rss_growth_max_pct,
        "frame_ms_median_after_warm": median(&after_warm),
        "frame_ms_median_last_third": median(&last_third),
        "frame_time_ratio": frame_time_ratio,
        "fds": fds,
        "threads": threads,
        "fds_leaked": fds_leaked,
        "threads_leaked": threads_leaked,
        "thirds": [
            part_json(&samples_between(0.0, third), &frame_ms_between(0.0, third)),
            part_json(&samples_between(third, 2.0 * third), &frame_ms_between(third, 2.0 * third)),
            part_json(&samples_between(2.0 * third, total_s + 1.0), &last_third),
        ],
        "minutes_frame_ms": minutes,
        "samples": samples.iter().map(|s| [s.t_s, s.rss_kib as f64, s.threads as f64, s.fds as f64]).collect::<Vec<_>>(),
        "samples_columns": ["t_s", "rss_kib", "threads", "fds"],
        "host_frames": host_frames,
        "dis_pdus_sent": dis_sent,
        "serve": {
            "frames": summary["frames"],
            "overframes": summary["overframes"],
            "frame_ms_mean": summary["frame_ms_mean"],
            "cigi_datagrams": summary["cigi"]["datagrams"],
            "hat_hot_answered": summary["cigi"]["hat_hot_answered"],
            "remote_entities": summary["dis"]["remote_entities"],
            "entity_states_applied": summary["dis"]["entity_states_applied"],
            "last_frame": summary["last_frame"],
            "effects_live": summary["effects_live"],
        },
        "passed": passed,
    });
    let summary_text = format!(
        "soak of {} min at {w}x{h}, {rate} Hz, {} remote entities: resident memory {:.1} MiB after the warm-up, {:.1} MiB at the end ({rss_growth_pct:+.2} %, at most {} %); \
         frame time {:.2} ms then {:.2} ms (x{frame_time_ratio:.2}, at most 1.25); descriptors {} -> {}, threads {} -> {}: {}",
        options.minutes,
        options.remote_entities,
        rss_warm_kib / 1024.0,
        rss_end_kib / 1024.0,
        options.rss_growth_max_pct,
        median(&after_warm),
        median(&last_third),
        fds[0],
        fds[1],
        threads[0],
        threads[1],
        if passed { "passed" } else { "FAILED" },
    );
    Ok(Report {
        json,
        summary: summary_text,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_can_be_sampled() {
        if cfg!(target_os = "linux") {
            let s = sample_process(std::process::id(), 0.0).expect("sample");
            assert!(s.rss_kib > 100 && s.threads >= 1 && s.fds >= 3, "{s:?}");
            // A file opened is one descriptor more.
            let file = std::fs::File::open("/proc/self/status").expect("open");
            let more = sample_process(std::process::id(), 0.0).expect("sample");
            assert!(more.fds > s.fds, "{} {}", more.fds, s.fds);
            drop(file);
        }
        assert!(sample_process(u32::MAX, 0.0).is_none());
    }

    #[test]
    fn remote_entities_go_back_along_their_line() {
        let bx = [35.9, -121.3, 36.1, -121.1];
        let entities = remote_entities(bx, 3, 1).expect("entities");
        let decode = |pdu: Vec<u8>| match cig_dis::decode_pdu(&pdu).expect("pdu").message {
            cig_dis::DisMessage::EntityState(es) => {
                let l = &es.entity_location;
                glam::DVec3::new(l.x_coordinate, l.y_coordinate, l.z_coordinate)
            }
            other => panic!("{other:?}"),
        };
        for e in &entities {
            // Where a leg ends the next begins: no jump at the turn.
            let end = decode(e.pdu(119.999, 0.0).expect("pdu"));
            let turn = decode(e.pdu(120.0, 0.0).expect("pdu"));
            assert!((end - turn).length() < 5.0, "{}", (end - turn).length());
            // And after two legs it is back where it started.
            let start = decode(e.pdu(0.0, 0.0).expect("pdu"));
            let again = decode(e.pdu(240.0, 0.0).expect("pdu"));
            assert!((start - again).length() < 1.0);
        }
        assert!(cig_ig::Scenario::from_toml(&scenario_toml(bx, 2.0, 3000, 3001)).is_ok());
    }
}
