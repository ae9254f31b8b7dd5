//! `cig bench sea`: the sea's costs (issue 21's targets), each against a baseline of the same
//! run.
//!
//! 1. Updating the wave cascades to a new time on one core, and building the frame's sea for
//!    the renderer from them (`cascade_update_ms`, `sea_frame_ms`: medians of 200 frames, sea
//!    state 5).
//! 2. 1000 height-of-terrain answers over the sea (off the database, the way `cig serve`
//!    answers them: terrain lookup, then the wave surface sampled with its displacement
//!    inverted), against 1000 over the database's land (`hot_1000_ms`, `hot_land_1000_ms`:
//!    medians of 20 batches).
//! 3. A periscope frame (6x, 8 degrees, the head 1.5 m above the sea, looking out to sea away
//!    from the database) at sea state 5 with three ships riding the waves, against the same
//!    view over a flat sea, interleaved, 9 of each after a warm-up (`sea_over_flat`). Frames
//!    are timed from the start of the draw until the image is read back.
//! 4. A ship's motion (`cig_sea::response`): making a hull's response to the sea state 5
//!    waves at one heading and speed (`ship_response_make_ms`, median over the three built-in
//!    hulls at 36 headings, 8 m/s; the IG makes one when a ship's heading or velocity enters
//!    a new step) and a ship's heave, pitch and roll from it each frame (`ship_ride_us`).

use crate::report::{date_utc, machine, median};
use crate::{BenchError, Report};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::{FrameOptions, Renderer};
use cig_scene::{EntityInstance, FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench sea` measures.
#[derive(Clone, Debug)]
pub struct SeaOptions {
    pub db: PathBuf,
    /// Frame size, pixels.
    pub size: (u32, u32),
    pub paging: PagingConfig,
    pub commit: String,
}

/// Late afternoon at the database (UTC; the sun low over the sea west of the western United
/// States, where the demo database lies): glitter in view.
const TIME_ISO: &str = "2026-06-21T23:30:00Z";

fn sea_error(what: &str, e: impl std::fmt::Display) -> BenchError {
    BenchError::Step {
        what: what.into(),
        reason: e.to_string(),
    }
}

pub fn run(options: &SeaOptions) -> Result<Report, BenchError> {
    let size = options.size;
    let database = Arc::new(cig_terrain_io::store::open_database(&options.db)?);
    let grid = database.layout().grid;
    let centre = grid.centre_deg();
    let origin = cig_scene::sea::sea_origin(centre.0, centre.1);
    let time = cig_environment::UtcTime::parse_iso8601(TIME_ISO)?;
    let mut sea = sea_state(5, 250.0)?;
    let mut flat = sea_state(0, 250.0)?;
    let environment = cig_ig::session::EnvironmentState::default();

    // 1. The cascades, and the frame's sea built from them.
    let mut update_ms = Vec::with_capacity(200);
    let mut frame_ms = Vec::with_capacity(200);
    let mut surface = cig_sea::surface::SeaSurface::new(
        &cig_sea::spectrum::SeaConditions::for_sea_state(5, 250.0)
            .map_err(|e| sea_error("the sea", e))?,
        1,
        cig_sea::surface::SurfaceConfig::default(),
    )
    .map_err(|e| sea_error("the sea", e))?;
    for k in 0..200 {
        let t_s = cig_scene::sea::wave_clock_s(time.unix_seconds()) + f64::from(k) / 60.0;
        let started = Instant::now();
        surface
            .update(t_s)
            .map_err(|e| sea_error("the cascades", e))?;
        update_ms.push(started.elapsed().as_secs_f64() * 1e3);
        let started = Instant::now();
        sea.update(
            &environment,
            None,
            origin,
            time.unix_seconds() + f64::from(k) / 60.0,
            &std::collections::BTreeMap::new(),
        )
        .map_err(|e| sea_error("the sea", e))?;
        frame_ms.push(started.elapsed().as_secs_f64() * 1e3);
    }
    let now = sea
        .now()
        .cloned()
        .ok_or_else(|| BenchError::Scene("no sea".into()))?;

    // 4. The ships' responses: made once per hull, heading and velocity, then ridden.
    let waves = surface.linear_waves();
    let hulls = [
        cig_sea::motion::HullParameters::DESTROYER,
        cig_sea::motion::HullParameters::MERCHANT,
        cig_sea::motion::HullParameters::PATROL_CRAFT,
    ];
    let (mut make_ms, mut ride_us, mut kept) = (Vec::new(), Vec::new(), Vec::new());
    let mut ride_checksum = 0.0;
    for i in 0..36_u32 {
        let heading = f64::from(i) * 10.0_f64;
        let velocity = [
            8.0 * heading.to_radians().sin(),
            8.0 * heading.to_radians().cos(),
        ];
        let started = Instant::now();
        let response = cig_sea::response::SeawayResponse::new(
            &hulls[i as usize % hulls.len()],
            &waves,
            heading,
            velocity,
        );
        make_ms.push(started.elapsed().as_secs_f64() * 1e3);
        #[expect(clippy::cast_precision_loss, reason = "a few thousand waves")]
        kept.push(response.wave_count() as f64);
        let started = Instant::now();
        for k in 0..100 {
            let t_s = surface.time_s() + f64::from(k) / 60.0;
            ride_checksum += response
                .motion_at(8.0 * f64::from(k) / 60.0, 0.0, t_s)
                .roll_deg;
        }
        ride_us.push(started.elapsed().as_secs_f64() * 1e6 / 100.0);
    }

    // 2. Height answers over the sea (west of the database) and over its land.
    let cache = Arc::new(TileCache::new(
        Arc::clone(&database),
        options.paging.clone(),
    )?);
    let mut query = QuerySession::new(Arc::clone(&cache));
    let (m_lat, m_lon) = cig_geo::metres_per_degree(centre.0);
    let sea_lon = grid.west_lon_deg - 20_000.0 / m_lon;
    let points: Vec<(f64, f64)> = (0..1000)
        .map(|k| {
            let f = f64::from(k);
            (
                centre.0 + ((f * 0.618_034).fract() - 0.5) * 8000.0 / m_lat,
                sea_lon + ((f * 0.414_214).fract() - 0.5) * 8000.0 / m_lon,
            )
        })
        .collect();
    let land: Vec<(f64, f64)> = points
        .iter()
        .map(|(lat, lon)| (*lat, lon - sea_lon + centre.1))
        .collect();
    let mut hot_ms = Vec::new();
    let mut land_ms = Vec::new();
    let mut checksum = 0.0;
    for _ in 0..20 {
        let started = Instant::now();
        for (lat, lon) in &points {
            checksum += now.hot(&mut query, *lat, *lon, 0.0)?.height_msl_m;
        }
        hot_ms.push(started.elapsed().as_secs_f64() * 1e3);
        let started = Instant::now();
        for (lat, lon) in &land {
            checksum += now.hot(&mut query, *lat, *lon, 0.0)?.height_msl_m;
        }
        land_ms.push(started.elapsed().as_secs_f64() * 1e3);
    }

    // 3. The periscope frame: looking west, out to sea, from 1.5 m above it.
    let geoid = cig_terrain::database::GeoidLookup::new(&database.manifest().geoid);
    let periscope = Periscope {
        head_height_m: 1.5,
        magnification: 6.0,
        heading_deg: 265.0,
        size,
        unix_time_s: time.unix_seconds(),
    };
    let rough = periscope.snapshot(&grid, &geoid, &mut sea)?;
    let calm = periscope.snapshot(&grid, &geoid, &mut flat)?;
    let eye = rough.views[0].eye;
    let gpu = cig_render::Gpu::headless()?;
    let mut renderer = Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
    cache.update(&[eye]);
    cache.wait_idle();
    cig_render::load_for_view(&mut renderer, &cache, &rough, 0, 64)?;
    let frame_options = FrameOptions {
        mesh_budget: usize::MAX,
        ..FrameOptions::default()
    };
    let mut times = [Vec::new(), Vec::new()];
    let mut ships_drawn = 0;
    for round in 0..10 {
        for (k, s) in [&calm, &rough].into_iter().enumerate() {
            let started = Instant::now();
            let (_, stats) =
                cig_render::render_image_with(&mut renderer, &cache, s, 0, frame_options)?;
            let ms = started.elapsed().as_secs_f64() * 1e3;
            ships_drawn = stats.entities_drawn;
            if round > 0 {
                times[k].push(ms);
            }
        }
    }
    let flat_ms = median(&times[0]);
    let sea_ms = median(&times[1]);
    let json = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "adapter": gpu.describe(),
        "database": options.db.display().to_string(),
        "size": [size.0, size.1],
        "cascades": surface.grids().iter().map(|g| [g.tile_m, g.size as f64]).collect::<Vec<_>>(),
        "cascade_update_ms": median(&update_ms),
        "sea_frame_ms": median(&frame_ms),
        "hot_1000_ms": median(&hot_ms),
        "hot_land_1000_ms": median(&land_ms),
        "hot_checksum_m": checksum,
        "periscope_flat_ms": flat_ms,
        "periscope_sea_state_5_ms": sea_ms,
        "ships_drawn": ships_drawn,
        "sea_waves": waves.len(),
        "ship_waves_kept": median(&kept),
        "ship_response_make_ms": median(&make_ms),
        "ship_ride_us": median(&ride_us),
        "ship_ride_checksum_deg": ride_checksum,
        "sea_over_flat": sea_ms / flat_ms,
        "targets": {
            "sea_over_flat": 1.5,
            "cascade_update_ms": 2.0,
            "hot_1000_ms": 1.0,
        },
    });
    let summary = format!(
        "wave cascades: {:.3} ms per update (target <= 2), the frame's sea {:.3} ms\n\
         1000 HOT over the sea: {:.3} ms (target <= 1); over land {:.3} ms\n\
         periscope frame, sea state 5, 3 ships ({ships_drawn} drawn): {sea_ms:.1} ms against a flat sea's {flat_ms:.1} ms: ratio {:.3} (target <= 1.5)\n\
         a ship's response to the sea: made in {:.2} ms ({:.0} of {} waves kept), ridden in {:.1} us a frame",
        median(&update_ms),
        median(&frame_ms),
        median(&hot_ms),
        median(&land_ms),
        sea_ms / flat_ms,
        median(&make_ms),
        median(&kept),
        waves.len(),
        median(&ride_us),
    );
    Ok(Report { json, summary })
}

/// A fully developed sea of WMO sea state `code` with its wind from `wind_from_deg`, seed 1,
/// the open ocean's water.
///
/// # Errors
/// A code outside 0-9.
pub fn sea_state(code: u8, wind_from_deg: f64) -> Result<cig_ig::sea::WorldSea, BenchError> {
    let conditions = cig_sea::spectrum::SeaConditions::for_sea_state(code, wind_from_deg)
        .map_err(|e| sea_error("the sea", e))?;
    Ok(cig_ig::sea::WorldSea::of_conditions(
        Some(conditions),
        cig_ig::sea::Water::of_scenario(None),
        1,
    ))
}

/// A periscope's look out to sea 12 km west of a database (beyond its edge): the head's height
/// above the sea, the magnification, where it looks, the frame and its time.
#[derive(Clone, Copy, Debug)]
pub struct Periscope {
    pub head_height_m: f64,
    pub magnification: f64,
    pub heading_deg: f64,
    pub size: (u32, u32),
    pub unix_time_s: f64,
}

/// The ships a periscope looks at: (model, range m, degrees right of the line of sight,
/// heading).
pub const PERISCOPE_SHIPS: [(&str, f64, f64, f64); 3] = [
    ("patrol_craft", 3000.0, -2.0, 40.0),
    ("merchant", 5500.0, 1.5, 300.0),
    ("destroyer", 8000.0, 0.5, 200.0),
];

impl Periscope {
    /// The frame: the sea (`sea` updated to the time, its plane at the database's centre) and
    /// [`PERISCOPE_SHIPS`] riding its waves.
    ///
    /// # Errors
    /// When the sea cannot be computed or the magnification is out of range.
    pub fn snapshot(
        &self,
        grid: &cig_terrain::GeoGrid,
        geoid: &cig_terrain::database::GeoidLookup,
        sea: &mut cig_ig::sea::WorldSea,
    ) -> Result<FrameSnapshot, BenchError> {
        let (centre_lat, centre_lon) = grid.centre_deg();
        let origin = cig_scene::sea::sea_origin(centre_lat, centre_lon);
        let (_, m_lon) = cig_geo::metres_per_degree(centre_lat);
        let eye_lon = grid.west_lon_deg - 12_000.0 / m_lon;
        let geoid_m = geoid.undulation_m(centre_lat, eye_lon);
        sea.update(
            &cig_ig::session::EnvironmentState::default(),
            None,
            origin,
            self.unix_time_s,
            &std::collections::BTreeMap::new(),
        )
        .map_err(|e| sea_error("the sea", e))?;
        let now = sea
            .now()
            .cloned()
            .ok_or_else(|| BenchError::Scene("no sea".into()))?;
        let level_m = geoid_m + now.draw().level_m;
        let eye = Geodetic::new(centre_lat, eye_lon, level_m + self.head_height_m);
        let fov_deg = cig_sea::periscope::Magnification::new(self.magnification)
            .map_err(|e| sea_error("the periscope", e))?
            .field_of_view_deg();
        let view = View {
            eye,
            orientation: Hpr {
                heading_deg: self.heading_deg,
                pitch_deg: 0.0,
                roll_deg: 0.0,
            },
            fov: FovDeg::from_horizontal(fov_deg, self.size.0, self.size.1),
            width_px: self.size.0,
            height_px: self.size.1,
        };
        let plane = EnuFrame::new(eye);
        let mut snapshot = FrameSnapshot::new(self.unix_time_s, vec![view]);
        for (id, (model, range_m, off_deg, heading_deg)) in (1..).zip(PERISCOPE_SHIPS) {
            let bearing = (self.heading_deg + off_deg).to_radians();
            let at = plane.enu_to_geodetic(glam::DVec3::new(
                range_m * bearing.sin(),
                range_m * bearing.cos(),
                0.0,
            ));
            let mut ship = EntityInstance {
                id,
                model: model.into(),
                position: Geodetic::new(at.lat_deg, at.lon_deg, level_m),
                orientation: Hpr {
                    heading_deg,
                    ..Hpr::default()
                },
                cue_important: false,
                critical_radius_m: None,
            };
            if let Some(hull) = cig_scene::sea::builtin_hull(model) {
                now.ride(&mut ship, &hull, [0.0, 0.0], level_m, None);
            }
            snapshot.entities.push(ship);
        }
        snapshot.sea = Some(Arc::clone(now.draw()));
        Ok(snapshot)
    }
}
