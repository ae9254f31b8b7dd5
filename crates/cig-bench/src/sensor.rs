//! `cig bench sensor`: the thermal sensor channel's costs against the visible channel's, in one
//! run (issue 19's targets).
//!
//! 1. The surface table's spin-up: every material at every standard orientation, stepped over
//!    the two days before the frame's time (`spin_up_s`, the best of three).
//! 2. Advancing the table by one second of simulation time, as the IG does each frame when
//!    the clock has moved that far (`advance_1s_ms`: the median of 200 advances on one core).
//! 3. A frame of the database with 50 vehicles (tanks and trucks, engines running) ahead of the
//!    eye, drawn as the visible channel and as LWIR, interleaved, 9 of each after a warm-up:
//!    the medians and `lwir_over_visible`; the same frame through the night-vision goggle
//!    (issue 20), interleaved with them: `nvg_over_visible`. Frames are timed from the start of
//!    the draw until the image is read back (the same readback for all).
//! 4. Light points: a 640 x 480 night frame of the same place with 10,000 lamps in view
//!    (500 cd, 5 m above the ground on a 100 x 100 grid from 300 m to 3 km ahead) against the
//!    same frame without them, interleaved, 9 of each: `lights_10k_share`, the lamps' share of
//!    the frame without them.

use crate::report::{date_utc, machine, median};
use crate::{require, BenchError, Report};
use cig_geo::Geodetic;
use cig_render::{FrameOptions, Renderer};
use cig_scene::thermal::{SensorView, ThermalScene};
use cig_scene::{EntityInstance, FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use cig_thermal::{
    Aerosol, EntityHeat, EntityThermalInput, IrBand, Orientations, SurfaceTable, ThermalMaterial,
    ThermalWeather,
};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench sensor` measures.
#[derive(Clone, Debug)]
pub struct SensorOptions {
    pub db: PathBuf,
    /// Frame size, pixels.
    pub size: (u32, u32),
    /// Vehicles in the frame.
    pub entities: usize,
    pub paging: PagingConfig,
    pub commit: String,
}

/// The frame's time: mid-afternoon in June at the database (UTC; the sun is up over the
/// western United States, where the demo database lies).
const TIME_ISO: &str = "2026-06-21T22:00:00Z";
/// The light points' frame: 22:00 local, the moon a little past first quarter.
const NIGHT_ISO: &str = "2026-06-22T05:00:00Z";

pub fn run(options: &SensorOptions) -> Result<Report, BenchError> {
    require((1..=1000).contains(&options.entities), || {
        format!("--entities {} must be between 1 and 1000", options.entities)
    })?;
    let size = options.size;
    let database = Arc::new(cig_terrain_io::store::open_database(&options.db)?);
    let grid = database.layout().grid;
    let (lat, lon) = (
        0.5 * (grid.south_lat_deg + grid.north_lat_deg()),
        0.5 * (grid.west_lon_deg + grid.east_lon_deg()),
    );
    let time = cig_environment::UtcTime::parse_iso8601(TIME_ISO)?;

    // 1. Spin-up.
    let mut spin_up_s = f64::INFINITY;
    let mut table = None;
    for _ in 0..3 {
        let started = Instant::now();
        let t = SurfaceTable::spin_up(
            lat,
            lon,
            time,
            ThermalWeather::default(),
            &ThermalMaterial::ALL,
            Orientations::Standard,
        )
        .map_err(|e| BenchError::Scene(format!("the thermal model: {e}")))?;
        spin_up_s = spin_up_s.min(started.elapsed().as_secs_f64());
        table = Some(t);
    }
    let mut table = table.ok_or_else(|| BenchError::Scene("no spin-up ran".into()))?;

    // 2. Advancing by one second.
    let mut advances = Vec::new();
    for i in 1..=200 {
        let started = Instant::now();
        table.advance_to(time.plus_seconds(f64::from(i)));
        advances.push(started.elapsed().as_secs_f64() * 1e3);
    }

    // 3. Frames.
    let cache = Arc::new(TileCache::new(
        Arc::clone(&database),
        options.paging.clone(),
    )?);
    let mut session = QuerySession::new(Arc::clone(&cache));
    let ground = crate::ground_m;
    let (m_lat, m_lon) = cig_geo::metres_per_degree(lat);
    let eye_lat = lat - 1500.0 / m_lat;
    let eye = Geodetic::new(eye_lat, lon, ground(&mut session, eye_lat, lon)? + 60.0);
    let view = View {
        eye,
        orientation: Hpr {
            heading_deg: 0.0,
            pitch_deg: -4.0,
            roll_deg: 0.0,
        },
        fov: FovDeg::from_horizontal(40.0, size.0, size.1),
        width_px: size.0,
        height_px: size.1,
    };
    let mut entities = Vec::new();
    for i in 0..options.entities {
        // Rows of ten across the middle of the view, from 300 m ahead, 120 m apart.
        let row = i / 10;
        let col = i % 10;
        let north = 300.0 + 120.0 * row as f64;
        let east = (col as f64 - 4.5) / 4.5 * 0.8 * north * 20f64.to_radians().tan();
        let (e_lat, e_lon) = (eye_lat + north / m_lat, lon + east / m_lon);
        entities.push(EntityInstance {
            id: i as u32 + 1,
            model: if i % 3 == 2 { "truck" } else { "tank" }.into(),
            position: Geodetic::new(e_lat, e_lon, ground(&mut session, e_lat, e_lon)?),
            orientation: Hpr {
                heading_deg: (i * 37 % 360) as f64,
                ..Hpr::default()
            },
            cue_important: false,
            critical_radius_m: None,
        });
    }
    let heat = EntityHeat::steady(
        &EntityThermalInput {
            engine_on: true,
            speed_mps: 5.0,
            burning: false,
            destroyed: false,
        },
        table.air_k(),
    );
    let scene = Arc::new(ThermalScene::from_table(
        &table,
        cig_scene::thermal::atmosphere_over(&table, Aerosol::Rural, 23_000.0),
        entities
            .iter()
            .map(|e| (e.id, heat.rise_k.map(|r| r as f32)))
            .collect(),
    ));
    let gpu = cig_render::Gpu::headless()?;
    let mut renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    let snapshot = |sensor: Option<SensorView>| {
        let mut s = FrameSnapshot::new(time.unix_seconds(), vec![view]);
        s.entities = entities.clone();
        s.sensors = vec![sensor];
        s.thermal = Some(Arc::clone(&scene));
        s
    };
    let visible = snapshot(None);
    let lwir = snapshot(Some(SensorView::new(IrBand::Lwir)));
    let mut nvg = snapshot(None);
    nvg.nvg = vec![Some(cig_scene::nvg::NvgView::default())];
    cache.update(&[eye]);
    cache.wait_idle();
    cig_render::load_for_view(&mut renderer, &cache, &visible, 0, 64)?;
    let options_frame = FrameOptions {
        mesh_budget: usize::MAX,
        ..FrameOptions::default()
    };
    let mut times = [Vec::new(), Vec::new(), Vec::new()];
    let mut entities_drawn = 0;
    for round in 0..10 {
        for (k, s) in [&visible, &lwir, &nvg].into_iter().enumerate() {
            let started = Instant::now();
            let (_, stats) =
                cig_render::render_image_with(&mut renderer, &cache, s, 0, options_frame)?;
            let ms = started.elapsed().as_secs_f64() * 1e3;
            entities_drawn = stats.entities_drawn;
            // The first round warms the pipelines and caches.
            if round > 0 {
                times[k].push(ms);
            }
        }
    }
    let visible_ms = median(&times[0]);
    let lwir_ms = median(&times[1]);
    let nvg_ms = median(&times[2]);

    // 4. Light points.
    let night = cig_environment::UtcTime::parse_iso8601(NIGHT_ISO)?;
    let lights_view = View {
        fov: FovDeg::from_horizontal(40.0, 640, 480),
        width_px: 640,
        height_px: 480,
        ..view
    };
    let mut lamps = Vec::with_capacity(10_000);
    let warm = cig_scene::lights::named_lamp("warm")
        .ok_or_else(|| BenchError::Scene("no warm lamp".into()))?;
    for row in 0..100 {
        let north = 300.0 + 27.0 * f64::from(row);
        for col in 0..100 {
            let east = (f64::from(col) - 49.5) / 49.5 * 0.9 * north * 20f64.to_radians().tan();
            let (l_lat, l_lon) = (eye_lat + north / m_lat, lon + east / m_lon);
            let at = Geodetic::new(l_lat, l_lon, ground(&mut session, l_lat, l_lon)? + 5.0);
            lamps.push(
                cig_scene::lights::omni_lamp(at, 500.0, warm)
                    .map_err(|e| BenchError::Scene(format!("a lamp: {e}")))?,
            );
        }
    }
    let mut dark = FrameSnapshot::new(night.unix_seconds(), vec![lights_view]);
    dark.culture = false;
    let mut lit = dark.clone();
    lit.lights = lamps;
    cig_render::load_for_view(&mut renderer, &cache, &dark, 0, 64)?;
    let mut light_times = [Vec::new(), Vec::new()];
    let mut lights_drawn = 0;
    for round in 0..10 {
        for (k, s) in [&dark, &lit].into_iter().enumerate() {
            let started = Instant::now();
            let (_, stats) =
                cig_render::render_image_with(&mut renderer, &cache, s, 0, options_frame)?;
            let ms = started.elapsed().as_secs_f64() * 1e3;
            if k == 1 {
                lights_drawn = stats.light_points;
            }
            if round > 0 {
                light_times[k].push(ms);
            }
        }
    }
    let dark_ms = median(&light_times[0]);
    let lit_ms = median(&light_times[1]);
    let lights_share = (lit_ms - dark_ms) / dark_ms;
    let json = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "adapter": gpu.describe(),
        "database": options.db.display().to_string(),
        "size": [size.0, size.1],
        "entities": options.entities,
        "entities_drawn": entities_drawn,
        "materials": ThermalMaterial::ALL.len(),
        "orientations": table.orientations().len(),
        "spin_up_s": spin_up_s,
        "advance_1s_ms": median(&advances),
        "visible_ms": visible_ms,
        "lwir_ms": lwir_ms,
        "lwir_over_visible": lwir_ms / visible_ms,
        "nvg_ms": nvg_ms,
        "nvg_over_visible": nvg_ms / visible_ms,
        "lights_frame_ms": dark_ms,
        "lights_10k_frame_ms": lit_ms,
        "lights_drawn": lights_drawn,
        "lights_10k_share": lights_share,
        "targets": {
            "lwir_over_visible": 1.3,
            "nvg_over_visible": 1.3,
            "lights_10k_share": 0.1,
            "advance_1s_ms": 0.2,
            "spin_up_s": 1.0,
        },
    });
    let summary = format!(
        "LWIR frame {lwir_ms:.1} ms, visible {visible_ms:.1} ms: ratio {:.3} (target <= 1.3)\n\
         table advance by 1 s: {:.4} ms (target <= 0.2); spin-up {spin_up_s:.3} s (target <= 1)\n\
         NVG frame {nvg_ms:.1} ms: ratio {:.3} (target <= 1.3)\n\
         10,000 lamps ({lights_drawn} drawn): {lit_ms:.1} ms against {dark_ms:.1} ms, share {:.3} (target <= 0.1)",
        lwir_ms / visible_ms,
        median(&advances),
        nvg_ms / visible_ms,
        lights_share,
    );
    Ok(Report { json, summary })
}
