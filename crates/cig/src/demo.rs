//! `cig demo`: builds the demo database when missing, shows the terrain answers and paging a
//! trainer relies on, then flies a scripted flight over it — a low pass along a valley, a climb,
//! a view at dusk, then the environment: the full moon at night, cumulus from below and above, a
//! thunderstorm with rain — rendered off-screen to PNG frames and a contact sheet.

use crate::cli::DemoArgs;
use crate::config::Config;
use anyhow::Context;
use cig_geo::Geodetic;
use cig_terrain::{QuerySession, TileCache};
use cig_terrain_io::store::open_database;
use std::sync::Arc;
use std::time::Instant;

/// The demo database: 50 km x 50 km at 30 m posts from near Fort Hunter Liggett, California.
pub fn demo_params() -> cig_synth::SynthParams {
    cig_synth::SynthParams {
        origin_lat_deg: 35.98,
        origin_lon_deg: -121.23,
        size_km: 50.0,
        spacing_m: 30.0,
        seed: 1,
    }
}

pub fn run(args: &DemoArgs, config: &Config) -> anyhow::Result<()> {
    if !args.db.exists() {
        println!(
            "building the demo database (50 km x 50 km, 30 m posts): {}",
            args.db.display()
        );
        let started = Instant::now();
        crate::db::synthesize_database(&demo_params(), &args.db, false, config)?;
        println!("built in {:.1} s", started.elapsed().as_secs_f64());
    }
    crate::db::info(&crate::cli::InfoArgs {
        db: args.db.clone(),
        json: false,
        lod_errors: true,
    })?;
    let db = Arc::new(open_database(&args.db)?);
    let g = db.layout().grid;
    let cache = Arc::new(TileCache::new(Arc::clone(&db), config.paging.clone())?);
    let mut q = QuerySession::new(Arc::clone(&cache));
    let (clat, clon) = (
        0.5 * (g.south_lat_deg + g.north_lat_deg()),
        0.5 * (g.west_lon_deg + g.east_lon_deg()),
    );
    println!();
    println!("height above terrain of a helicopter at 1500 m over five points:");
    for k in 0..5 {
        let f = 0.1 + 0.2 * k as f64;
        let lat = g.south_lat_deg + f * (g.north_lat_deg() - g.south_lat_deg);
        let lon = g.west_lon_deg + (1.0 - f) * (g.east_lon_deg() - g.west_lon_deg);
        let (hat, s) = q.hat(Geodetic::new(lat, lon, 1500.0))?;
        println!(
            "  {lat:.5}, {lon:.5}: ground {:7.1} m MSL, {:<10} HAT {:7.1} m",
            s.height_msl_m,
            s.material.name(),
            hat
        );
    }
    println!();
    // The tank sits on the highest point within 4 km of the centre: an overwatch position.
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(clat);
    let (mut olat, mut olon, mut best) = (clat, clon, f64::NEG_INFINITY);
    for i in -40..=40 {
        for j in -40..=40 {
            let lat = clat + f64::from(i) * 100.0 / north_m_per_deg;
            let lon = clon + f64::from(j) * 100.0 / east_m_per_deg;
            let h = q.height_msl_m(lat, lon)?;
            if h > best {
                (olat, olon, best) = (lat, lon, h);
            }
        }
    }
    // Climb post by post to the summit itself.
    loop {
        let mut next = (olat, olon, best);
        for (di, dj) in [
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, -1),
            (0, 1),
            (1, -1),
            (1, 0),
            (1, 1),
        ] {
            let lat = olat + f64::from(di) * g.dlat_deg;
            let lon = olon + f64::from(dj) * g.dlon_deg;
            if let Ok(h) = q.height_msl_m(lat, lon) {
                if h > next.2 {
                    next = (lat, lon, h);
                }
            }
        }
        if next.2 <= best {
            break;
        }
        (olat, olon, best) = next;
    }
    println!("line of sight from a tank 2 m above a hilltop ({olat:.5}, {olon:.5}), 8 km in 8 directions:");
    let (clat, clon) = (olat, olon);
    let eye_ground = q.hot(clat, clon)?.height_ellipsoid_m();
    for k in 0..8 {
        let az = f64::from(k) * 45.0;
        let lat2 = clat + 8000.0 * az.to_radians().cos() / north_m_per_deg;
        let lon2 = clon + 8000.0 * az.to_radians().sin() / east_m_per_deg;
        let target_ground = q.hot(lat2, lon2)?.height_ellipsoid_m();
        let r = q.los(
            Geodetic::new(clat, clon, eye_ground + 2.0),
            Geodetic::new(lat2, lon2, target_ground + 2.0),
        )?;
        match r.hit {
            None => println!("  azimuth {az:5.1}: target visible"),
            Some(h) => println!(
                "  azimuth {az:5.1}: blocked {:6.0} m out, by {}",
                h.range_m, h.material
            ),
        }
    }
    println!();
    println!("paging while flying west to east at 300 m/s for 150 s (60 Hz updates):");
    let started = Instant::now();
    let mut max_bytes = 0;
    for frame in 0..9000u32 {
        let t_s = f64::from(frame) / 60.0;
        let lon = g.west_lon_deg
            + 0.05 * (g.east_lon_deg() - g.west_lon_deg)
            + 300.0 * t_s / east_m_per_deg;
        let stats = cache.update(&[Geodetic::new(clat, lon.min(g.east_lon_deg()), 1500.0)]);
        max_bytes = max_bytes.max(stats.resident_bytes);
    }
    cache.wait_idle();
    let s = cache.stats();
    println!(
        "  {} tiles loaded, {} evicted, {} area moves; at most {:.1} MiB resident (budget {:.0} MiB); {:.2} s for 9000 updates",
        s.loads_completed,
        s.evictions,
        s.active_area_moves,
        max_bytes as f64 / 1048576.0,
        config.paging.budget_bytes as f64 / 1048576.0,
        started.elapsed().as_secs_f64()
    );
    println!();
    cigi_session(args, Geodetic::new(clat, clon, 0.0))?;
    fly(args, config, &db, &mut q)
}

/// A free UDP port on the loopback (bound, then released).
fn free_port() -> anyhow::Result<u16> {
    Ok(std::net::UdpSocket::bind("127.0.0.1:0")?
        .local_addr()?
        .port())
}

/// Runs `cig serve` (no drawing) and `cig host` against it over UDP on the loopback for two
/// seconds: a helicopter flown by the host, its height above the terrain asked every frame.
fn cigi_session(args: &DemoArgs, centre: Geodetic) -> anyhow::Result<()> {
    println!("a CIGI 3.3 host flies a helicopter across the database through cig serve (UDP on the loopback):");
    let exe = std::env::current_exe().context("the cig executable")?;
    let (ig_port, host_port) = (free_port()?, free_port()?);
    let dir = tempfile::tempdir().context("a temporary folder")?;
    let script = dir.path().join("host.toml");
    let (north, east) = cig_geo::metres_per_degree(centre.lat_deg);
    std::fs::write(
        &script,
        format!(
            "frames = 120\ntime = \"2026-06-21T19:00:00Z\"\n\
             [[entities]]\nid = 0\ntype = 1\nalt_m = 900\nspeed_mps = 80\npath = [[{}, {}], [{}, {}]]\n\
             [view]\nentity = 0\n\
             [[hat]]\nid = 1\nentity = 0\ntype = \"extended\"\nevery_frame = true\n",
            centre.lat_deg,
            centre.lon_deg - 5000.0 / east,
            centre.lat_deg + 2000.0 / north,
            centre.lon_deg + 5000.0 / east,
        ),
    )
    .with_context(|| format!("cannot write {}", script.display()))?;
    let mut serve = std::process::Command::new(&exe)
        .arg("serve")
        .arg("--db")
        .arg(&args.db)
        .args(["--no-render", "--cigi-port", &ig_port.to_string()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .context("starting cig serve")?;
    // The IG opens its database and binds its port; the host's early frames may be lost.
    std::thread::sleep(std::time::Duration::from_millis(300));
    let host = std::process::Command::new(&exe)
        .arg("host")
        .arg("--script")
        .arg(&script)
        .args(["--ig", &format!("127.0.0.1:{ig_port}")])
        .args(["--port", &host_port.to_string(), "--json"])
        .output()
        .context("running cig host");
    let _ = serve.kill();
    let _ = serve.wait();
    let host = host?;
    let text = String::from_utf8_lossy(&host.stdout);
    let lines: Vec<serde_json::Value> = text
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    let hats: Vec<f64> = lines
        .iter()
        .filter(|v| v["packet"] == "hat_hot_extended" && v["valid"] == true)
        .filter_map(|v| v["hat_m"].as_f64())
        .collect();
    match lines.iter().find_map(|v| v.get("summary")) {
        Some(summary) if !hats.is_empty() => {
            let lo = hats.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = hats.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            println!(
                "  {} host frames, {} Start of Frame, {} HAT/HOT answers (latency {:.1} host frames on average); height above terrain {lo:.0}-{hi:.0} m",
                summary["frames_sent"], summary["start_of_frames"], hats.len(),
                summary["latency_frames_mean"].as_f64().unwrap_or(0.0)
            );
        }
        _ => println!(
            "  the IG did not answer ({})",
            String::from_utf8_lossy(&host.stderr)
                .lines()
                .last()
                .unwrap_or("no message")
        ),
    }
    println!();
    Ok(())
}

/// The heading from the centre whose first 10 km are lowest on average: along a valley.
fn valley_heading(q: &mut QuerySession, centre: Geodetic) -> anyhow::Result<f64> {
    let frame = cig_geo::EnuFrame::new(centre);
    let mut best = (0.0, f64::INFINITY);
    for k in 0..24 {
        let heading = f64::from(k) * 15.0;
        let (s, c) = heading.to_radians().sin_cos();
        let mut sum = 0.0;
        for step in 1..=20 {
            let d = f64::from(step) * 500.0;
            let p = frame.enu_to_geodetic(glam::DVec3::new(s * d, c * d, 0.0));
            sum += q.height_msl_m(p.lat_deg, p.lon_deg).unwrap_or(1e9);
        }
        if sum < best.1 {
            best = (heading, sum);
        }
    }
    Ok(best.0)
}

/// Renders the scripted flight to PNG frames and a contact sheet.
fn fly(
    args: &DemoArgs,
    config: &Config,
    db: &Arc<cig_terrain::TerrainDatabase>,
    q: &mut QuerySession,
) -> anyhow::Result<()> {
    use crate::flight::{views_along, Leg};
    let g = db.layout().grid;
    let centre = Geodetic::new(
        0.5 * (g.south_lat_deg + g.north_lat_deg()),
        0.5 * (g.west_lon_deg + g.east_lon_deg()),
        0.0,
    );
    let heading = valley_heading(q, centre)?;
    let size = (480, 270);
    let noon = crate::render::parse_time("2026-06-21T19:30:00Z")?;
    let dusk = crate::render::parse_time("2026-06-22T03:00:00Z")?;
    let low = Leg {
        start: centre,
        heading_deg: heading,
        speed_mps: 120.0,
        duration_s: 40.0,
        agl_start_m: 40.0,
        agl_end_m: 40.0,
        pitch_deg: -2.0,
    };
    let mut shots: Vec<(f64, cig_scene::View)> = Vec::new();
    for v in views_along(q, &low, 40.0 / 10.0, 60.0, size)? {
        shots.push((noon, v));
    }
    let end = shots.last().map(|s| s.1.eye).unwrap_or(centre);
    let climb = Leg {
        start: Geodetic::new(end.lat_deg, end.lon_deg, 0.0),
        heading_deg: heading + 30.0,
        speed_mps: 80.0,
        duration_s: 60.0,
        agl_start_m: 60.0,
        agl_end_m: 1800.0,
        pitch_deg: -12.0,
    };
    let climb_views = views_along(q, &climb, 60.0 / 8.0, 60.0, size)?;
    for v in &climb_views {
        shots.push((noon, *v));
    }
    let mut last = *climb_views.last().unwrap_or(&shots[0].1);
    for k in 0..6 {
        last.orientation.heading_deg = heading + 180.0 + f64::from(k) * 30.0;
        last.orientation.pitch_deg = -10.0;
        shots.push((dusk + f64::from(k) * 240.0, last));
    }
    let weather = environment_shots(q, &shots, size)?;
    let has_display =
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if has_display && !args.no_window {
        let cache = Arc::new(TileCache::new(Arc::clone(db), config.paging.clone())?);
        // Play the flight faster than real time: a second per low-pass shot, 1.5 s per climb
        // shot, 2 s per dusk view; then the camera is the user's (Esc closes).
        let mut script = Vec::with_capacity(shots.len());
        let mut at_s = 0.0;
        for (i, (time, view)) in shots.iter().enumerate() {
            script.push(cig_render::viewer::Shot {
                at_s,
                eye: view.eye,
                orientation: view.orientation,
                unix_time_s: *time,
            });
            at_s += if i < 10 {
                1.0
            } else if i < 18 {
                1.5
            } else {
                2.0
            };
        }
        let first = shots[0].1;
        let mut options = cig_render::ViewerOptions::new(first.eye, first.orientation);
        options.title = "cig demo".into();
        options.unix_time_s = shots[0].0;
        options.visibility_m = 30_000.0;
        options.script = script;
        options.exit_after_frames = args.exit_after_frames;
        println!(
            "flying in a window: a low pass along the valley heading {heading:.0} deg, a climb to 1800 m, dusk (Esc closes)"
        );
        match cig_render::run_viewer(cache, options) {
            Ok(report) => {
                println!("{} frames in {:.1} s", report.frames, report.seconds);
                return Ok(());
            }
            Err(cig_render::ViewerError::NoDisplay(reason)) => {
                println!("no usable display ({reason}): rendering to PNG files instead");
            }
            Err(e) => return Err(e.into()),
        }
    }
    let out_dir = args.out.clone();
    std::fs::create_dir_all(&out_dir)
        .with_context(|| format!("cannot create {}", out_dir.display()))?;
    let cache = Arc::new(TileCache::new(Arc::clone(db), config.paging.clone())?);
    let gpu = cig_render::Gpu::headless()?;
    println!(
        "flying: a low pass along the valley heading {heading:.0} deg, a climb to 1800 m, dusk; then the full moon, cumulus from below and above, a thunderstorm ({} frames of {}x{} on {})",
        shots.len() + weather.len(),
        size.0,
        size.1,
        gpu.describe()
    );
    let mut renderer = cig_render::Renderer::new(gpu, &cache, cig_render::FRAME_FORMAT);
    let started = Instant::now();
    let mut frames = Vec::new();
    let clear = shots
        .iter()
        .enumerate()
        .map(|(i, (time, view))| {
            let mut snapshot = cig_scene::FrameSnapshot::new(*time, vec![*view]);
            // The haze of the low pass; clearer air for the long views of the climb and dusk
            // (the classic fog is as thick aloft as at the ground).
            let visibility_m = if i < 10 { 30_000.0 } else { 80_000.0 };
            snapshot.fog =
                cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, visibility_m);
            snapshot
        })
        .collect::<Vec<_>>();
    for (i, snapshot) in clear.into_iter().chain(weather).enumerate() {
        let Some(view) = snapshot.views.first() else {
            continue;
        };
        cache.update(&[view.eye]);
        cache.wait_idle();
        cig_render::load_for_view(&mut renderer, &cache, &snapshot, 0, 64)?;
        let (image, stats) = cig_render::render_image(&mut renderer, &cache, &snapshot, 0)?;
        let path = out_dir.join(format!("frame_{i:03}.png"));
        crate::render::write_png(&image, &path)?;
        println!(
            "  {}: {:>8} triangles, {:>4} nodes, gpu {:6.1} ms",
            path.display(),
            stats.triangles,
            stats.terrain_nodes,
            stats.gpu_ms
        );
        frames.push(image);
    }
    let sheet = contact_sheet(&frames, 6);
    let sheet_path = out_dir.join("contact-sheet.png");
    crate::render::write_png(&sheet, &sheet_path)?;
    println!(
        "{} frames in {:.1} s; contact sheet: {}",
        frames.len(),
        started.elapsed().as_secs_f64(),
        sheet_path.display()
    );
    Ok(())
}

/// The environment's shots after the flight (off-screen only): the full moon over the valley
/// at night, cumulus seen from under its base and from above it, and a thunderstorm with rain.
fn environment_shots(
    q: &mut QuerySession,
    shots: &[(f64, cig_scene::View)],
    size: (u32, u32),
) -> anyhow::Result<Vec<cig_scene::FrameSnapshot>> {
    use cig_environment::clouds::{CloudKind, CloudLayer};
    let (Some(low), Some(high)) = (shots.first().map(|s| s.1), shots.get(17).map(|s| s.1)) else {
        return Ok(Vec::new());
    };
    let ground_m = q
        .hot(low.eye.lat_deg, low.eye.lon_deg)
        .map_or(0.0, |g| g.height_ellipsoid_m());
    let origin = cig_environment::CloudOrigin {
        lat_deg: low.eye.lat_deg.round(),
        lon_deg: low.eye.lon_deg.round(),
    };
    let fog = |visibility_m: f64| {
        cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, visibility_m)
    };
    let with_clouds = |snapshot: &mut cig_scene::FrameSnapshot, layers: Vec<CloudLayer>| {
        snapshot.cloud_cover_fraction = cig_environment::cloud_cover_fraction(&layers);
        snapshot.cloud_layers = layers;
        snapshot.cloud_origin = origin;
    };
    let mut out = Vec::new();
    // Night: the full moon of 29 June 2026, high over the valley in the small hours.
    let night = crate::render::parse_time("2026-06-30T08:30:00Z")?;
    let moon = cig_environment::ephemeris(
        &cig_environment::Observer::new(low.eye.lat_deg, low.eye.lon_deg, low.eye.alt_m)?,
        cig_environment::UtcTime::from_unix_seconds(night)?,
    )
    .moon;
    let mut view = high;
    view.orientation.heading_deg = moon.azimuth_deg;
    view.orientation.pitch_deg = (moon.apparent_altitude_deg - 12.0).clamp(-10.0, 60.0);
    let mut snapshot = cig_scene::FrameSnapshot::new(night, vec![view]);
    snapshot.fog = fog(30_000.0);
    out.push(snapshot);
    // Cumulus 1200 m above the valley floor drifting in a 10 m/s westerly: from under it,
    // and from above it at the climb's end.
    let cumulus = CloudLayer {
        wind_speed_mps: 10.0,
        wind_from_deg: 270.0,
        ..CloudLayer::new(ground_m + 1200.0, 700.0, 0.45, CloudKind::Cumulus)
    };
    let day = shots[0].0;
    let mut view = low;
    view.orientation.pitch_deg = 12.0;
    let mut snapshot = cig_scene::FrameSnapshot::new(day, vec![view]);
    snapshot.fog = fog(30_000.0);
    with_clouds(&mut snapshot, vec![cumulus]);
    out.push(snapshot);
    let mut view = high;
    view.eye.alt_m = view.eye.alt_m.max(ground_m + 2600.0);
    view.orientation.pitch_deg = -20.0;
    let mut snapshot = cig_scene::FrameSnapshot::new(day + 60.0, vec![view]);
    snapshot.fog = fog(30_000.0);
    with_clouds(&mut snapshot, vec![cumulus]);
    out.push(snapshot);
    // A thunderstorm late in the afternoon: overcast stratus, 8 mm/h of rain, a bolt 1.2 km ahead.
    let storm_time = crate::render::parse_time("2026-06-22T01:30:00Z")?;
    let rain = cig_environment::Precipitation::new(cig_environment::PrecipitationKind::Rain, 8.0)?;
    let mut storm_view = low;
    storm_view.orientation.pitch_deg = 6.0;
    let mut snapshot = cig_scene::FrameSnapshot::new(storm_time, vec![storm_view]);
    snapshot.fog = fog(rain.combined_visibility_m(20_000.0));
    snapshot.precipitation = Some(cig_scene::PrecipitationDraw {
        precipitation: rain,
        wind_en_mps: [4.0, 0.0],
        seed: 1,
    });
    with_clouds(
        &mut snapshot,
        vec![CloudLayer::new(
            ground_m + 900.0,
            1200.0,
            1.0,
            CloudKind::Stratus,
        )],
    );
    let (bolt, flash_lux, _) = crate::render::lightning_bolt(q, &storm_view, 7, 1200.0);
    snapshot.bolts = vec![bolt];
    snapshot.flash_lux = flash_lux;
    out.push(snapshot);
    for snapshot in &mut out {
        for view in &mut snapshot.views {
            view.width_px = size.0;
            view.height_px = size.1;
        }
    }
    Ok(out)
}

/// Frames side by side, `columns` to a row, each halved.
fn contact_sheet(frames: &[cig_render::Image], columns: usize) -> cig_render::Image {
    let (fw, fh) = frames
        .first()
        .map_or((1, 1), |f| ((f.width / 2).max(1), (f.height / 2).max(1)));
    let rows = frames.len().div_ceil(columns).max(1);
    let (w, h) = (fw * columns as u32, fh * rows as u32);
    let mut rgba = vec![0u8; (w * h * 4) as usize];
    for (k, frame) in frames.iter().enumerate() {
        let (ox, oy) = ((k % columns) as u32 * fw, (k / columns) as u32 * fh);
        for y in 0..fh {
            for x in 0..fw {
                let src = (((2 * y).min(frame.height - 1) * frame.width
                    + (2 * x).min(frame.width - 1))
                    * 4) as usize;
                let dst = (((oy + y) * w + ox + x) * 4) as usize;
                if let (Some(s), Some(d)) =
                    (frame.rgba.get(src..src + 4), rgba.get_mut(dst..dst + 4))
                {
                    d.copy_from_slice(s);
                }
            }
        }
    }
    cig_render::Image {
        width: w,
        height: h,
        rgba,
    }
}
