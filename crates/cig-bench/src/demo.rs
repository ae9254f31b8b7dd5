//! The demo's scenes: a hilltop for the line-of-sight show, the scripted flight (a low pass
//! along a valley, a climb, views at dusk) and the environment after it (the full moon,
//! cumulus from below and above, a thunderstorm, the valley at night through a thermal
//! sight and through night-vision goggles), and a contact sheet of the frames.
//!
//! Algorithm: the low pass starts 1.2 km short of the database's densest village (the 8 x 8-
//! cell block with the most buildings) when it has culture, else at its centre; its valley is
//! the heading from there whose first 10 km are lowest on average (24 headings, 20 samples
//! each); the hilltop is the highest post within
//! 4 km of the centre (100 m steps), then climbed post by post; the legs follow the terrain
//! ([`crate::flight`]). Limits: fixed times (June 2026) and frame size (480 x 270); a database
//! smaller than the legs (about 10 km from the centre) ends the flight with an error.

use crate::flight::{views_along, Leg};
use crate::BenchError;
use cig_geo::Geodetic;
use cig_scene::{FrameSnapshot, View};
use cig_terrain::{GeoGrid, QuerySession};
use std::sync::Arc;

/// Seconds since 1970 of an ISO 8601 instant.
fn unix_time(text: &str) -> Result<f64, BenchError> {
    Ok(cig_environment::UtcTime::parse_iso8601(text)?.unix_seconds())
}

/// The highest point within 4 km of the database's centre, climbed post by post to the summit
/// itself: an overwatch position. Latitude and longitude, degrees.
///
/// # Errors
/// When a point of the 4 km square is off the database.
pub fn overwatch(q: &mut QuerySession, g: &GeoGrid) -> Result<(f64, f64), BenchError> {
    let (clat, clon) = (
        0.5 * (g.south_lat_deg + g.north_lat_deg()),
        0.5 * (g.west_lon_deg + g.east_lon_deg()),
    );
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
    Ok((olat, olon))
}

/// The heading from the centre whose first 10 km are lowest on average: along a valley.
fn valley_heading(q: &mut QuerySession, centre: Geodetic) -> f64 {
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
    best.0
}

/// The scripted flight: the low pass's heading, the frame size and the shots (UTC seconds
/// since 1970, and the view): 10 of the low pass, 8 of the climb, 6 at dusk.
#[derive(Clone, Debug)]
pub struct Flight {
    /// Heading of the low pass, along the valley, degrees.
    pub heading_deg: f64,
    /// Frame size of every shot, pixels.
    pub size: (u32, u32),
    /// The shots, in flying order.
    pub shots: Vec<(f64, View)>,
}

/// The demo's flight over the database of `g`, from its centre.
///
/// # Errors
/// When a leg leaves the database.
pub fn flight(q: &mut QuerySession, g: &GeoGrid) -> Result<Flight, BenchError> {
    let centre = Geodetic::new(
        0.5 * (g.south_lat_deg + g.north_lat_deg()),
        0.5 * (g.west_lon_deg + g.east_lon_deg()),
        0.0,
    );
    let size = (480, 270);
    // Through the village with the most buildings when the database has culture: the low pass
    // starts 1.2 km short of it, heading along its valley; else along the centre's valley.
    let village = {
        let db = Arc::clone(q.cache().database());
        crate::culture::densest_block_of(&db, cig_terrain::CultureKind::is_building).ok()
    };
    let (start, heading) = match village {
        Some((lat, lon, _)) => {
            let spot = Geodetic::new(lat, lon, 0.0);
            let heading = valley_heading(q, spot);
            let back = cig_geo::EnuFrame::new(spot).enu_to_geodetic(glam::DVec3::new(
                -1200.0 * heading.to_radians().sin(),
                -1200.0 * heading.to_radians().cos(),
                0.0,
            ));
            (Geodetic::new(back.lat_deg, back.lon_deg, 0.0), heading)
        }
        None => (centre, valley_heading(q, centre)),
    };
    let noon = unix_time("2026-06-21T19:30:00Z")?;
    let dusk = unix_time("2026-06-22T03:00:00Z")?;
    let low = Leg {
        start,
        heading_deg: heading,
        speed_mps: 120.0,
        duration_s: 40.0,
        agl_start_m: 40.0,
        agl_end_m: 40.0,
        pitch_deg: -2.0,
    };
    let mut shots: Vec<(f64, cig_scene::View)> = Vec::new();
    // A pass that would leave the database falls back to the centre's valley.
    let low_views = views_along(q, &low, 40.0 / 10.0, 60.0, size).or_else(|_| {
        let heading = valley_heading(q, centre);
        views_along(
            q,
            &Leg {
                start: centre,
                heading_deg: heading,
                ..low
            },
            40.0 / 10.0,
            60.0,
            size,
        )
    })?;
    let heading = low_views
        .first()
        .map_or(heading, |v| v.orientation.heading_deg);
    for v in low_views {
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
    Ok(Flight {
        heading_deg: heading,
        size,
        shots,
    })
}

/// The flight as the window's script, faster than real time: a second per low-pass shot,
/// 1.5 s per climb shot, 2 s per dusk view.
#[must_use]
pub fn window_script(shots: &[(f64, View)]) -> Vec<cig_render::viewer::Shot> {
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
    script
}

/// The flight's frames off-screen: the haze of the low pass; clearer air for the long views of
/// the climb and dusk (the classic fog is as thick aloft as at the ground).
#[must_use]
pub fn clear_skies(shots: &[(f64, View)]) -> Vec<FrameSnapshot> {
    shots
        .iter()
        .enumerate()
        .map(|(i, (time, view))| {
            let mut snapshot = FrameSnapshot::new(*time, vec![*view]);
            let visibility_m = if i < 10 { 30_000.0 } else { 80_000.0 };
            snapshot.fog =
                cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, visibility_m);
            snapshot
        })
        .collect()
}

/// The environment's shots after the flight (off-screen only): the full moon over the valley
/// at night, cumulus seen from under its base and from above it, and a thunderstorm with rain.
/// `shots` are the flight's ([`flight`]); none without them.
///
/// # Errors
/// When the moon's place or the rain cannot be computed.
pub fn environment_shots(
    q: &mut QuerySession,
    shots: &[(f64, cig_scene::View)],
    size: (u32, u32),
) -> Result<Vec<cig_scene::FrameSnapshot>, BenchError> {
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
    let night = unix_time("2026-06-30T08:30:00Z")?;
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
    let storm_time = unix_time("2026-06-22T01:30:00Z")?;
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
    let (bolt, flash_lux, _) = cig_ig::scenes::lightning_bolt(q, &storm_view, 7, 1200.0);
    snapshot.bolts = vec![bolt];
    snapshot.flash_lux = flash_lux;
    out.push(snapshot);
    out.push(thermal_night(q, low, ground_m)?);
    out.push(nvg_night(q, low, ground_m)?);
    for snapshot in &mut out {
        for view in &mut snapshot.views {
            view.width_px = size.0;
            view.height_px = size.1;
        }
    }
    Ok(out)
}

/// Three tanks 300-500 m down the valley ahead of `view`'s eye, on the ground.
fn valley_tanks(
    q: &mut QuerySession,
    view: &cig_scene::View,
    ground_m: f64,
) -> Vec<cig_scene::EntityInstance> {
    let (north_m, east_m) = cig_geo::metres_per_degree(view.eye.lat_deg);
    let heading = view.orientation.heading_deg.to_radians();
    let mut entities = Vec::new();
    for (k, (ahead_m, side_m)) in [(300.0, -25.0), (380.0, 20.0), (480.0, -5.0)]
        .into_iter()
        .enumerate()
    {
        let east = ahead_m * heading.sin() + side_m * heading.cos();
        let north = ahead_m * heading.cos() - side_m * heading.sin();
        let (lat, lon) = (
            view.eye.lat_deg + north / north_m,
            view.eye.lon_deg + east / east_m,
        );
        let alt = q.hot(lat, lon).map_or(ground_m, |h| h.height_ellipsoid_m());
        entities.push(cig_scene::EntityInstance {
            id: k as u32 + 1,
            model: "tank".into(),
            position: Geodetic::new(lat, lon, alt),
            orientation: cig_scene::Hpr {
                heading_deg: view.orientation.heading_deg + 40.0 * k as f64,
                ..cig_scene::Hpr::default()
            },
            cue_important: false,
            critical_radius_m: None,
        });
    }
    entities
}

/// The valley at 22:00 through night-vision goggles (P43, automatic brightness): the same three
/// tanks driving toward the eye with their headlights and tail lights on, the settlements' street and porch lights,
/// and an illumination flare 350 m above the valley 2.5 km ahead, 20 s after it lit.
fn nvg_night(
    q: &mut QuerySession,
    low: cig_scene::View,
    ground_m: f64,
) -> Result<cig_scene::FrameSnapshot, BenchError> {
    let night = unix_time("2026-06-22T05:00:00Z")?;
    let mut view = low;
    view.orientation.pitch_deg = -2.0;
    // Driving toward the eye, headlights on.
    let mut entities = valley_tanks(q, &view, ground_m);
    for (k, e) in entities.iter_mut().enumerate() {
        e.orientation.heading_deg = view.orientation.heading_deg + 170.0 + 10.0 * k as f64;
    }
    let mut snapshot = cig_scene::FrameSnapshot::new(night, vec![view]);
    snapshot.fog = cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, 30_000.0);
    let switches = cig_scene::lights::LightSwitches {
        head: true,
        tail: true,
        ..Default::default()
    };
    for e in &entities {
        cig_scene::lights::entity_lights(
            cig_scene::lights::EntityLightSet::GroundVehicle,
            &switches,
            e.id,
            e.position,
            e.orientation,
            [3.5, 1.8, 1.2],
            &mut snapshot.lights,
        );
    }
    let (north_m, east_m) = cig_geo::metres_per_degree(view.eye.lat_deg);
    let heading = view.orientation.heading_deg.to_radians();
    let (lat, lon) = (
        view.eye.lat_deg + 2500.0 * heading.cos() / north_m,
        view.eye.lon_deg + 2500.0 * heading.sin() / east_m,
    );
    let below = q.hot(lat, lon).map_or(ground_m, |h| h.height_ellipsoid_m());
    let flare = cig_scene::lights::Flare::artillery_155mm(
        Geodetic::new(lat, lon, below + 450.0),
        night - 20.0,
    );
    snapshot.lights.extend(flare.light_at(night, Some(below)));
    snapshot.entities = entities;
    snapshot.nvg = vec![Some(cig_scene::nvg::NvgView::default())];
    Ok(snapshot)
}

/// The valley at night through a long-wave infrared sight (white-hot, automatic gain): three
/// tanks with their engines running 300-500 m down the valley, the river warmer than the
/// fields, the roads holding the day's heat. The surface table is spun up over the two days
/// before, with a clear June day of 12-28 C.
fn thermal_night(
    q: &mut QuerySession,
    low: cig_scene::View,
    ground_m: f64,
) -> Result<cig_scene::FrameSnapshot, BenchError> {
    use cig_thermal::{Aerosol, AirTemperature, EntityThermalInput, IrBand, ThermalWeather};
    let night = unix_time("2026-06-22T09:00:00Z")?;
    let time = cig_environment::UtcTime::from_unix_seconds(night)?;
    let weather = ThermalWeather {
        air: AirTemperature::diurnal_c(12.0, 28.0)
            .map_err(|e| BenchError::Scene(format!("the thermal weather: {e}")))?,
        relative_humidity_pct: 45.0,
        wind_mps: 2.0,
        cloud_cover: 0.0,
        deep_ground_k: None,
    };
    let mut view = low;
    view.orientation.pitch_deg = -4.0;
    let entities = valley_tanks(q, &view, ground_m);
    let ids: Vec<u32> = entities.iter().map(|e| e.id).collect();
    let scene = cig_scene::thermal::still_scene(
        low.eye.lat_deg,
        low.eye.lon_deg,
        ground_m,
        time,
        weather,
        (Aerosol::Rural, 30_000.0),
        &ids,
        &EntityThermalInput {
            engine_on: true,
            speed_mps: 3.0,
            burning: false,
            destroyed: false,
        },
    )
    .map_err(|e| BenchError::Scene(format!("the thermal model: {e}")))?;
    let mut snapshot = cig_scene::FrameSnapshot::new(night, vec![view]);
    snapshot.fog = cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, 30_000.0);
    snapshot.entities = entities;
    snapshot.sensors = vec![Some(cig_scene::thermal::SensorView::new(IrBand::Lwir))];
    snapshot.thermal = Some(Arc::new(scene));
    Ok(snapshot)
}

/// Frames side by side, `columns` to a row, each halved.
#[must_use]
/// Three display channels of one eyepoint: `view`'s eye and orientation, a 90° horizontal
/// field split into equal thirds of its tangent (left, centre, right), each `view`'s size
/// (so each channel has the same pixels per unit of tangent, as one wide view's).
pub fn three_channels(view: &cig_scene::View) -> [cig_scene::View; 3] {
    let third_deg = (1.0f64 / 3.0).atan().to_degrees();
    let half_up_deg = (f64::from(view.height_px) / (3.0 * f64::from(view.width_px)))
        .atan()
        .to_degrees();
    [
        (45.0, -third_deg),
        (third_deg, third_deg),
        (-third_deg, 45.0),
    ]
    .map(|(left, right)| cig_scene::View {
        fov: cig_scene::FovDeg {
            left_deg: left,
            right_deg: right,
            down_deg: half_up_deg,
            up_deg: half_up_deg,
        },
        ..*view
    })
}

/// Frames of equal height side by side, left to right.
pub fn side_by_side(frames: &[cig_render::Image]) -> cig_render::Image {
    let height = frames.iter().map(|f| f.height).min().unwrap_or(1);
    let width: u32 = frames.iter().map(|f| f.width).sum();
    let mut rgba = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height {
        for frame in frames {
            let row = (y * frame.width * 4) as usize;
            if let Some(pixels) = frame.rgba.get(row..row + (frame.width * 4) as usize) {
                rgba.extend_from_slice(pixels);
            }
        }
    }
    cig_render::Image {
        width,
        height,
        rgba,
    }
}

pub fn contact_sheet(frames: &[cig_render::Image], columns: usize) -> cig_render::Image {
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
