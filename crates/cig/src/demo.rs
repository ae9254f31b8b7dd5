//! `cig demo`: builds the demo database when missing, shows the terrain answers and paging a
//! trainer relies on, then flies a scripted flight over it — a low pass through a village and
//! its woods, a climb with the overload control holding a triangle budget,
//! a view at dusk, then the environment: the full moon at night, cumulus from below and above, a
//! thunderstorm with rain, the valley at night through a thermal sight and goggles, and a
//! periscope at sea (1.5x and 6x, three ships in a sea state 4) — rendered off-screen to PNG
//! frames and a contact sheet.

use crate::cli::DemoArgs;
use crate::config::Config;
use anyhow::Context;
use cig_bench::database::demo_params;
use cig_geo::Geodetic;
use cig_terrain::{QuerySession, TileCache};
use cig_terrain_io::store::open_database;
use std::sync::Arc;
use std::time::Instant;

pub fn run(args: &DemoArgs, config: &Config) -> anyhow::Result<()> {
    if !args.db.exists() {
        println!(
            "building the demo database (50 km x 50 km, 30 m posts): {}",
            args.db.display()
        );
        let started = Instant::now();
        crate::db::synthesize_database(
            &demo_params(),
            &cig_synth::SynthOptions::default(),
            &args.db,
            false,
            config,
        )?;
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
    let centre_lat = 0.5 * (g.south_lat_deg + g.north_lat_deg());
    let (north_m_per_deg, east_m_per_deg) = cig_geo::metres_per_degree(centre_lat);
    let (olat, olon) = cig_bench::demo::overwatch(&mut q, &g)?;
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

/// Runs `cig serve` (no drawing) and `cig host` against it over UDP on the loopback for two
/// seconds: a helicopter flown by the host, its height above the terrain asked every frame.
fn cigi_session(args: &DemoArgs, centre: Geodetic) -> anyhow::Result<()> {
    println!("a CIGI 3.3 host flies a helicopter across the database through cig serve (UDP on the loopback):");
    let exe = std::env::current_exe().context("the cig executable")?;
    let (ig_port, host_port) = (cig_net::free_udp_port()?, cig_net::free_udp_port()?);
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

/// The demo's triangle budget for the overload control (a view's frame).
const DEMO_TRIANGLE_BUDGET: f64 = 130_000.0;
/// Frames flown from one climb shot to the next.
const CLIMB_STEPS: u32 = 6;

/// Renders the scripted flight to PNG frames and a contact sheet.
fn fly(
    args: &DemoArgs,
    config: &Config,
    db: &Arc<cig_terrain::TerrainDatabase>,
    q: &mut QuerySession,
) -> anyhow::Result<()> {
    let cig_bench::demo::Flight {
        heading_deg: heading,
        size,
        shots,
    } = cig_bench::demo::flight(q, &db.layout().grid)?;
    let weather = cig_bench::demo::environment_shots(q, &shots, size)?;
    let has_display =
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if has_display && !args.no_window {
        let cache = Arc::new(TileCache::new(Arc::clone(db), config.paging.clone())?);
        // Play the flight faster than real time; then the camera is the user's (Esc closes).
        let script = cig_bench::demo::window_script(&shots);
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
        "flying: a low pass along the valley heading {heading:.0} deg, a climb to 1800 m, dusk; then the full moon, cumulus from below and above, a thunderstorm, the valley at night through a thermal sight, a periscope at sea ({} frames of {}x{} on {})",
        shots.len() + weather.len() + 2,
        size.0,
        size.1,
        gpu.describe()
    );
    let mut renderer = cig_render::Renderer::new(gpu, &cache, cig_render::FRAME_FORMAT);
    config.configure_renderer(&mut renderer)?;
    // The overload control at work: a triangle budget the low pass and the climb over the
    // woods reach (source 004 Table 4); K_LOD falls a step a frame above 95 % of it and
    // rises below 75 %.
    let mut overload = renderer.overload().copied().unwrap_or_default();
    overload.triangles = Some(cig_scene::overload::CounterLimits {
        capacity: DEMO_TRIANGLE_BUDGET,
        begin_decrement: 0.95 * DEMO_TRIANGLE_BUDGET,
        begin_increment: 0.75 * DEMO_TRIANGLE_BUDGET,
    });
    renderer.set_overload(Some(overload))?;
    println!(
        "overload control: {DEMO_TRIANGLE_BUDGET:.0} triangles a frame; the climb is flown in {CLIMB_STEPS} frames between its shots"
    );
    let started = Instant::now();
    let mut frames = Vec::new();
    let clear = cig_bench::demo::clear_skies(&shots);
    let mut previous: Option<cig_scene::FrameSnapshot> = None;
    // A complete frame: the eye's tiles paged in and its meshes built first.
    let draw = |renderer: &mut cig_render::Renderer,
                snapshot: &cig_scene::FrameSnapshot|
     -> anyhow::Result<(cig_render::Image, cig_render::FrameStats)> {
        cache.update(&[snapshot.views[0].eye]);
        cache.wait_idle();
        cig_render::load_for_view(renderer, &cache, snapshot, 0, 64)?;
        Ok(cig_render::render_image(renderer, &cache, snapshot, 0)?)
    };
    for (i, snapshot) in clear.into_iter().chain(weather).enumerate() {
        let Some(view) = snapshot.views.first().copied() else {
            continue;
        };
        // The climb's shots (10 to 17) are reached through frames in between, so the overload
        // control follows the growing view frame by frame as it would in flight.
        if let (true, Some(before)) = ((10..18).contains(&i), &previous) {
            let from = before.views[0].eye;
            for step in 1..CLIMB_STEPS {
                let t = f64::from(step) / f64::from(CLIMB_STEPS);
                let mut between = snapshot.clone();
                between.views[0].eye = Geodetic::new(
                    from.lat_deg + t * (view.eye.lat_deg - from.lat_deg),
                    from.lon_deg + t * (view.eye.lon_deg - from.lon_deg),
                    from.alt_m + t * (view.eye.alt_m - from.alt_m),
                );
                draw(&mut renderer, &between)?;
            }
        }
        let (image, stats) = draw(&mut renderer, &snapshot)?;
        let path = out_dir.join(format!("frame_{i:03}.png"));
        crate::render::write_png(&image, &path)?;
        println!(
            "  {}: {:>8} triangles ({:>7} in {:>6} culture objects), {:>4} nodes, K_LOD {:>4.0} of {:>4.0} ({}), gpu {:6.1} ms",
            path.display(),
            stats.triangles,
            stats.culture_triangles,
            stats.culture_drawn,
            stats.terrain_nodes,
            stats.klod,
            stats.klod_nominal,
            stats.overload,
            stats.gpu_ms
        );
        frames.push(image);
        previous = Some(snapshot);
    }
    // The periscope leg: out to sea west of the database at sea state 4, the head 2 m above
    // the water, sweeping at 1.5x and then looking at 6x, three ships riding the waves.
    renderer.set_overload(None)?;
    let mut sea = cig_bench::sea::sea_state(4, 270.0)?;
    let geoid = cig_terrain::database::GeoidLookup::new(&db.manifest().geoid);
    for (k, magnification) in [1.5, 6.0].into_iter().enumerate() {
        let periscope = cig_bench::sea::Periscope {
            head_height_m: 2.0,
            magnification,
            heading_deg: 265.0,
            size,
            unix_time_s: shots[0].0 + 2.0 * k as f64,
        };
        let snapshot = periscope.snapshot(&db.layout().grid, &geoid, &mut sea)?;
        let (mut image, stats) = draw(&mut renderer, &snapshot)?;
        crate::sea::draw_reticle(&mut image, &snapshot.views[0]);
        let path = out_dir.join(format!("frame_{:03}.png", frames.len()));
        crate::render::write_png(&image, &path)?;
        println!(
            "  {}: periscope {magnification}x, sea state 4, {} ships drawn, gpu {:6.1} ms",
            path.display(),
            stats.entities_drawn,
            stats.gpu_ms
        );
        frames.push(image);
    }
    // Three channels of the low pass's eyepoint (left, centre, right) side by side: the
    // picture runs on across the seams. Their exposure is the natural light's, the same in
    // every channel, as `cig serve --view` channels have it.
    if let Some(low_pass) = cig_bench::demo::clear_skies(&shots).into_iter().nth(2) {
        // One detail for the three (the overload control would step K_LOD between them).
        renderer.set_overload(None)?;
        let mut channels = Vec::new();
        for view in cig_bench::demo::three_channels(&low_pass.views[0]) {
            let mut snapshot = low_pass.clone();
            snapshot.views = vec![view];
            cache.update(&[view.eye]);
            cache.wait_idle();
            cig_render::load_for_view(&mut renderer, &cache, &snapshot, 0, 64)?;
            let (image, _) = cig_render::render_image_with(
                &mut renderer,
                &cache,
                &snapshot,
                0,
                cig_render::FrameOptions {
                    mesh_budget: usize::MAX,
                    adaptation: cig_render::Adaptation::Off,
                    ..cig_render::FrameOptions::default()
                },
            )?;
            channels.push(image);
        }
        let path = out_dir.join("channels.png");
        crate::render::write_png(&cig_bench::demo::side_by_side(&channels), &path)?;
        println!(
            "  three channels of one eyepoint side by side: {}",
            path.display()
        );
    }
    let sheet = cig_bench::demo::contact_sheet(&frames, 6);
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
