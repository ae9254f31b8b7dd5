//! The physical sky, exposure and aerial perspective through the real renderer (lavapipe when
//! there is no GPU): behaviour compared within each test, never absolute colours.

mod common;

use cig_geo::{EnuFrame, Geodetic};
use cig_render::Image;
use cig_scene::lighting::{Fog, FogMode, SkyModel};
use cig_scene::models::{Model, ModelMesh};
use cig_scene::{EntityInstance, FrameSnapshot, Hpr};
use common::*;
use glam::{DVec3, Vec3};

/// The first minute after `from_unix_s` at which the sun sinks below `altitude_deg`.
fn sun_sinks_below(eye: Geodetic, from_unix_s: f64, altitude_deg: f64) -> f64 {
    (0..24 * 60)
        .map(|m| from_unix_s + 60.0 * f64::from(m))
        .find(|&t| sun_at(eye, t).1 < altitude_deg)
        .expect("the sun sets within a day")
}

fn pixel(image: &Image, x: u32, y: u32) -> [f64; 3] {
    let i = ((y * image.width + x) * 4) as usize;
    [0, 1, 2].map(|c| f64::from(image.rgba[i + c]))
}

fn mean(image: &Image) -> f64 {
    let n = image.rgba.len() / 4;
    image
        .rgba
        .chunks_exact(4)
        .map(|p| (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0)
        .sum::<f64>()
        / n as f64
}

#[test]
fn the_sky_is_blue_overhead_at_noon_and_red_toward_the_setting_sun() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = Geodetic::new(36.0, -122.0, 10.0);
    let noon = unix(2026, 6, 21, 20.1);
    let mut snapshot = FrameSnapshot::new(noon, vec![view(eye, (0.0, 80.0, 0.0), 40.0, (96, 64))]);
    snapshot.fog = Fog::from_visibility(FogMode::Off, 1e6);
    let (up, _) = render(&mut renderer, &cache, &snapshot, false);
    write_png(&up, &out_dir().join("sky_noon_up.png"));
    let [r, _, b] = pixel(&up, 48, 32);
    assert!(b > r + 40.0, "overhead at noon: red {r}, blue {b}");

    // Sunset: the sun half a degree up; look at it from just above the horizon.
    let sunset = sun_sinks_below(eye, unix(2026, 6, 22, 1.0), 0.5);
    let (azimuth, _) = sun_at(eye, sunset);
    snapshot.unix_time_s = sunset;
    snapshot.views[0] = view(eye, (azimuth, 3.0, 0.0), 40.0, (96, 64));
    let (toward, _) = render(&mut renderer, &cache, &snapshot, false);
    write_png(&toward, &out_dir().join("sky_sunset_toward.png"));
    // A column beside the sun, from the horizon up: the low sky glows red.
    let [r, _, b] = pixel(&toward, 20, 34);
    assert!(r > b + 20.0, "toward the setting sun: red {r}, blue {b}");
    let flat = {
        snapshot.sky.model = SkyModel::Flat;
        render(&mut renderer, &cache, &snapshot, false).0
    };
    assert!(
        mean(&toward) != mean(&flat),
        "the flat sky differs from the physical one"
    );
}

#[test]
fn exposure_orders_noon_dusk_moonlight_and_a_moonless_night_and_the_moon_lights_the_ground() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let site = Geodetic::new(36.0159, -121.1854, 0.0);
    let frame = EnuFrame::new(site);
    let g = frame.enu_to_geodetic(DVec3::new(-1500.0, -1500.0, 0.0));
    let ground = cig_terrain::QuerySession::new(cache.clone())
        .hot(g.lat_deg, g.lon_deg)
        .expect("inside the test database")
        .height_ellipsoid_m();
    let eye = Geodetic::new(g.lat_deg, g.lon_deg, ground + 250.0);
    let v = view(eye, (40.0, -10.0, 0.0), 60.0, (96, 64));
    let shot = |renderer: &mut cig_render::Renderer, unix_s: f64| {
        let snapshot = FrameSnapshot::new(unix_s, vec![v]);
        render(renderer, &cache, &snapshot, false).0
    };
    let noon_s = unix(2024, 6, 21, 20.0);
    // Civil dusk (sun 5 degrees down) that evening.
    let dusk_s = sun_sinks_below(site, unix(2024, 6, 22, 1.0), -5.0);
    // Full moon 2024-06-22 01:08 UTC, high at local midnight; new moon 2024-07-05 22:57 UTC.
    let moonlit_s = unix(2024, 6, 22, 8.0);
    let moonless_s = unix(2024, 7, 6, 8.0);
    let noon = shot(&mut renderer, noon_s);
    let dusk = shot(&mut renderer, dusk_s);
    let moonlit = shot(&mut renderer, moonlit_s);
    let moonless = shot(&mut renderer, moonless_s);
    for (name, image) in [
        ("noon", &noon),
        ("dusk", &dusk),
        ("moonlit", &moonlit),
        ("moonless", &moonless),
    ] {
        write_png(image, &out_dir().join(format!("exposure_{name}.png")));
    }
    // The ground (the lower half of the frame): the sky is always brighter than the ground it
    // lights at dusk, so the whole frame's mean depends on the framing.
    let ground = |i: &Image| {
        let half = (i.rgba.len() / 8) * 4;
        mean(&Image {
            width: i.width,
            height: i.height / 2,
            rgba: i.rgba[half..].to_vec(),
        })
    };
    let (n, d, m, k) = (
        ground(&noon),
        ground(&dusk),
        ground(&moonlit),
        ground(&moonless),
    );
    assert!(
        n > d && d > m && m > k,
        "noon {n}, dusk {d}, moonlit {m}, moonless {k}"
    );
    // A moonlit night is readable, not black.
    assert!(m > 25.0, "moonlit mean {m}");
    // The night is bluer than the day (the scotopic shift).
    let blueness = |i: &Image| {
        i.rgba
            .chunks_exact(4)
            .map(|p| f64::from(p[2]) - f64::from(p[0]))
            .sum::<f64>()
            / (i.rgba.len() / 4) as f64
    };
    assert!(
        blueness(&moonlit) > blueness(&noon),
        "{} vs {}",
        blueness(&moonlit),
        blueness(&noon)
    );
}

#[test]
fn exposure_compensation_and_a_fixed_exposure_act_on_the_frame() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = Geodetic::new(36.0, -122.0, 20.0);
    let v = view(eye, (0.0, 0.0, 0.0), 60.0, (64, 48));
    let mut snapshot = FrameSnapshot::new(unix(2024, 7, 6, 8.0), vec![v]);
    let (auto, _) = render(&mut renderer, &cache, &snapshot, false);
    snapshot.sky.exposure_compensation_ev = 2.0;
    let (brighter, _) = render(&mut renderer, &cache, &snapshot, false);
    assert!(
        mean(&brighter) > mean(&auto) * 1.3,
        "{} vs {}",
        mean(&brighter),
        mean(&auto)
    );
    // Exposed for daylight, the moonless night is black.
    snapshot.sky.exposure_compensation_ev = 0.0;
    snapshot.sky.fixed_exposure_ev = Some(cig_scene::lighting::exposure_value(1.0e5));
    let (daylight, _) = render(&mut renderer, &cache, &snapshot, false);
    assert!(mean(&daylight) < 2.0, "{}", mean(&daylight));
}

fn white_block() -> Model {
    box_model("block", 300.0, 300.0, [180, 180, 180, 255])
}

/// The exposed linear radiance of an 8-bit sRGB pixel of a daylight frame: the tone map's sRGB
/// encoding and ACES curve undone (no scotopic shift by day).
fn exposed_radiance(px: [f64; 3]) -> [f64; 3] {
    px.map(|v| {
        let e = v / 255.0;
        let y = if e <= 0.04045 {
            e / 12.92
        } else {
            ((e + 0.055) / 1.055).powf(2.4)
        };
        // y = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), solved for x.
        let (a, b, c) = (2.51 - 2.43 * y, 0.03 - 0.59 * y, -0.14 * y);
        (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
    })
}

/// A box standing on the ground, `size_m` square and `height_m` high, of one colour, at every
/// level of detail. A black one shows the air's in-scattered light alone.
fn box_model(name: &str, size_m: f32, height_m: f32, rgba: [u8; 4]) -> Model {
    let mut mesh = ModelMesh::default();
    let h = size_m / 2.0;
    mesh.add_box(Vec3::new(-h, -h, 0.0), Vec3::new(h, h, height_m), rgba);
    Model::new(name, vec![mesh.clone(), mesh.clone(), mesh])
}

#[test]
fn aerial_perspective_matches_a_march_of_the_same_air() {
    // Black boxes' in-scattered light against the sky 15 degrees up, both drawn, and the same
    // ratio from cig_environment's march to the box (64 steps) and to space. Slabs on the sea end
    // descending rays near where the table's ray meets the ground: the sky-view source function
    // times 1 - T(d) must give the march's light to within 8 % (measured: 3 %). Towers end level
    // rays that would have gone on for hundreds of kilometres, so their share 1 - T(d) is a small
    // part of the ray's 1 - T(ray), and the source function is the whole ray's mean: within 12 %
    // (measured: 4 % by day, 8 % in the red with the sun 11 degrees up, the documented limit).
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = Geodetic::new(36.0, -122.0, 1500.0);
    let at_eye = EnuFrame::new(eye);
    let sea_level = EnuFrame::new(Geodetic::new(36.0, -122.0, 0.0));
    struct Target {
        name: String,
        north_m: f64,
        size_m: f64,
        height_m: f64,
        /// The aimed point: its distance north and height.
        aim_north_m: f64,
        aim_height_m: f64,
        /// The relative error allowed.
        allowed: f64,
    }
    let slabs = [3_000.0, 6_000.0, 12_000.0, 25_000.0].map(|d| Target {
        name: format!("slab {d}"),
        north_m: d,
        size_m: 0.15 * d,
        height_m: 5.0,
        aim_north_m: d,
        aim_height_m: 5.0,
        allowed: 0.08,
    });
    let towers = [4_000.0, 10_000.0, 20_000.0].map(|d| Target {
        name: format!("tower {d}"),
        north_m: d,
        size_m: 0.04 * d,
        height_m: 3000.0,
        aim_north_m: 0.98 * d,
        aim_height_m: eye.alt_m,
        allowed: 0.12,
    });
    let targets: Vec<Target> = slabs.into_iter().chain(towers).collect();
    renderer.set_models(
        targets
            .iter()
            .map(|t| box_model(&t.name, t.size_m as f32, t.height_m as f32, [0, 0, 0, 255]))
            .collect(),
    );
    // One narrow frame aimed at each target, all at one fixed exposure.
    let seen =
        |renderer: &mut cig_render::Renderer, time: f64, pitch: f64, at: Option<(&str, f64)>| {
            let mut snapshot =
                FrameSnapshot::new(time, vec![view(eye, (0.0, pitch, 0.0), 3.0, (16, 16))]);
            snapshot.fog = Fog::from_visibility(FogMode::Off, 1e6);
            snapshot.sky.fixed_exposure_ev = Some(14.0);
            if let Some((model, d)) = at {
                let at = sea_level.enu_to_geodetic(DVec3::new(0.0, d, 0.0));
                snapshot.entities = vec![EntityInstance {
                    id: 1,
                    cue_important: false,
                    critical_radius_m: None,
                    model: model.into(),
                    position: Geodetic::new(at.lat_deg, at.lon_deg, 0.0),
                    orientation: Hpr::default(),
                }];
            }
            let (image, _) = render(renderer, &cache, &snapshot, false);
            let mut sum = [0.0; 3];
            for (x, y) in [(7, 7), (8, 7), (7, 8), (8, 8)] {
                let p = exposed_radiance(pixel(&image, x, y));
                for c in 0..3 {
                    sum[c] += p[c] / 4.0;
                }
            }
            sum
        };
    let atmosphere = cig_environment::atmosphere::Atmosphere::earth();
    // Mid-morning (the sun 35 degrees up, to the east) and evening (11 degrees, west-north-west).
    for time in [unix(2026, 6, 21, 16.0), unix(2026, 6, 21, 26.4)] {
        let (sun_az, sun_alt) = sun_at(eye, time);
        let (az, alt) = (sun_az.to_radians(), sun_alt.to_radians());
        let sun_enu = [alt.cos() * az.sin(), alt.cos() * az.cos(), alt.sin()];
        // The sky 15 degrees up sets the scale between the frame's units and the march's.
        let sky = seen(&mut renderer, time, 15.0, None);
        let sky_dir = [0.0, 15f64.to_radians().cos(), 15f64.to_radians().sin()];
        let sky_ref = atmosphere.sky_radiance(eye.alt_m, sky_dir, sun_enu);
        for t in &targets {
            let name = &t.name;
            let g = sea_level.enu_to_geodetic(DVec3::new(0.0, t.aim_north_m, 0.0));
            let target =
                at_eye.geodetic_to_enu(Geodetic::new(g.lat_deg, g.lon_deg, t.aim_height_m));
            let range_m = target.length();
            let dir = target / range_m;
            let pitch = dir.z.asin().to_degrees();
            let drawn_light = seen(&mut renderer, time, pitch, Some((name, t.north_m)));
            let (in_scattered, _) =
                atmosphere.march(eye.alt_m, [dir.x, dir.y, dir.z], sun_enu, range_m, 64);
            for c in 0..3 {
                let drawn = drawn_light[c] / sky[c];
                let expected = in_scattered[c] / sky_ref[c];
                assert!(
                    (drawn / expected - 1.0).abs() < t.allowed,
                    "sun at {sun_alt:.1} degrees, {name} m away, {pitch:.2} degrees, channel \
                     {c}: {drawn:.4} of the sky drawn, {expected:.4} marched"
                );
            }
        }
    }
}

#[test]
fn aerial_perspective_takes_far_objects_toward_the_sky_colour() {
    let db = sea();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    renderer.set_models(vec![white_block()]);
    let eye = Geodetic::new(36.0, -122.0, 150.0);
    let frame = EnuFrame::new(Geodetic::new(36.0, -122.0, 0.0));
    // The same block 3 km and 30 km north, seen at the same size (fields of view in ratio).
    let measure = |renderer: &mut cig_render::Renderer, distance_m: f64, fov_deg: f64| {
        let at = frame.enu_to_geodetic(DVec3::new(0.0, distance_m, 0.0));
        let mut snapshot = FrameSnapshot::new(
            unix(2026, 6, 21, 20.0),
            vec![view(eye, (0.0, 0.0, 0.0), fov_deg, (64, 64))],
        );
        snapshot.fog = Fog::from_visibility(FogMode::Off, 1e6);
        snapshot.entities = vec![EntityInstance {
            id: 1,
            cue_important: false,
            critical_radius_m: None,
            model: "block".into(),
            position: Geodetic::new(at.lat_deg, at.lon_deg, 0.0),
            orientation: Hpr::default(),
        }];
        let (image, _) = render(renderer, &cache, &snapshot, false);
        write_png(&image, &out_dir().join(format!("aerial_{distance_m}.png")));
        // The block's face (below the centre: the eye is at half its height) and the sky
        // straight above it (the top rows).
        let block = pixel(&image, 32, 33);
        let sky = pixel(&image, 32, 2);
        (block, sky)
    };
    let (near, near_sky) = measure(&mut renderer, 3000.0, 10.0);
    let (far, far_sky) = measure(&mut renderer, 30_000.0, 1.0);
    let distance = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let (dn, df) = (distance(near, near_sky), distance(far, far_sky));
    assert!(df < 0.7 * dn, "block to sky: near {dn:.1}, far {df:.1}");
    // Blue-grey by day: the far block is bluer than the near one.
    assert!(
        far[2] - far[0] > near[2] - near[0],
        "near {near:?}, far {far:?}"
    );
}
