//! Thermal sensor views on lavapipe (or any GPU): what the issue asks the picture to show. A
//! running tank's engine deck is the hottest part of a night frame in white-hot and the darkest
//! in black-hot; a tank behind smoke is hidden in the visible and seen in the long-wave
//! infrared; the clear sky is colder than the ground; the sensor's polarity and manual window.

mod common;

use cig_effects::PuffInstance;
use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::thermal::{Polarity, SensorView, ThermalScene};
use cig_scene::{EntityInstance, FrameSnapshot, Hpr};
use cig_thermal::{
    Aerosol, EntityHeat, EntityThermalInput, IrAtmosphere, IrBand, ModelAtmosphere, Orientations,
    SurfaceTable, ThermalMaterial, ThermalWeather,
};
use common::*;
use glam::DVec3;
use std::sync::Arc;

const SIZE: (u32, u32) = (160, 120);
/// 2026-06-22 09:00 UTC: 01:00 in California.
const NIGHT_UNIX_S: f64 = MORNING_UNIX_S + 14.0 * 3600.0;

fn tank_at(at: Geodetic, heading_deg: f64) -> EntityInstance {
    EntityInstance {
        id: 1,
        model: "tank".into(),
        position: at,
        orientation: Hpr {
            heading_deg,
            pitch_deg: 0.0,
            roll_deg: 0.0,
        },
        cue_important: false,
        critical_radius_m: None,
    }
}

/// The thermal state at `unix_s` over the hills, the tank's engine running or not.
fn thermal(unix_s: f64, engine_on: bool) -> Arc<ThermalScene> {
    let time = cig_environment::UtcTime::from_unix_seconds(unix_s).expect("time");
    let table = SurfaceTable::spin_up(
        36.0159,
        -121.1854,
        time,
        ThermalWeather::default(),
        &ThermalMaterial::ALL,
        Orientations::Standard,
    )
    .expect("table");
    let heat = EntityHeat::steady(
        &EntityThermalInput {
            engine_on,
            speed_mps: 0.0,
            burning: false,
            destroyed: false,
        },
        table.air_k(),
    );
    Arc::new(ThermalScene::from_table(
        &table,
        IrAtmosphere::model(ModelAtmosphere::MidLatitudeSummer, Aerosol::Rural),
        vec![(1, heat.rise_k.map(|r| r as f32))],
    ))
}

fn quiet(band: IrBand, polarity: Polarity) -> SensorView {
    SensorView {
        polarity,
        netd_k: 0.0,
        fixed_pattern: 0.0,
        ..SensorView::new(band)
    }
}

/// Where the eye and the tank stand: the tank on the hills, the eye 60 m south of it and
/// 12 m above the ground there.
fn eye_and_tank() -> (Geodetic, Geodetic) {
    (hills_point(-60.0, 0.0, 12.0), hills_point(0.0, 0.0, 0.0))
}

/// The tank's centre from the eye, east-north-up metres.
fn toward_tank() -> DVec3 {
    let (eye, tank) = eye_and_tank();
    EnuFrame::new(eye).geodetic_to_enu(tank) + DVec3::new(0.0, 0.0, 1.5)
}

/// A frame looking north at the tank 60 m ahead (the view's axis on the tank).
fn tank_frame(unix_s: f64, sensor: Option<SensorView>, scene: Arc<ThermalScene>) -> FrameSnapshot {
    let (eye, tank) = eye_and_tank();
    let d = toward_tank();
    let pitch = d.z.atan2(d.y).to_degrees();
    let mut snapshot = FrameSnapshot::new(unix_s, vec![view(eye, (0.0, pitch, 0.0), 24.0, SIZE)]);
    snapshot.entities = vec![tank_at(tank, 200.0)];
    snapshot.culture = false;
    snapshot.sensors = vec![sensor];
    snapshot.thermal = Some(scene);
    snapshot
}

fn grey(image: &Image, i: usize) -> u8 {
    image.rgba[i * 4]
}

#[test]
fn a_running_engine_deck_is_the_hottest_part_of_a_night_frame() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let running = thermal(NIGHT_UNIX_S, true);
    let off = thermal(NIGHT_UNIX_S, false);
    for polarity in [Polarity::WhiteHot, Polarity::BlackHot] {
        let sensor = Some(quiet(IrBand::Lwir, polarity));
        let (hot, stats) = render(
            &mut r,
            &cache,
            &tank_frame(NIGHT_UNIX_S, sensor, running.clone()),
            false,
        );
        assert_eq!(stats.entities_drawn, 1);
        let (cold, _) = render(
            &mut r,
            &cache,
            &tank_frame(NIGHT_UNIX_S, sensor, off.clone()),
            false,
        );
        write_png(
            &hot,
            &out_dir().join(format!("sensor_engine_{polarity:?}.png")),
        );
        let pixels = (SIZE.0 * SIZE.1) as usize;
        // Where the engine's heat shows: the running frame differs from the cold one.
        let heated: Vec<usize> = (0..pixels)
            .filter(|&i| (i32::from(grey(&hot, i)) - i32::from(grey(&cold, i))).abs() > 25)
            .collect();
        assert!(
            heated.len() > 10,
            "{polarity:?}: the engine shows on {} pixels",
            heated.len()
        );
        let extreme = |i: usize| match polarity {
            Polarity::WhiteHot => i32::from(grey(&hot, i)),
            Polarity::BlackHot => 255 - i32::from(grey(&hot, i)),
        };
        let best_heated = heated.iter().map(|&i| extreme(i)).max().unwrap_or(0);
        let best_elsewhere = (0..pixels)
            .filter(|i| !heated.contains(i))
            .map(extreme)
            .max()
            .unwrap_or(0);
        assert!(
            best_heated > best_elsewhere + 5,
            "{polarity:?}: engine {best_heated} vs the rest of the frame {best_elsewhere}"
        );
    }
}

/// A wall of thick smoke 25 m in front of the eye, across the line of sight to the tank.
fn smoke_wall(eye: Geodetic) -> Vec<PuffInstance> {
    let enu = EnuFrame::new(eye);
    let centre = toward_tank() * (25.0 / toward_tank().length());
    let mut puffs = Vec::new();
    for east in [-12.0, -4.0, 4.0, 12.0] {
        for up in [-6.0, 0.0, 6.0] {
            let e = enu.enu_vector_to_ecef(centre + DVec3::new(east, 0.0, up));
            puffs.push(PuffInstance {
                position_eye_m: [e.x as f32, e.y as f32, e.z as f32],
                radius_m: 14.0,
                colour_rgb: [0.12, 0.12, 0.12],
                opacity: 0.998,
                emissive: 0.0,
                temperature_k: 290.0,
                kind: 0,
                effect: 1,
            });
        }
    }
    puffs
}

#[test]
fn a_tank_behind_smoke_is_hidden_in_the_visible_and_seen_in_lwir() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let day = MORNING_UNIX_S;
    let scene = thermal(day, true);
    let mut diffs = Vec::new();
    for sensor in [None, Some(quiet(IrBand::Lwir, Polarity::WhiteHot))] {
        let mut with_tank = tank_frame(day, sensor, scene.clone());
        with_tank.puff_origin_ecef_m = with_tank.views[0].eye.to_ecef();
        with_tank.puffs = smoke_wall(with_tank.views[0].eye);
        let mut without = with_tank.clone();
        without.entities.clear();
        let (a, _) = render(&mut r, &cache, &with_tank, false);
        let (b, _) = render(&mut r, &cache, &without, false);
        let name = if sensor.is_some() { "lwir" } else { "visible" };
        write_png(&a, &out_dir().join(format!("sensor_smoke_{name}.png")));
        let largest = a
            .rgba
            .iter()
            .zip(&b.rgba)
            .map(|(x, y)| (i32::from(*x) - i32::from(*y)).abs())
            .max()
            .unwrap_or(0);
        diffs.push(largest);
    }
    assert!(
        diffs[0] <= 6,
        "the tank shows through the smoke in the visible: {}",
        diffs[0]
    );
    assert!(
        diffs[1] >= 40,
        "the tank is not seen through the smoke in LWIR: {}",
        diffs[1]
    );
}

#[test]
fn the_clear_sky_is_colder_than_the_ground_and_black_hot_inverts() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let scene = thermal(MORNING_UNIX_S, true);
    let eye = hills_point(-60.0, 0.0, 12.0);
    let frame = |sensor: SensorView| {
        let mut s =
            FrameSnapshot::new(MORNING_UNIX_S, vec![view(eye, (0.0, 2.0, 0.0), 60.0, SIZE)]);
        s.culture = false;
        s.sensors = vec![Some(sensor)];
        s.thermal = Some(scene.clone());
        s
    };
    for band in [IrBand::Lwir, IrBand::Mwir] {
        let (white, _) = render(
            &mut r,
            &cache,
            &frame(quiet(band, Polarity::WhiteHot)),
            false,
        );
        let (black, _) = render(
            &mut r,
            &cache,
            &frame(quiet(band, Polarity::BlackHot)),
            false,
        );
        let w = SIZE.0 as usize;
        let top = grey(&white, 5 * w + w / 2);
        let bottom = grey(&white, (SIZE.1 as usize - 5) * w + w / 2);
        assert!(bottom > top + 40, "{band:?}: ground {bottom} vs sky {top}");
        for i in [5 * w + w / 2, (SIZE.1 as usize - 5) * w + w / 2] {
            let sum = i32::from(grey(&white, i)) + i32::from(grey(&black, i));
            assert!(
                (sum - 255).abs() <= 2,
                "{band:?}: polarity does not invert ({sum})"
            );
        }
        // Grey: the channels are equal on a white display.
        assert!(white.rgba.chunks(4).all(|p| p[0] == p[1] && p[1] == p[2]));
    }
    // A manual window: gain 1 (2 K wide) centred far above the scene shows it black.
    let mut manual = quiet(IrBand::Lwir, Polarity::WhiteHot);
    manual.manual_gain_level = Some((1.0, 1.0));
    let (dark, _) = render(&mut r, &cache, &frame(manual), false);
    assert!(
        dark.rgba.chunks(4).all(|p| p[0] < 5),
        "a 359-361 K window shows nothing"
    );
}

#[test]
fn ac_coupling_takes_the_level_out_of_each_line() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let scene = thermal(MORNING_UNIX_S, true);
    let eye = hills_point(-60.0, 0.0, 12.0);
    let frame = |ac_us: f32| {
        let mut s =
            FrameSnapshot::new(MORNING_UNIX_S, vec![view(eye, (0.0, 2.0, 0.0), 60.0, SIZE)]);
        s.culture = false;
        let mut sensor = quiet(IrBand::Lwir, Polarity::WhiteHot);
        sensor.ac_coupling_us = ac_us;
        // A fixed window, so the two frames compare grey for grey.
        sensor.manual_gain_level = Some((0.6, 0.45));
        s.sensors = vec![Some(sensor)];
        s.thermal = Some(scene.clone());
        s
    };
    let (plain, _) = render(&mut r, &cache, &frame(0.0), false);
    let (coupled, _) = render(&mut r, &cache, &frame(1.0), false);
    write_png(&coupled, &out_dir().join("sensor_ac_coupled.png"));
    let w = SIZE.0 as usize;
    // Sky rows against ground rows, in the middle of their lines.
    let level = |img: &Image, row: usize| i32::from(grey(img, row * w + w * 3 / 4));
    let plain_gap = (level(&plain, 5) - level(&plain, SIZE.1 as usize - 5)).abs();
    let coupled_gap = (level(&coupled, 5) - level(&coupled, SIZE.1 as usize - 5)).abs();
    assert!(
        plain_gap > 40,
        "sky and ground differ without coupling: {plain_gap}"
    );
    // The coupled frame is a picture (the level added back sits mid-window), not saturated.
    let mid = level(&coupled, SIZE.1 as usize / 2);
    assert!((60..=200).contains(&mid), "coupled mid-frame grey {mid}");
    assert!(
        coupled_gap * 3 < plain_gap,
        "AC coupling takes each line's level out: {coupled_gap} against {plain_gap}"
    );
}

#[test]
fn clouds_are_warmer_than_the_clear_sky_in_lwir() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let scene = thermal(MORNING_UNIX_S, true);
    let eye = hills_point(-60.0, 0.0, 12.0);
    let frame = |clouds: bool| {
        let mut s = FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(eye, (0.0, 30.0, 0.0), 40.0, SIZE)],
        );
        s.culture = false;
        if clouds {
            s.cloud_layers = vec![cig_environment::clouds::CloudLayer::new(
                eye.alt_m + 800.0,
                400.0,
                1.0,
                cig_environment::CloudKind::Stratus,
            )];
            s.cloud_cover_fraction = 1.0;
        }
        let mut sensor = quiet(IrBand::Lwir, Polarity::WhiteHot);
        // One window for both frames: 240-300 K.
        sensor.manual_gain_level = Some((0.12, 0.357));
        s.sensors = vec![Some(sensor)];
        s.thermal = Some(scene.clone());
        s
    };
    let (clear, _) = render(&mut r, &cache, &frame(false), false);
    let (cloudy, stats) = render(&mut r, &cache, &frame(true), false);
    assert_eq!(stats.cloud_layers_drawn, 1);
    write_png(&cloudy, &out_dir().join("sensor_overcast.png"));
    let mean = |img: &Image| {
        img.rgba.chunks(4).map(|p| f64::from(p[0])).sum::<f64>() / f64::from(SIZE.0 * SIZE.1)
    };
    assert!(
        mean(&cloudy) > mean(&clear) + 30.0,
        "an overcast at ~280 K is brighter than the clear sky: {} against {}",
        mean(&cloudy),
        mean(&clear)
    );
}

#[test]
fn a_fresh_crater_glows_on_the_ground() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let (_, tank) = eye_and_tank();
    let frame = |spot: bool| {
        let mut scene = (*thermal(NIGHT_UNIX_S, false)).clone();
        if spot {
            scene.hot_spots = vec![(tank.to_ecef().to_array(), 3.0, 300.0)];
        }
        let mut s = tank_frame(
            NIGHT_UNIX_S,
            Some(quiet(IrBand::Lwir, Polarity::WhiteHot)),
            Arc::new(scene),
        );
        s.entities.clear();
        s
    };
    let (plain, _) = render(&mut r, &cache, &frame(false), false);
    let (crater, _) = render(&mut r, &cache, &frame(true), false);
    write_png(&crater, &out_dir().join("sensor_crater.png"));
    // The view's axis is on the spot: the centre is the hottest there.
    let centre = ((SIZE.1 / 2) * SIZE.0 + SIZE.0 / 2) as usize;
    assert!(
        grey(&crater, centre) > grey(&plain, centre) + 60,
        "{} vs {}",
        grey(&crater, centre),
        grey(&plain, centre)
    );
    // The frame's hottest pixel is on the spot, a little below the view's axis (the axis aims
    // 1.5 m above the ground).
    let hottest = (0..(SIZE.0 * SIZE.1) as usize)
        .max_by_key(|&i| grey(&crater, i))
        .unwrap_or(0);
    let (x, y) = (hottest % SIZE.0 as usize, hottest / SIZE.0 as usize);
    let (cx, cy) = (SIZE.0 as usize / 2, SIZE.1 as usize / 2);
    assert!(
        x.abs_diff(cx) <= 12 && y.abs_diff(cy) <= 20,
        "hottest at {x}, {y}"
    );
}

#[test]
fn a_ground_fog_layer_veils_the_tank_less_in_lwir_than_in_the_visible() {
    let db = hills();
    let cache = cache(&db);
    let mut r = renderer(&cache);
    let scene = thermal(MORNING_UNIX_S, true);
    // The tank's whole contrast: the summed difference the tank makes to the frame.
    let mut contrast = |sensor: Option<SensorView>, fog: bool| {
        let mut with_tank = tank_frame(MORNING_UNIX_S, sensor, scene.clone());
        if fog {
            with_tank.ground_fog = Some(cig_scene::FogLayer {
                top_m: with_tank.views[0].eye.alt_m + 50.0,
                visibility_m: 120.0,
            });
        }
        let mut without = with_tank.clone();
        without.entities.clear();
        let (a, _) = render(&mut r, &cache, &with_tank, false);
        let (b, _) = render(&mut r, &cache, &without, false);
        a.rgba
            .iter()
            .zip(&b.rgba)
            .map(|(x, y)| f64::from((i32::from(*x) - i32::from(*y)).abs()))
            .sum::<f64>()
    };
    // A wide manual window (190-390 K), the same for clear and fogged frames: nothing of the
    // tank but its exhausts saturates.
    let mut lwir = quiet(IrBand::Lwir, Polarity::WhiteHot);
    lwir.manual_gain_level = Some((0.0, 0.5));
    let visible = contrast(None, true) / contrast(None, false);
    let infrared = contrast(Some(lwir), true) / contrast(Some(lwir), false);
    assert!(
        infrared < 0.9,
        "the fog veils the tank in LWIR too: {infrared}"
    );
    assert!(
        infrared > 1.5 * visible,
        "LWIR keeps more of the tank's contrast through fog: {infrared} against {visible}"
    );
}
