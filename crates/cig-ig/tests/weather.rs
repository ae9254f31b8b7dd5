//! Lightning and precipitation in the world: the same seed and time give the same bolts and
//! flash on two IGs whatever their frame rates, the flash rises within two frames and decays,
//! and the host's rain layer (CIGI Weather Control) reaches the snapshot, clamped and reported;
//! night-vision views from the scenario and the host, and the world's lights (entity lamps
//! switched by the scenario and the host's Component Control, lamps and flares).

use cig_cigi::{
    decode_message, encode_message, ByteOrder, ComponentControl, EntityControl, IgControl, Message,
    Packet, SensorControl, Version, ViewControl, ViewDefinition, WeatherControl,
};
use cig_effects::EffectsConfig;
use cig_environment::{PrecipitationKind, UtcTime};
use cig_geo::Geodetic;
use cig_ig::{IgWorld, Scenario, SessionConfig, WorldConfig};
use cig_scene::lighting::FogMode;
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::sync::Arc;

const SOUTH: f64 = 36.0;
const WEST: f64 = -121.0;

/// 65 x 65 posts, 60 m apart, a plane at 100 m.
fn query() -> QuerySession {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    let grid = GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: 60.0 / n,
        dlon_deg: 60.0 / e,
        rows: 65,
        cols: 65,
    };
    let raster = Raster {
        grid,
        elevation_m: vec![100.0; grid.len()],
        material: Some(vec![Material::Grass; grid.len()]),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 64, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec!["test".into()]);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    let cache = TileCache::new(Arc::new(db), PagingConfig::default()).expect("cache");
    QuerySession::new(Arc::new(cache))
}

/// The middle of the test terrain.
fn centre() -> (f64, f64) {
    let (n, e) = cig_geo::metres_per_degree(SOUTH);
    (SOUTH + 1920.0 / n, WEST + 1920.0 / e)
}

fn world(scenario: &str) -> IgWorld {
    IgWorld::new(
        Scenario::from_toml(scenario).expect("scenario"),
        WorldConfig {
            session: SessionConfig::default(),
            start: UtcTime::from_calendar(2026, 6, 21, 4, 0, 0.0).expect("time"),
            fog_mode: FogMode::Exponential,
            effects: EffectsConfig::default(),
            join_exercise: false,
        },
    )
    .expect("world")
}

fn storm(seed: u64) -> String {
    let (lat, lon) = centre();
    format!(
        "[view]\neye = [{lat}, {lon}, 300.0]\n\
         [lightning]\nlat_deg = {lat}\nlon_deg = {lon}\nradius_m = 3000\n\
         strikes_per_minute = 120\nseed = {seed}\n"
    )
}

fn fallback() -> View {
    let (lat, lon) = centre();
    View {
        eye: Geodetic::new(lat, lon, 500.0),
        orientation: Hpr::default(),
        fov: FovDeg::symmetric(60.0, 45.0),
        width_px: 64,
        height_px: 48,
    }
}

fn snap(w: &IgWorld) -> FrameSnapshot {
    w.snapshot(64, 48, &fallback())
}

/// What a frame shows of the lightning: each bolt's origin, lines and intensity, and the flash.
fn lightning_of(s: &FrameSnapshot) -> (Vec<String>, u64) {
    let bolts = s
        .bolts
        .iter()
        .map(|b| format!("{:?} {:?} {}", b.origin_ecef_m, b.lines, b.intensity))
        .collect();
    (bolts, s.flash_lux.to_bits())
}

#[test]
fn the_same_seed_and_time_give_the_same_bolts_at_any_frame_rate() {
    let (mut qa, mut qb) = (query(), query());
    let mut a = world(&storm(5));
    let mut b = world(&storm(5));
    let mut other = world(&storm(6));
    let mut qo = query();
    let mut lit_frames = 0;
    let mut differs = false;
    // A steps at 64 Hz, B at 16 Hz; they meet every 1/16 s for 20 s.
    for _ in 0..320 {
        for _ in 0..4 {
            a.step(1.0 / 64.0, &mut qa);
        }
        b.step(1.0 / 16.0, &mut qb);
        other.step(1.0 / 16.0, &mut qo);
        assert_eq!(a.unix_time_s(), b.unix_time_s());
        let (sa, sb, so) = (snap(&a), snap(&b), snap(&other));
        assert_eq!(lightning_of(&sa), lightning_of(&sb));
        if !sa.bolts.is_empty() {
            lit_frames += 1;
            assert!(sa.flash_lux > 0.0);
        }
        differs |= lightning_of(&sa) != lightning_of(&so);
    }
    // 40 strikes expected in 20 s, each lit for about 4 of these frames.
    assert!(lit_frames > 20, "{lit_frames} frames with a bolt");
    assert!(differs, "another seed strikes elsewhere and at other times");
    let stats = a.lightning().stats();
    assert!(stats.bolts_generated > 10, "{stats:?}");
}

#[test]
fn a_flash_rises_within_two_frames_and_decays() {
    let mut q = query();
    let (lat, lon) = centre();
    let mut w = world(&format!("[view]\neye = [{lat}, {lon}, 300.0]\n"));
    w.step(1.0 / 60.0, &mut q);
    assert_eq!(snap(&w).flash_lux, 0.0);
    w.strike_lightning_now(Geodetic::new(lat + 0.01, lon, 100.0), 77);
    let mut flashes = Vec::new();
    for _ in 0..30 {
        w.step(1.0 / 60.0, &mut q);
        flashes.push(snap(&w).flash_lux);
    }
    let peak = flashes.iter().copied().fold(0.0, f64::max);
    assert!(
        peak > 10.0,
        "a strike 1 km away lights the scene: {flashes:?}"
    );
    assert!(
        flashes[0].max(flashes[1]) >= 0.8 * peak,
        "full within two frames: {flashes:?}"
    );
    let top = flashes.iter().position(|f| *f == peak).unwrap_or(0);
    assert!(top <= 1);
    for w2 in flashes[top..].windows(2) {
        assert!(w2[1] <= w2[0], "decays: {flashes:?}");
    }
    assert_eq!(flashes[20], 0.0, "gone within 20 frames: {flashes:?}");
    assert!(snap(&w).bolts.is_empty());
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
        &Message::new(Version::V3_3, ByteOrder::BigEndian, all),
        &mut bytes,
    )
    .expect("encode");
    world.receive_cigi(&bytes).expect("accepted");
}

fn rain_layer(severity: u8, concentration: f32, visibility_m: f32) -> Packet {
    Packet::WeatherControl(WeatherControl {
        layer_id: 4,
        weather_enable: true,
        scope: 0,
        severity,
        base_elevation_m: 0.0,
        thickness_m: 3000.0,
        visibility_range_m: visibility_m,
        aerosol_concentration_gpm3: concentration,
        ..WeatherControl::default()
    })
}

#[test]
fn the_hosts_rain_layer_reaches_the_snapshot_clamped_and_reported() {
    let mut q = query();
    let (lat, lon) = centre();
    let mut w = world("");
    let eye = vec![
        Packet::EntityControl(EntityControl {
            entity_id: 0,
            entity_state: 1,
            lat_deg_or_x_m: lat,
            lon_deg_or_y_m: lon,
            alt_m_or_z_m: 200.0,
            ..EntityControl::default()
        }),
        Packet::ViewControl(ViewControl {
            view_id: 0,
            entity_id: 0,
            ..ViewControl::default()
        }),
    ];
    send(&mut w, 1, eye.clone());
    w.step(1.0 / 60.0, &mut q);
    let dry = snap(&w);
    assert!(dry.precipitation.is_none());
    // Severity 3, no concentration, no visibility stated: 10 mm/h, and the rain lowers the
    // visibility by its own extinction.
    let mut packets = eye.clone();
    packets.push(rain_layer(3, 0.0, 0.0));
    send(&mut w, 2, packets);
    w.step(1.0 / 60.0, &mut q);
    let wet = snap(&w);
    let p = wet.precipitation.expect("rain").precipitation;
    assert_eq!(p.kind, PrecipitationKind::Rain);
    assert_eq!(p.rate_mm_per_h, 10.0);
    assert!(wet.fog.density_per_m > dry.fog.density_per_m + 3.912 / 4000.0);
    // A water content far beyond any rain: clamped to 200 mm/h and told to the host once.
    let mut packets = eye.clone();
    packets.push(rain_layer(3, 500.0, 0.0));
    send(&mut w, 3, packets);
    w.step(1.0 / 60.0, &mut q);
    let p = snap(&w).precipitation.expect("rain").precipitation;
    assert_eq!(p.rate_mm_per_h, 200.0);
    let message = w.host_message(&mut q, 0);
    let mut bytes = Vec::new();
    encode_message(&message, &mut bytes).expect("encode");
    let told: Vec<String> = decode_message(&bytes)
        .expect("decode")
        .packets
        .into_iter()
        .filter_map(|p| match p {
            Packet::ImageGeneratorMessage(m) => Some(m.text),
            _ => None,
        })
        .collect();
    assert!(
        told.iter()
            .any(|t| t.contains("layer 4") && t.contains("clamped")),
        "{told:?}"
    );
    // Above the layer's top the rain stops.
    let mut packets = vec![Packet::EntityControl(EntityControl {
        entity_id: 0,
        entity_state: 1,
        lat_deg_or_x_m: lat,
        lon_deg_or_y_m: lon,
        alt_m_or_z_m: 4000.0,
        ..EntityControl::default()
    })];
    packets.extend(eye[1..].iter().cloned());
    send(&mut w, 4, packets);
    w.step(1.0 / 60.0, &mut q);
    assert!(snap(&w).precipitation.is_none());
}

#[test]
fn the_hosts_random_lightning_strikes_around_the_eye() {
    let mut q = query();
    let (lat, lon) = centre();
    let mut w = world("");
    let mut packets = vec![
        Packet::EntityControl(EntityControl {
            entity_id: 0,
            entity_state: 1,
            lat_deg_or_x_m: lat,
            lon_deg_or_y_m: lon,
            alt_m_or_z_m: 200.0,
            ..EntityControl::default()
        }),
        Packet::ViewControl(ViewControl {
            view_id: 0,
            entity_id: 0,
            ..ViewControl::default()
        }),
    ];
    send(&mut w, 1, packets.clone());
    let mut seen = 0;
    for _ in 0..16 * 20 {
        w.step(1.0 / 16.0, &mut q);
        seen += snap(&w).bolts.len();
    }
    assert_eq!(seen, 0, "no lightning without the host's");
    packets.push(Packet::WeatherControl(WeatherControl {
        layer_id: 1,
        weather_enable: true,
        random_lightning_enable: true,
        scope: 0,
        severity: 5,
        base_elevation_m: 1500.0,
        thickness_m: 2000.0,
        coverage_pct: 80.0,
        ..WeatherControl::default()
    }));
    send(&mut w, 2, packets);
    for _ in 0..16 * 20 {
        w.step(1.0 / 16.0, &mut q);
        seen += snap(&w).bolts.len();
    }
    // 30 strikes a minute for 20 s: about 10.
    assert!(
        w.lightning().stats().bolts_generated >= 3,
        "{:?}",
        w.lightning().stats()
    );
    assert!(seen > 0);
}

#[test]
fn the_operators_sensor_turns_every_view_thermal_and_back() {
    let (lat, lon) = centre();
    let mut w = world(&format!("[view]\neye = [{lat}, {lon}, 300.0]\n"));
    let mut q = query();
    w.step(0.1, &mut q);
    let visible = snap(&w);
    assert!(visible.thermal.is_none() && visible.sensors.iter().all(Option::is_none));
    let lwir = cig_scene::thermal::SensorView::new(cig_thermal::IrBand::Lwir);
    w.set_operator_sensor(Some(lwir));
    w.step(0.1, &mut q);
    let sensed = snap(&w);
    assert!(
        sensed.thermal.is_some(),
        "the thermal state spins up for the operator's sensor"
    );
    assert_eq!(sensed.sensors, vec![Some(lwir)]);
    w.set_operator_sensor(None);
    w.step(0.1, &mut q);
    assert_eq!(snap(&w).sensors, vec![None]);
}

#[test]
fn a_scenario_thermal_section_is_checked() {
    for (text, needle) in [
        ("[thermal]\nair_min_c = 30\nair_max_c = 10\n", "air"),
        ("[thermal]\nhumidity_pct = 130\n", "130"),
        ("[thermal]\naerosol = \"volcanic\"\n", "volcanic"),
        ("[thermal]\nair_hourly_c = [1.0, 2.0]\n", "24"),
        ("[view]\nsensor = \"uv\"\n", "uv"),
    ] {
        let e = Scenario::from_toml(text).expect_err(text);
        assert!(e.to_string().contains(needle), "{text}: {e}");
    }
    Scenario::from_toml("[thermal]\nair_min_c = 2\nair_max_c = 15\nhumidity_pct = 70\naerosol = \"maritime\"\n[[entities]]\nid = 1\nlat_deg = 36.0\nlon_deg = -121.0\nengine = false\n")
        .expect("a good thermal scenario");
}

#[test]
fn nvg_views_come_from_the_scenario_and_the_host_and_yield_to_a_thermal_sensor() {
    let (lat, lon) = centre();
    let mut q = query();
    let mut w = world(&format!(
        "[view]\neye = [{lat}, {lon}, 300.0]\nsensor = \"nvg\"\n[view.nvg]\ngain = 3.0\n"
    ));
    w.step(0.1, &mut q);
    let s = snap(&w);
    assert_eq!(s.nvg_of(0).map(|n| n.gain), Some(3.0));
    assert!(
        s.sensors.iter().all(Option::is_none),
        "an NVG view is not thermal"
    );
    let lwir = cig_scene::thermal::SensorView::new(cig_thermal::IrBand::Lwir);
    w.set_operator_sensor(Some(lwir));
    w.step(0.1, &mut q);
    assert_eq!(snap(&w).nvg_of(0), None, "the thermal sensor wins");
    w.set_operator_sensor(None);

    // The host's view of type 3 with a Sensor Control's gain of 1: the goggle at gain 10.
    let mut w = world("");
    let view = vec![
        Packet::EntityControl(EntityControl {
            entity_id: 0,
            entity_state: 1,
            lat_deg_or_x_m: lat,
            lon_deg_or_y_m: lon,
            alt_m_or_z_m: 200.0,
            ..EntityControl::default()
        }),
        Packet::ViewControl(ViewControl {
            view_id: 0,
            entity_id: 0,
            ..ViewControl::default()
        }),
        Packet::ViewDefinition(ViewDefinition {
            view_id: 0,
            view_type: 3,
            ..ViewDefinition::default()
        }),
    ];
    send(&mut w, 1, view.clone());
    w.step(0.1, &mut q);
    assert_eq!(snap(&w).nvg_of(0).map(|n| n.gain), Some(1.0));
    let mut packets = view;
    packets.push(Packet::SensorControl(SensorControl {
        view_id: 0,
        sensor_on: true,
        gain: 1.5,
        ..SensorControl::default()
    }));
    send(&mut w, 2, packets);
    w.step(0.1, &mut q);
    let gain = snap(&w).nvg_of(0).map(|n| n.gain).expect("an NVG view");
    assert!((gain - 10.0).abs() < 1e-4, "gain 1.5 clamped to 1: {gain}");
    let mut told = String::new();
    for m in w.host_message(&mut q, 0).packets {
        if let Packet::ImageGeneratorMessage(m) = m {
            told.push_str(&m.text);
        }
    }
    assert!(told.contains("clamped"), "the host is told: {told}");
}

#[test]
fn entity_lamps_follow_the_scenario_and_the_hosts_component_control() {
    let (lat, lon) = centre();
    let mut q = query();
    let mut w = world(&format!(
        "[view]\neye = [{lat}, {lon}, 300.0]\n\
         [[entities]]\nid = 1\nmodel = \"truck\"\nlat_deg = {lat}\nlon_deg = {lon}\nclamp = \"height\"\n\
         lights = [\"head\", \"tail\"]\n\
         [[light]]\nlat_deg = {lat}\nlon_deg = {lon}\nalt_m = 110.0\ncandela = 300.0\n\
         [[flare]]\nlat_deg = {lat}\nlon_deg = {lon}\nalt_m = 700.0\nat_s = 1.0\nkind = \"155mm\"\n"
    ));
    w.step(0.1, &mut q);
    // Two headlamps, two tail lamps, the standing lamp; the flare is not lit yet.
    assert_eq!(snap(&w).lights.len(), 5);
    for _ in 0..20 {
        w.step(0.1, &mut q);
    }
    let lit = snap(&w);
    assert_eq!(lit.lights.len(), 6, "the flare burns");
    assert!(lit
        .lights
        .iter()
        .any(|l| l.spectrum == cig_environment::nvg::LightSpectrum::Flare));
    // The host switches the truck's lamps to headlamps and brake lamps (bits 0 and 2).
    let switch = |mask: u32, state: u8| {
        Packet::ComponentControl(ComponentControl {
            component_class: cig_ig::lights::COMPONENT_CLASS_ENTITY,
            component_id: cig_ig::lights::LIGHTS_COMPONENT,
            instance_id: 1,
            component_state: state,
            data: [mask, 0, 0, 0, 0, 0],
        })
    };
    send(&mut w, 1, vec![switch(0b101, 1)]);
    w.step(0.1, &mut q);
    let s = snap(&w);
    assert_eq!(
        s.lights.len(),
        6,
        "head and brake lamps instead of head and tail"
    );
    send(&mut w, 2, vec![switch(0b101, 0)]);
    w.step(0.1, &mut q);
    assert_eq!(snap(&w).lights.len(), 2, "all off: the lamp and the flare");
}
