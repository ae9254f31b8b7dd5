//! The sea in the IG's world: height of terrain over water is the wave surface at that time
//! (material water, the wave's normal), the host's Maritime Surface Conditions and Wave
//! Control drive it and the Environmental Conditions response reports them, ships float on the
//! same waves on two IGs (their own and the DIS exercise's), harder in a rougher sea.

use cig_cigi::{
    decode_message, encode_message, ByteOrder, EnvironmentalConditionsRequest,
    EnvironmentalRegionControl, HatHotRequest, IgControl, MaritimeSurfaceConditionsControl,
    Message, Packet, Version, WaveControl,
};
use cig_effects::EffectsConfig;
use cig_environment::UtcTime;
use cig_geo::{EnuFrame, Geodetic};
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_scene::lighting::FogMode;
use cig_scene::{FovDeg, Hpr, View};
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::sync::Arc;

const SOUTH: f64 = 36.0;
const WEST: f64 = -121.0;
const GEOID_M: f32 = 12.0;
const SPACING_M: f64 = 60.0;

/// 65 x 65 posts 60 m apart: the western half sea (water posts at 0 m MSL), the eastern half
/// land at 20 m.
fn query() -> QuerySession {
    database(SPACING_M, 32)
}

/// 65 x 65 posts `spacing_m` apart: the western `sea_columns` sea (water posts at 0 m MSL),
/// the rest land at 20 m.
fn database(spacing_m: f64, sea_columns: usize) -> QuerySession {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    let grid = GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: spacing_m / n,
        dlon_deg: spacing_m / e,
        rows: 65,
        cols: 65,
    };
    let sea = |k: usize| k % grid.cols < sea_columns;
    let raster = Raster {
        grid,
        elevation_m: (0..grid.len())
            .map(|k| if sea(k) { 0.0 } else { 20.0 })
            .collect(),
        material: Some(
            (0..grid.len())
                .map(|k| {
                    if sea(k) {
                        Material::Water
                    } else {
                        Material::Grass
                    }
                })
                .collect(),
        ),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 64, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = GEOID_M);
    let manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    let cache = TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache");
    QuerySession::new(Arc::new(cache))
}

fn at_post(row: f64, col: f64) -> (f64, f64) {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    (SOUTH + row * SPACING_M / n, WEST + col * SPACING_M / e)
}

fn world_with(scenario: &str, join_exercise: bool) -> IgWorld {
    IgWorld::new(
        Scenario::from_toml(scenario).expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise,
        },
    )
    .expect("world")
}

fn send(world: &mut IgWorld, frame: u32, packets: Vec<Packet>) {
    let mut all = vec![Packet::IgControl(IgControl {
        ig_mode: 1,
        host_frame_number: frame,
        ..IgControl::default()
    })];
    all.extend(packets);
    let mut bytes = Vec::new();
    encode_message(
        &Message::new(Version::V3_3, ByteOrder::LittleEndian, all),
        &mut bytes,
    )
    .expect("encode");
    world.receive_cigi(&bytes).expect("accepted");
}

fn frame(world: &mut IgWorld, q: &mut QuerySession) -> Message {
    world.step(1.0 / 60.0, q);
    let message = world.host_message(q, 1234);
    let mut bytes = Vec::new();
    encode_message(&message, &mut bytes).expect("encode");
    decode_message(&bytes).expect("decode")
}

fn hot_request(id: u16, (lat, lon): (f64, f64)) -> Packet {
    Packet::HatHotRequest(HatHotRequest {
        hat_hot_id: id,
        request_type: 2,
        lat_deg_or_x_m: lat,
        lon_deg_or_y_m: lon,
        alt_m_or_z_m: 100.0,
        ..HatHotRequest::default()
    })
}

/// The extended HAT/HOT answers of a message: (id, valid, hot, material, normal elevation).
fn hot_answers(m: &Message) -> Vec<(u16, bool, f64, u32, f32)> {
    m.packets
        .iter()
        .filter_map(|p| match p {
            Packet::HatHotExtendedResponse(r) => Some((
                r.hat_hot_id,
                r.valid,
                r.hot_m,
                r.material_code,
                r.normal_elevation_deg,
            )),
            _ => None,
        })
        .collect()
}

/// The sea's own height above MSL at a point (the surface the renderer's grids hold).
fn sea_height_msl(world: &IgWorld, (lat, lon): (f64, f64), level_m: f64) -> f64 {
    let sea = world.sea().expect("a sea");
    let at = EnuFrame::new(sea.draw().origin).geodetic_to_enu(Geodetic::new(lat, lon, 0.0));
    level_m + sea.surface().sample(at.x, at.y).height_m
}

#[test]
fn height_of_terrain_over_the_sea_is_the_wave_surface_and_land_keeps_the_terrain() {
    let mut q = query();
    let mut w = world_with("[sea]\nsea_state = 5\nlevel_m = 0.4\n", false);
    let water = at_post(30.0, 10.0);
    let off_database = (SOUTH - 0.02, WEST - 0.02);
    let land = at_post(30.0, 50.0);
    let mut heights = Vec::new();
    for k in 0..4u32 {
        send(
            &mut w,
            k,
            vec![
                hot_request(1, water),
                hot_request(2, off_database),
                hot_request(3, land),
            ],
        );
        // A second between the questions: the waves move.
        for _ in 0..59 {
            w.step(1.0 / 60.0, &mut q);
        }
        let reply = frame(&mut w, &mut q);
        let answers = hot_answers(&reply);
        assert_eq!(answers.len(), 3, "{answers:?}");
        for (id, valid, hot, material, elevation) in answers {
            assert!(valid, "request {id} unanswered");
            match id {
                1 | 2 => {
                    let point = if id == 1 { water } else { off_database };
                    let expected = sea_height_msl(&w, point, 0.4);
                    assert!(
                        (hot - expected).abs() < 1e-3,
                        "request {id}: {hot} against the sea's {expected}"
                    );
                    assert_eq!(material, u32::from(Material::Water.to_byte()));
                    // A sea state 5 (Hs 2.5-4 m) is not flat: the waves tilt the normal.
                    assert!(elevation < 89.99, "request {id}: elevation {elevation}");
                    if id == 1 {
                        heights.push(hot);
                    }
                }
                _ => assert!((hot - 20.0).abs() < 1e-3, "land: {hot}"),
            }
        }
    }
    let spread = heights.iter().copied().fold(f64::MIN, f64::max)
        - heights.iter().copied().fold(f64::MAX, f64::min);
    assert!(spread > 0.05, "the sea at one point over 4 s: {heights:?}");
    assert!(heights.iter().all(|h| (h - 0.4).abs() < 5.0), "{heights:?}");
}

#[test]
fn the_hosts_maritime_conditions_and_waves_make_and_drive_the_sea() {
    let mut q = query();
    let mut w = world_with("", false);
    let water = at_post(30.0, 10.0);
    // No scenario sea and nothing from the host: no sea; off the database nothing answers.
    send(&mut w, 0, vec![hot_request(1, (SOUTH - 0.02, WEST - 0.02))]);
    let reply = frame(&mut w, &mut q);
    assert!(w.sea().is_none());
    assert!(
        !hot_answers(&reply)[0].1,
        "answered off the database without a sea"
    );
    let maritime = |scope: u8, id: u16, height: f32| {
        Packet::MaritimeSurfaceConditionsControl(MaritimeSurfaceConditionsControl {
            entity_or_region_id: id,
            surface_conditions_enable: true,
            whitecap_enable: true,
            scope,
            sea_surface_height_m: height,
            surface_water_temperature_c: 9.0,
            surface_clarity_pct: 40.0,
        })
    };
    let wave = |id: u8, height: f32| {
        Packet::WaveControl(WaveControl {
            wave_id: id,
            wave_enable: true,
            height_m: height,
            wavelength_m: 80.0,
            period_s: 7.2,
            direction_deg: 90.0,
            ..WaveControl::default()
        })
    };
    send(&mut w, 1, vec![maritime(0, 0, 1.5), wave(1, 2.0)]);
    frame(&mut w, &mut q);
    let sea = w.sea().expect("the host's sea");
    assert_eq!(sea.surface().explicit_waves().len(), 1);
    assert!((sea.draw().level_m - 1.5).abs() < 1e-6);
    // Calm wind sea plus the host's 2 m swell: the heights along a wavelength span it.
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    let mut heights = Vec::new();
    for k in 0..16 {
        let point = (water.0, water.1 + f64::from(k) * 5.0 / e);
        heights.push(sea_height_msl(&w, point, 1.5));
    }
    let (lo, hi) = (
        heights.iter().copied().fold(f64::MAX, f64::min),
        heights.iter().copied().fold(f64::MIN, f64::max),
    );
    assert!(
        (hi - lo - 2.0).abs() < 0.3 && (0.5 * (hi + lo) - 1.5).abs() < 0.3,
        "{heights:?}"
    );
    // The environmental response reports the host's water, and a region's inside it.
    let region_centre = at_post(20.0, 10.0);
    send(
        &mut w,
        2,
        vec![
            Packet::EnvironmentalRegionControl(EnvironmentalRegionControl {
                region_id: 7,
                region_state: 1,
                latitude_deg: region_centre.0,
                longitude_deg: region_centre.1,
                size_x_m: 600.0,
                size_y_m: 600.0,
                ..EnvironmentalRegionControl::default()
            }),
            maritime(1, 7, -1.0),
            Packet::EnvironmentalConditionsRequest(EnvironmentalConditionsRequest {
                request_type: 1,
                request_id: 3,
                latitude_deg: water.0,
                longitude_deg: water.1,
                altitude_m: 0.0,
            }),
            Packet::EnvironmentalConditionsRequest(EnvironmentalConditionsRequest {
                request_type: 1,
                request_id: 4,
                latitude_deg: region_centre.0,
                longitude_deg: region_centre.1,
                altitude_m: 0.0,
            }),
            hot_request(5, region_centre),
            // Out of the sea's range: clamped and told.
            wave(2, 99.0),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let responses: Vec<(u8, f32, f32, f32)> = reply
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::MaritimeSurfaceConditionsResponse(r) => Some((
                r.request_id,
                r.sea_surface_height_m,
                r.surface_water_temperature_c,
                r.surface_clarity_pct,
            )),
            _ => None,
        })
        .collect();
    assert_eq!(responses, vec![(3, 1.5, 9.0, 40.0), (4, -1.0, 9.0, 40.0)]);
    let hot = hot_answers(&reply)[0].2;
    let expected = sea_height_msl(&w, region_centre, -1.0);
    assert!((hot - expected).abs() < 1e-3, "{hot} against {expected}");
    let told: Vec<String> = reply
        .packets
        .iter()
        .filter_map(|p| match p {
            Packet::ImageGeneratorMessage(m) => Some(m.text.clone()),
            _ => None,
        })
        .collect();
    assert!(
        told.iter()
            .any(|t| t.contains("Wave Control 2") && t.contains("clamped")),
        "{told:?}"
    );
    assert_eq!(w.sea().expect("sea").surface().explicit_waves().len(), 2);
    let _ = n;
}

const SHIP: &str = r#"
start_time = "2026-06-21T12:00:00Z"
[sea]
sea_state = SEA_STATE
[[models]]
model = "ship"
dis_type = "1:3:*:*"
[[entities]]
id = 1
model = "ship"
dis_id = "1:3001:1"
dis_type = "1:3:225:6:1:0:0"
lat_deg = LAT
lon_deg = LON
heading_deg = 30
clamp = "height_and_attitude"
[dis]
site = 1
application = 3001
exercise = 4
time_master = true
"#;

fn ship_scenario(sea_state: u8) -> String {
    let (lat, lon) = at_post(32.0, 12.0);
    SHIP.replace("SEA_STATE", &sea_state.to_string())
        .replace("LAT", &lat.to_string())
        .replace("LON", &lon.to_string())
}

/// The ship's heave above the mean level (metres), pitch and roll (degrees).
fn ship_motion(w: &IgWorld) -> [f64; 3] {
    let pose = w.session().poses()[&1];
    [
        pose.position.alt_m - f64::from(GEOID_M),
        pose.orientation.pitch_deg,
        pose.orientation.roll_deg,
    ]
}

#[test]
fn a_ship_rides_the_same_waves_on_two_igs_and_harder_in_a_rougher_sea() {
    let run = |sea_state: u8, dt_s: f64, seconds: f64| {
        let mut q = query();
        let mut w = world_with(&ship_scenario(sea_state), false);
        let mut samples = Vec::new();
        let steps = (seconds / dt_s).round() as usize;
        for k in 1..=steps {
            w.step(dt_s, &mut q);
            if k % ((1.0 / dt_s).round() as usize) == 0 {
                samples.push(ship_motion(&w));
            }
        }
        samples
    };
    // Two IGs at different frame rates agree at every second.
    let a = run(6, 1.0 / 60.0, 6.0);
    let b = run(6, 1.0 / 25.0, 6.0);
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        for (u, v) in x.iter().zip(y) {
            assert!((u - v).abs() < 1e-6, "{x:?} against {y:?}");
        }
    }
    let rms = |samples: &[[f64; 3]], i: usize| {
        (samples.iter().map(|s| s[i] * s[i]).sum::<f64>() / samples.len() as f64).sqrt()
    };
    let calm = run(2, 0.5, 30.0);
    let rough = run(6, 0.5, 30.0);
    for (i, what) in ["heave", "pitch", "roll"].iter().enumerate() {
        assert!(
            rms(&rough, i) > 2.0 * rms(&calm, i),
            "{what}: sea state 2 {} against 6 {}",
            rms(&calm, i),
            rms(&rough, i)
        );
    }
    assert!(rms(&rough, 0) > 0.3, "heave {}", rms(&rough, 0));
}

#[test]
fn the_exercises_ships_float_on_the_same_waves_on_every_ig() {
    let mut qa = query();
    let mut qb = query();
    let mut a = world_with(&ship_scenario(5), true);
    // B owns nothing: the same sea, its own site.
    let b_scenario = "start_time = \"2026-01-01T00:00:00Z\"\n[sea]\nsea_state = 5\n\
                      [[models]]\nmodel = \"ship\"\ndis_type = \"1:3:*:*\"\n\
                      [dis]\nsite = 1\napplication = 3002\nexercise = 4\n";
    let mut b = world_with(b_scenario, true);
    let fallback = View {
        eye: Geodetic::new(SOUTH + 0.01, WEST + 0.01, 50.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    };
    let mut compared = 0;
    for k in 0..240 {
        a.step(1.0 / 60.0, &mut qa);
        b.step(1.0 / 60.0, &mut qb);
        for d in a.take_dis_outgoing() {
            b.receive_dis(&d, &mut qb);
        }
        if k < 120 {
            continue;
        }
        let seen = b.snapshot(64, 48, &fallback);
        let Some(ship) = seen.entities.iter().find(|e| e.model == "ship") else {
            continue;
        };
        let truth = a.session().poses()[&1];
        assert!(
            (ship.position.alt_m - truth.position.alt_m).abs() < 0.05
                && (ship.orientation.pitch_deg - truth.orientation.pitch_deg).abs() < 0.1
                && (ship.orientation.roll_deg - truth.orientation.roll_deg).abs() < 0.1,
            "frame {k} (A {} B {}): B draws {:?} {:?}, A has {:?}",
            a.unix_time_s(),
            b.unix_time_s(),
            ship.position,
            ship.orientation,
            truth
        );
        compared += 1;
    }
    assert!(compared > 100, "B drew the ship {compared} times");
    // And it moves: not a ship parked at the mean level.
    let pose = a.session().poses()[&1];
    assert!(
        (pose.position.alt_m - f64::from(GEOID_M)).abs() > 1e-3
            || pose.orientation.pitch_deg.abs() > 1e-3,
        "{pose:?}"
    );
}

/// An extended LOS segment request between two points (latitude, longitude, altitude MSL).
fn los_segment(id: u16, from: (f64, f64, f64), to: (f64, f64, f64)) -> Packet {
    Packet::LosSegmentRequest(cig_cigi::LosSegmentRequest {
        los_id: id,
        request_type_extended: true,
        source_lat_deg_or_x_m: from.0,
        source_lon_deg_or_y_m: from.1,
        source_alt_m_or_z_m: from.2,
        destination_lat_deg_or_x_m: to.0,
        destination_lon_deg_or_y_m: to.1,
        destination_alt_m_or_z_m: to.2,
        ..cig_cigi::LosSegmentRequest::default()
    })
}

/// The extended LOS answers of a message, by id.
fn los_answers(m: &Message) -> std::collections::BTreeMap<u16, cig_cigi::LosExtendedResponse> {
    m.packets
        .iter()
        .filter_map(|p| match p {
            Packet::LosExtendedResponse(r) => Some((r.los_id, r.clone())),
            _ => None,
        })
        .collect()
}

/// The WGS84 radii of curvature at `lat_deg`: the meridian's (north-south) and the prime
/// vertical's (east-west), metres.
fn radii_m(lat_deg: f64) -> (f64, f64) {
    let s = lat_deg.to_radians().sin();
    let w2 = 1.0 - cig_geo::WGS84_E2 * s * s;
    let prime_vertical = cig_geo::WGS84_A_M / w2.sqrt();
    (
        prime_vertical * (1.0 - cig_geo::WGS84_E2) / w2,
        prime_vertical,
    )
}

/// A point `east_m` east and `north_m` north of the database's south-west corner.
fn offset_point(east_m: f64, north_m: f64) -> (f64, f64) {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    (SOUTH + north_m / n, WEST + east_m / e)
}

#[test]
fn line_of_sight_over_open_sea_sees_the_refracted_bulge_of_the_earth() {
    let mut q = query();
    let mut w = world_with("[sea]\nsea_state = 0\n", false);
    let k = cig_ig::sea::STANDARD_REFRACTION_K;
    let (_, east_radius) = radii_m(SOUTH + 0.01);
    let r_eff = east_radius / (1.0 - k);
    // Along a parallel well west of the database: open sea, no terrain at all.
    let start = offset_point(-30_000.0, 600.0);
    let east_of = |metres: f64| offset_point(-30_000.0 + metres, 600.0);
    let pair = |id: u16, span: f64, height: f64| {
        let end = east_of(span);
        los_segment(id, (start.0, start.1, height), (end.0, end.1, height))
    };
    send(
        &mut w,
        1,
        vec![
            // 12 km at 2 m: the refracted bulge is 2.45 m, so the sea hides one from the other.
            pair(1, 12_000.0, 2.0),
            // 8 km at 2 m: 1.1 m of bulge, clear.
            pair(2, 8_000.0, 2.0),
            // 12 km at 2.6 m: clear with refraction (2.45 m), hidden without it (2.82 m).
            pair(3, 12_000.0, 2.6),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let answers = los_answers(&reply);
    assert_eq!(answers.len(), 3, "{answers:?}");
    let blocked = &answers[&1];
    assert!(
        blocked.valid && !blocked.visible && blocked.range_valid,
        "{blocked:?}"
    );
    // Where the refracted chord 2 m up at both ends meets the sea: x (D - x) = 2 h R_eff.
    let expected = 6_000.0 - (6_000.0_f64.powi(2) - 2.0 * 2.0 * r_eff).sqrt();
    assert!(
        (blocked.range_m - expected).abs() < 2.0,
        "range {} against {expected}",
        blocked.range_m
    );
    assert_eq!(blocked.material_code, u32::from(Material::Water.to_byte()));
    assert!(blocked.alt_m_or_z_m.abs() < 0.01, "{blocked:?}");
    assert!(blocked.normal_elevation_deg > 89.99, "{blocked:?}");
    let hit_east = east_of(expected);
    assert!(
        (blocked.lat_deg_or_x_m - hit_east.0).abs() < 1e-4
            && (blocked.lon_deg_or_y_m - hit_east.1).abs() < 1e-4,
        "{blocked:?} against {hit_east:?}"
    );
    for id in [2, 3] {
        let clear = &answers[&id];
        assert!(
            clear.valid && clear.visible && !clear.range_valid,
            "{clear:?}"
        );
    }
    // The geometric bulge would have hidden the 2.6 m pair: refraction is what clears it.
    assert!(12_000.0_f64.powi(2) / (8.0 * east_radius) > 2.6);
    assert!(12_000.0_f64.powi(2) / (8.0 * r_eff) < 2.6);
}

#[test]
fn line_of_sight_over_land_without_a_sea_is_refracted_too() {
    // Land at 20 m, 25.6 km across, and no sea in the world: the IG's sightlines bend as
    // what the eye sees does.
    let mut q = database(400.0, 0);
    let mut w = world_with("", false);
    assert!(w.sea().is_none());
    let k = cig_ig::sea::STANDARD_REFRACTION_K;
    let (_, east_radius) = radii_m(SOUTH + 0.05);
    let r_eff = east_radius / (1.0 - k);
    let start = offset_point(4_000.0, 6_000.0);
    let pair = |id: u16, span: f64, above_m: f64| {
        let end = offset_point(4_000.0 + span, 6_000.0);
        los_segment(
            id,
            (start.0, start.1, 20.0 + above_m),
            (end.0, end.1, 20.0 + above_m),
        )
    };
    send(
        &mut w,
        1,
        vec![
            // 16 km 4.2 m above the ground: the refracted bulge is 4.36 m, hidden.
            pair(1, 16_000.0, 4.2),
            // 16 km 4.8 m up: clear with refraction, hidden without it (5.02 m).
            pair(2, 16_000.0, 4.8),
        ],
    );
    let reply = frame(&mut w, &mut q);
    let answers = los_answers(&reply);
    let blocked = &answers[&1];
    assert!(blocked.valid && !blocked.visible, "{blocked:?}");
    // Grazing, the range moves about 5 km per metre of height: 100 m is 2 cm.
    let expected = 8_000.0 - (8_000.0_f64.powi(2) - 2.0 * 4.2 * r_eff).sqrt();
    assert!(
        (blocked.range_m - expected).abs() < 100.0,
        "range {} against {expected}",
        blocked.range_m
    );
    let clear = &answers[&2];
    assert!(clear.valid && clear.visible, "{clear:?}");
    assert!(16_000.0_f64.powi(2) / (8.0 * east_radius) > 4.8);
    assert!(16_000.0_f64.powi(2) / (8.0 * r_eff) < 4.8);
}

#[test]
fn a_line_of_sight_vector_down_to_the_sea_off_the_database_meets_it() {
    let mut q = query();
    let mut w = world_with("[sea]\nsea_state = 0\n", false);
    let from = offset_point(-5_000.0, 600.0);
    send(
        &mut w,
        1,
        vec![Packet::LosVectorRequest(cig_cigi::LosVectorRequest {
            los_id: 9,
            request_type_extended: true,
            azimuth_deg: 270.0,
            elevation_deg: -1.0,
            min_range_m: 100.0,
            max_range_m: 2_000.0,
            source_lat_deg_or_x_m: from.0,
            source_lon_deg_or_y_m: from.1,
            source_alt_m_or_z_m: 10.0,
            ..cig_cigi::LosVectorRequest::default()
        })],
    );
    let reply = frame(&mut w, &mut q);
    let answer = &los_answers(&reply)[&9];
    assert!(
        answer.valid && !answer.visible && answer.range_valid,
        "{answer:?}"
    );
    // 10 m up, 1 degree down over the refracted earth: 10 - x sin 1° + (1 - k) x² / (2 R) = 0.
    let (_, east_radius) = radii_m(from.0);
    let a = (1.0 - cig_ig::sea::STANDARD_REFRACTION_K) / (2.0 * east_radius);
    let s = 1.0_f64.to_radians().sin();
    let expected = (s - (s * s - 4.0 * a * 10.0).sqrt()) / (2.0 * a);
    assert!(
        (answer.range_m - expected).abs() < 3.0,
        "range {} against {expected}",
        answer.range_m
    );
    assert_eq!(answer.material_code, u32::from(Material::Water.to_byte()));
}

#[test]
fn the_sea_replaces_the_databases_sea_posts_and_the_coast_still_blocks() {
    let mut q = query();
    let mut calm = world_with("[sea]\nsea_state = 0\n", false);
    let mut dry = world_with("", false);
    // North-south along the sea posts' column 10, 15 km long with its middle on the
    // database: 4.1 m up at both ends, the geometric chord dips 0.3 m below the posts (MSL)
    // but the refracted one clears the sea by 0.25 m.
    let col = 10.0 * SPACING_M;
    let south = offset_point(col, -5_500.0);
    let north = offset_point(col, 9_500.0);
    let (meridian, _) = radii_m(SOUTH + 0.02);
    assert!(15_000.0_f64.powi(2) / (8.0 * meridian) > 4.1 + 0.3);
    assert!(
        15_000.0_f64.powi(2) * (1.0 - cig_ig::sea::STANDARD_REFRACTION_K) / (8.0 * meridian)
            < 4.1 - 0.2
    );
    // East along row 30 from 5 km off the database into the land (20 m), 3 m up: the coast
    // between columns 31 and 32 stops it.
    let west = offset_point(-5_000.0, 30.0 * SPACING_M);
    let inland = offset_point(50.0 * SPACING_M, 30.0 * SPACING_M);
    let requests = vec![
        los_segment(1, (south.0, south.1, 4.1), (north.0, north.1, 4.1)),
        los_segment(2, (west.0, west.1, 3.0), (inland.0, inland.1, 3.0)),
    ];
    send(&mut calm, 1, requests.clone());
    send(&mut dry, 1, requests);
    let with_sea = los_answers(&frame(&mut calm, &mut q));
    let without = los_answers(&frame(&mut dry, &mut q));
    assert!(
        with_sea[&1].valid && with_sea[&1].visible,
        "{:?}",
        with_sea[&1]
    );
    // Without a sea the terrain's sightline bends as much and clears its sea posts too; the
    // geometric chord would not.
    assert!(
        without[&1].valid && without[&1].visible,
        "the terrain alone, refracted: {:?}",
        without[&1]
    );
    let geometric = q
        .los(
            Geodetic::new(south.0, south.1, 4.1 + f64::from(GEOID_M)),
            Geodetic::new(north.0, north.1, 4.1 + f64::from(GEOID_M)),
        )
        .expect("los");
    assert!(!geometric.visible, "{geometric:?}");
    for answers in [&with_sea, &without] {
        let coast = &answers[&2];
        assert!(coast.valid && !coast.visible, "{coast:?}");
        let expected = 5_000.0 + 31.5 * SPACING_M;
        assert!(
            (coast.range_m - expected).abs() < SPACING_M,
            "range {} against about {expected}",
            coast.range_m
        );
    }
    // With a sea the terrain's sightline is refracted as the sea's is: 3.4 cm higher where
    // it meets the coast, a few centimetres further on the rising shore.
    let later_m = with_sea[&2].range_m - without[&2].range_m;
    assert!((0.0..0.5).contains(&later_m), "{later_m}");
}

#[test]
fn a_rough_sea_hides_a_low_line_of_sight_behind_its_crests() {
    let mut q = query();
    let mut w = world_with("[sea]\nsea_state = 6\n", false);
    // 500 m north along the sea posts' column 10, from 1 m above the waves at one end to
    // 1 m above them at the other (a periscope looking at a low target).
    let from = at_post(20.0, 10.0);
    let to = offset_point(10.0 * SPACING_M, 20.0 * SPACING_M + 500.0);
    let mut blocked = 0;
    for k in 0..8u32 {
        // Half a second between the questions: the waves move.
        for _ in 0..30 {
            w.step(1.0 / 60.0, &mut q);
        }
        let (from_m, to_m) = (
            sea_height_msl(&w, from, 0.0) + 1.0,
            sea_height_msl(&w, to, 0.0) + 1.0,
        );
        send(
            &mut w,
            k,
            vec![los_segment(1, (from.0, from.1, from_m), (to.0, to.1, to_m))],
        );
        let reply = frame(&mut w, &mut q);
        let answer = &los_answers(&reply)[&1];
        assert!(answer.valid, "{answer:?}");
        if answer.visible {
            continue;
        }
        blocked += 1;
        assert!(answer.range_valid, "{answer:?}");
        assert!(answer.range_m > 0.0 && answer.range_m < 500.0, "{answer:?}");
        assert_eq!(answer.material_code, u32::from(Material::Water.to_byte()));
        // The hit is on the waves: the sea's own height there, a tilted normal.
        let crest = sea_height_msl(&w, (answer.lat_deg_or_x_m, answer.lon_deg_or_y_m), 0.0);
        assert!(
            (answer.alt_m_or_z_m - crest).abs() < 0.05,
            "{answer:?} against the sea's {crest}"
        );
        // A crest that reaches the line: at least as high as its lower end.
        assert!(
            answer.alt_m_or_z_m > from_m.min(to_m) - 0.01,
            "{answer:?} from {from_m} to {to_m}"
        );
        assert!(answer.normal_elevation_deg < 89.9, "{answer:?}");
    }
    assert!(blocked > 0, "never blocked in 8 looks");
}

#[test]
fn the_search_over_the_waves_finds_the_first_crest_a_dense_march_finds() {
    let mut q = query();
    let mut w = world_with("[sea]\nsea_state = 5\n", false);
    let k = cig_ig::sea::STANDARD_REFRACTION_K;
    for look in 0..2u32 {
        for _ in 0..37 {
            w.step(1.0 / 60.0, &mut q);
        }
        let sea = w.sea().expect("sea").clone();
        let plane = EnuFrame::new(sea.draw().origin);
        // Heights above the sea at the ends, metres, and the length: a line grazing the waves
        // over 30 km, one that meets them near its start, a short low one.
        for (h1, h2, span) in [
            (15.0, 15.0, 30_000.0),
            (2.0, 40.0, 30_000.0),
            (4.0, 4.0, 2_000.0),
        ] {
            let west = -40_000.0 + 700.0 * f64::from(look);
            let (a, b) = (offset_point(west, 600.0), offset_point(west + span, 600.0));
            let geoid = f64::from(GEOID_M);
            let from = Geodetic::new(a.0, a.1, h1 + geoid);
            let to = Geodetic::new(b.0, b.1, h2 + geoid);
            let sightline = cig_ig::sea::SeaSightline {
                level_msl_m: 0.0,
                geoid_m: [geoid, geoid],
                refraction_k: k,
                with_waves: true,
                max_range_m: f64::INFINITY,
            };
            let hit = sea.first_hit(from, to, &sightline, |_, _| true);
            // The refracted chord's clearance over the waves, as the module doc gives it.
            let (ea, eb) = (from.to_ecef(), to.to_ecef());
            let d = (eb - ea).length();
            let (_, radius) = radii_m(Geodetic::from_ecef((ea + eb) * 0.5).lat_deg);
            let flat = 1.0 - ((h2 - h1) / d).powi(2);
            let gap = |x: f64| {
                let p = Geodetic::from_ecef(ea + (eb - ea) * (x / d));
                let at = plane.geodetic_to_enu(Geodetic::new(p.lat_deg, p.lon_deg, 0.0));
                h1 + (h2 - h1) * x / d
                    - (1.0 - k) * flat * x * (d - x) / (2.0 * radius)
                    - sea.surface().sample(at.x, at.y).height_m
            };
            if let Some(h) = hit {
                assert!(gap(h.range_m).abs() < 0.02, "{h:?}: gap {}", gap(h.range_m));
                let sea_there =
                    plane.geodetic_to_enu(Geodetic::new(h.point.lat_deg, h.point.lon_deg, 0.0));
                let height = sea.surface().sample(sea_there.x, sea_there.y).height_m;
                assert!((h.height_msl_m - height).abs() < 1e-6, "{h:?}");
            }
            // Nothing under the waves before the hit, 10 cm apart (a ripple's tip may be
            // grazed by a centimetre).
            let end = hit.map_or(d, |h| h.range_m - 0.05);
            let deepest = (0..(end / 0.1) as usize)
                .map(|i| -gap(i as f64 * 0.1))
                .fold(f64::MIN, f64::max);
            assert!(
                deepest < 0.01,
                "look {look}, {h1}-{h2} m over {span} m: {deepest} m under before {hit:?}"
            );
        }
    }
}

/// A 64 x 48 view from 100 m over a point.
fn small_view_over(lat: f64, lon: f64) -> View {
    View {
        eye: Geodetic::new(lat, lon, 100.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    }
}

#[test]
fn a_ship_under_way_leaves_a_wake_along_its_course_at_its_speed() {
    let (lat, lon) = at_post(32.0, 20.0);
    let (west_lat, west_lon) = at_post(32.0, 2.0);
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n[sea]\nsea_state = 2\n\
         [[entities]]\nid = 1\nmodel = \"patrol_craft\"\nlat_deg = {lat}\nlon_deg = {lon}\n\
         clamp = \"height_and_attitude\"\nspeed_mps = 8\npath = [[{west_lat}, {west_lon}]]\n"
    );
    let mut q = query();
    let mut w = world_with(&scenario, false);
    let fallback = small_view_over(lat, lon);
    for _ in 0..120 {
        w.step(1.0 / 60.0, &mut q);
    }
    let snapshot = w.snapshot(64, 48, &fallback);
    assert_eq!(snapshot.wakes.len(), 1, "{:?}", snapshot.wakes);
    let wake = &snapshot.wakes[0];
    assert!((wake.speed_mps - 8.0).abs() < 0.4, "{wake:?}");
    let course_error = (wake.heading_deg - 270.0 + 180.0).rem_euclid(360.0) - 180.0;
    assert!(course_error.abs() < 2.0, "{wake:?}");
    assert!(
        wake.foam_generation > 0.5 && wake.arm_half_angle_deg <= 19.48,
        "{wake:?}"
    );
    // A ship lying still, or without a sea, leaves none.
    let still = scenario.replace("speed_mps = 8\n", "");
    let mut w = world_with(&still, false);
    for _ in 0..120 {
        w.step(1.0 / 60.0, &mut q);
    }
    assert!(w.snapshot(64, 48, &fallback).wakes.is_empty());
    let dry = scenario.replace("[sea]\nsea_state = 2\n", "");
    let mut w = world_with(&dry, false);
    for _ in 0..120 {
        w.step(1.0 / 60.0, &mut q);
    }
    assert!(w.snapshot(64, 48, &fallback).wakes.is_empty());
}

#[test]
fn a_ship_that_turned_leaves_its_wake_along_the_track_it_made() {
    // West 25 s at 8 m/s (200 m), then north: the wake's track bends round the corner.
    let (lat, lon) = at_post(20.0, 20.0);
    let (corner_lat, corner_lon) = at_post(20.0, 20.0 - 200.0 / SPACING_M);
    let (north_lat, north_lon) = at_post(40.0, 20.0 - 200.0 / SPACING_M);
    let scenario = format!(
        "start_time = \"2026-06-21T12:00:00Z\"\n[sea]\nsea_state = 2\n\
         [[entities]]\nid = 1\nmodel = \"patrol_craft\"\nlat_deg = {lat}\nlon_deg = {lon}\n\
         clamp = \"height_and_attitude\"\nspeed_mps = 8\n\
         path = [[{corner_lat}, {corner_lon}], [{north_lat}, {north_lon}]]\n"
    );
    let mut q = query();
    let mut w = world_with(&scenario, false);
    let fallback = small_view_over(lat, lon);
    // 45 s: the corner at 25 s, then 20 s north.
    for _ in 0..450 {
        w.step(0.1, &mut q);
    }
    let snapshot = w.snapshot(64, 48, &fallback);
    assert_eq!(snapshot.wakes.len(), 1, "{:?}", snapshot.wakes);
    let wake = &snapshot.wakes[0];
    let course_error = (wake.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
    assert!(course_error.abs() < 3.0, "heading north: {wake:?}");
    assert!(wake.track.len() >= 4, "{:?}", wake.track);
    let frame = EnuFrame::new(wake.stern());
    let places: Vec<(glam::DVec3, f64)> = wake
        .track
        .iter()
        .map(|(p, age)| (frame.geodetic_to_enu(*p), *age))
        .collect();
    // Newest first, each older; the newest on the present leg (straight astern, south), the
    // oldest before the corner: east of the northward leg, where the ship came from.
    assert!(places.windows(2).all(|p| p[1].1 > p[0].1), "{places:?}");
    let (newest, _) = places[0];
    assert!(newest.x.abs() < 3.0 && newest.y <= 0.5, "{places:?}");
    let (oldest, oldest_age) = places[places.len() - 1];
    assert!(oldest_age > 20.0, "{places:?}");
    assert!(
        oldest.x > 50.0,
        "the track before the corner lies east: {places:?}"
    );
    // A straight course's wake has its track straight astern.
    let straight = scenario.replace(&format!(", [{north_lat}, {north_lon}]"), "");
    let mut w = world_with(&straight, false);
    for _ in 0..200 {
        w.step(0.1, &mut q);
    }
    let snapshot = w.snapshot(64, 48, &fallback);
    let wake = &snapshot.wakes[0];
    let frame = EnuFrame::new(wake.stern());
    for (p, _) in &wake.track {
        let at = frame.geodetic_to_enu(*p);
        // West-bound: astern is east, on the line.
        assert!(at.y.abs() < 2.0 && at.x >= -0.5, "{at}");
    }
}

/// A world whose clock starts `after_s` seconds after [`world_with`]'s.
fn world_started(scenario: &str, after_s: f64) -> IgWorld {
    IgWorld::new(
        Scenario::from_toml(scenario).expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 12, 0, after_s).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: false,
        },
    )
    .expect("world")
}

#[test]
fn a_ship_that_turns_rings_down_into_its_new_motion_and_knows_its_speed_at_once() {
    // A patrol craft in sea state 6 runs west at 8 m/s and turns north at the corner, 200 m
    // on, at 25 s (A). B starts at the corner at 25 s already heading north; C starts 80 m
    // south of the corner at 15 s heading north, so it is where B is from 25 s on.
    let ship = |from: (f64, f64), path: &[(f64, f64)]| {
        let path: Vec<String> = path.iter().map(|(a, b)| format!("[{a}, {b}]")).collect();
        format!(
            "[sea]\nsea_state = 6\nwind_from_deg = 270\n\
             [[entities]]\nid = 1\nmodel = \"patrol_craft\"\nlat_deg = {}\nlon_deg = {}\n\
             clamp = \"height_and_attitude\"\nspeed_mps = 8\npath = [{}]\n",
            from.0,
            from.1,
            path.join(", ")
        )
    };
    let start = at_post(20.0, 20.0);
    let corner = at_post(20.0, 20.0 - 200.0 / SPACING_M);
    let north = at_post(60.0, 20.0 - 200.0 / SPACING_M);
    let south = at_post(20.0 - 80.0 / SPACING_M, 20.0 - 200.0 / SPACING_M);
    let mut q = query();
    let mut a = world_with(&ship(start, &[corner, north]), false);
    let mut b = world_started(&ship(corner, &[north]), 25.0);
    let mut c = world_started(&ship(south, &[corner, north]), 15.0);
    let dt = 0.1;
    for _ in 0..100 {
        c.step(dt, &mut q);
    }
    let mut rolls_a = Vec::new();
    for _ in 0..250 {
        a.step(dt, &mut q);
        rolls_a.push(ship_motion(&a)[2]);
    }
    let mut differences = Vec::new();
    for k in 0..900 {
        a.step(dt, &mut q);
        b.step(dt, &mut q);
        c.step(dt, &mut q);
        let (ma, mb, mc) = (ship_motion(&a), ship_motion(&b), ship_motion(&c));
        if k < 10 {
            // B knows its speed from its first frame: it rides as C, which has sailed this
            // course for 10 s (no half second at rest).
            for (x, y) in mb.iter().zip(&mc) {
                assert!((x - y).abs() < 1e-4, "frame {k}: B {mb:?} against C {mc:?}");
            }
        }
        rolls_a.push(ma[2]);
        differences.push((ma[2] - mb[2]).abs());
    }
    // Through the turn A's roll changes no faster than it does anywhere else on its run.
    let steps: Vec<f64> = rolls_a.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let at_turn = steps[248..252].iter().copied().fold(0.0, f64::max);
    let elsewhere = steps[..240].iter().copied().fold(0.0, f64::max);
    assert!(
        at_turn <= 1.2 * elsewhere,
        "roll step at the turn {at_turn} deg, elsewhere at most {elsewhere}"
    );
    // Just after the turn A still rolls as it did before, then rings down into B's motion.
    let early = differences[..20].iter().copied().fold(0.0, f64::max);
    let late = differences[800..].iter().copied().fold(0.0, f64::max);
    assert!(early > 0.5, "A against B just after the turn: {early} deg");
    assert!(
        late < 0.02 * early,
        "A against B 80 s on: {late} deg (early {early})"
    );
}

#[test]
fn regional_and_entity_waves_apply_where_the_host_puts_them() {
    // A calm sea, a 2 m swell confined to a region 3 km west of the database and a 1 m wave
    // around the ship (entity 1) on the database's sea.
    let mut q = query();
    let mut w = world_with(&ship_scenario(0), false);
    let region_centre = offset_point(-3_000.0, 1_000.0);
    let ship = at_post(32.0, 12.0);
    let far = offset_point(-9_000.0, 1_000.0);
    let wave = |scope: u8, id: u16, height: f32, wavelength_m: f32, period_s: f32| {
        Packet::WaveControl(WaveControl {
            entity_or_region_id: id,
            wave_id: 1,
            wave_enable: true,
            scope,
            height_m: height,
            wavelength_m,
            period_s,
            direction_deg: 90.0,
            ..WaveControl::default()
        })
    };
    send(
        &mut w,
        1,
        vec![
            Packet::EnvironmentalRegionControl(EnvironmentalRegionControl {
                region_id: 4,
                region_state: 1,
                latitude_deg: region_centre.0,
                longitude_deg: region_centre.1,
                size_x_m: 1_500.0,
                size_y_m: 1_500.0,
                transition_perimeter_m: 300.0,
                ..EnvironmentalRegionControl::default()
            }),
            wave(1, 4, 2.0, 80.0, 7.2),
            // A swell longer than the ship, which it follows.
            wave(2, 1, 1.0, 400.0, 16.0),
        ],
    );
    frame(&mut w, &mut q);
    // The waves' span along a wavelength at a place, as HOT answers it.
    let span = |w: &mut IgWorld, q: &mut QuerySession, (lat, lon): (f64, f64), step_m: f64| {
        let (_, e) = cig_geo::metres_per_degree(lat);
        let requests = (0..16)
            .map(|k| hot_request(10 + k, (lat, lon + f64::from(k) * step_m / e)))
            .collect();
        send(w, 2, requests);
        let answers = hot_answers(&frame(w, q));
        assert_eq!(answers.len(), 16);
        let heights: Vec<f64> = answers.iter().map(|a| a.2).collect();
        heights.iter().copied().fold(f64::MIN, f64::max)
            - heights.iter().copied().fold(f64::MAX, f64::min)
    };
    let in_region = span(&mut w, &mut q, region_centre, 5.0);
    let by_the_ship = span(&mut w, &mut q, (ship.0, ship.1 - 0.003), 25.0);
    let elsewhere = span(&mut w, &mut q, far, 25.0);
    assert!((in_region - 2.0).abs() < 0.3, "in the region: {in_region}");
    assert!(
        (by_the_ship - 1.0).abs() < 0.2,
        "by the ship: {by_the_ship}"
    );
    assert!(elsewhere < 0.05, "elsewhere the sea is calm: {elsewhere}");
    // The ship rides its own wave: it heaves by about its height.
    let mut heave = Vec::new();
    for _ in 0..80 {
        w.step(0.25, &mut q);
        heave.push(ship_motion(&w)[0]);
    }
    let heave_span = heave.iter().copied().fold(f64::MIN, f64::max)
        - heave.iter().copied().fold(f64::MAX, f64::min);
    assert!(
        heave_span > 0.7 && heave_span < 1.2,
        "the ship heaves {heave_span} m in its 1 m swell"
    );
    // The region deactivated: its wave is gone, and the sea there is calm.
    send(
        &mut w,
        3,
        vec![Packet::EnvironmentalRegionControl(
            EnvironmentalRegionControl {
                region_id: 4,
                region_state: 0,
                latitude_deg: region_centre.0,
                longitude_deg: region_centre.1,
                ..EnvironmentalRegionControl::default()
            },
        )],
    );
    frame(&mut w, &mut q);
    let in_region = span(&mut w, &mut q, region_centre, 5.0);
    assert!(in_region < 0.05, "the region gone: {in_region}");
}

#[test]
fn a_ships_ride_starts_again_after_a_jump_or_with_another_hull_and_odd_speeds_stay_sane() {
    use cig_ig::sea::{ShipKey, WorldSea};
    let mut sea = WorldSea::of_conditions(
        Some(cig_sea::spectrum::SeaConditions::for_sea_state(6, 270.0).expect("sea state")),
        cig_ig::sea::Water::of_scenario(None),
        1,
    );
    let origin = cig_scene::sea::sea_origin(SOUTH, WEST);
    let start_s = 1_782_000_000.0;
    let places = std::collections::BTreeMap::new();
    let environment = cig_ig::session::EnvironmentState::default();
    let ship = |lat: f64, lon: f64, heading_deg: f64| cig_scene::EntityInstance {
        id: 1,
        model: "ship".into(),
        position: Geodetic::new(lat, lon, 0.0),
        orientation: Hpr {
            heading_deg,
            ..Hpr::default()
        },
        cue_important: false,
        critical_radius_m: None,
    };
    let destroyer = cig_scene::sea::builtin_hull("destroyer").expect("hull");
    let patrol = cig_scene::sea::builtin_hull("patrol_craft").expect("hull");
    let (a, b) = (offset_point(-4_000.0, 0.0), offset_point(-1_000.0, 0.0));
    let motion = |e: &cig_scene::EntityInstance| {
        [
            e.position.alt_m,
            e.orientation.pitch_deg,
            e.orientation.roll_deg,
        ]
    };
    // Ship 1 sails north at 8 m/s for a minute at A, then turns west and is moved 3 km to B
    // within a frame (as a host repositions it): it starts again in B's steady state, as
    // ship 2 first seen there does. Ship 3 is a destroyer that becomes a patrol craft under
    // the same id: it rides as ship 4, a patrol craft from the start.
    let mut last = [[0.0; 3]; 4];
    for k in 0..=600 {
        let t = start_s + f64::from(k) * 0.1;
        sea.update(&environment, None, origin, t, &places)
            .expect("sea");
        let now = sea.now().expect("a sea");
        let jumped = k == 600;
        let mut one = if jumped {
            ship(b.0, b.1, 270.0)
        } else {
            ship(a.0, a.1, 0.0)
        };
        let velocity = if jumped { [-8.0, 0.0] } else { [0.0, 8.0] };
        now.ride(&mut one, &destroyer, velocity, 0.0, Some(ShipKey::Own(1)));
        let mut three = ship(a.0, a.1, 0.0);
        let hull = if jumped { &patrol } else { &destroyer };
        now.ride(&mut three, hull, [0.0, 8.0], 0.0, Some(ShipKey::Own(3)));
        last[0] = motion(&one);
        last[2] = motion(&three);
        if jumped {
            let mut two = ship(b.0, b.1, 270.0);
            now.ride(
                &mut two,
                &destroyer,
                [-8.0, 0.0],
                0.0,
                Some(ShipKey::Own(2)),
            );
            let mut four = ship(a.0, a.1, 0.0);
            now.ride(&mut four, &patrol, [0.0, 8.0], 0.0, Some(ShipKey::Own(4)));
            last[1] = motion(&two);
            last[3] = motion(&four);
        }
        // An absurd speed (a host's bad rates) is taken as 40 m/s: the ride stays sane.
        let mut wild = ship(a.0, a.1, 0.0);
        let speed = if k % 2 == 0 { 1.0e6 } else { 0.0 };
        now.ride(&mut wild, &patrol, [speed, 0.0], 0.0, Some(ShipKey::Own(5)));
        let m = motion(&wild);
        assert!(
            m[0].abs() < 10.0 && m[1].abs() < 30.0 && m[2].abs() < 60.0,
            "{m:?}"
        );
    }
    for (x, y) in last[0].iter().zip(&last[1]) {
        assert!(
            (x - y).abs() < 1e-9,
            "jumped {:?} against fresh {:?}",
            last[0],
            last[1]
        );
    }
    for (x, y) in last[2].iter().zip(&last[3]) {
        assert!(
            (x - y).abs() < 1e-9,
            "new hull {:?} against fresh {:?}",
            last[2],
            last[3]
        );
    }
}
