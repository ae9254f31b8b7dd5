//! The picture a trainee reads, on lavapipe (or any GPU): the night is dark against noon, the
//! exposure follows what the view shows (a low sun at dusk does not wash the frame out; a turn
//! from a dark view to the bright sky adapts over time, faster toward light than toward dark),
//! and clouds seen from above and below show no regular sampling pattern or half-resolution
//! blocks.

mod common;

use cig_environment::clouds::{CloudKind, CloudLayer, CloudOrigin};
use cig_geo::{EnuFrame, Geodetic};
use cig_render::{Adaptation, FrameStats, Image, Renderer};
use cig_scene::FrameSnapshot;
use cig_terrain::TileCache;
use common::*;
use glam::DVec3;

/// Display brightness of a pixel: the mean of its three 8-bit channels.
fn brightness(p: &[u8]) -> f64 {
    (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0
}

fn mean_brightness(image: &Image) -> f64 {
    image.rgba.chunks_exact(4).map(brightness).sum::<f64>() / (image.rgba.len() / 4) as f64
}

/// Rows `rows` of an image (a band of the frame).
fn rows(image: &Image, rows: std::ops::Range<u32>) -> Image {
    let w = image.width as usize * 4;
    Image {
        width: image.width,
        height: rows.end - rows.start,
        rgba: image.rgba[rows.start as usize * w..rows.end as usize * w].to_vec(),
    }
}

/// Share of pixels with a channel at the top of the display range (250 of 255 and above: the
/// tone curve's shoulder, where gradations are lost).
fn clipped_share(image: &Image) -> f64 {
    image
        .rgba
        .chunks_exact(4)
        .filter(|p| p[..3].iter().any(|&c| c >= 250))
        .count() as f64
        / (image.rgba.len() / 4) as f64
}

/// Standard deviation of the pixels' brightness (display levels).
fn spread(image: &Image) -> f64 {
    let mean = mean_brightness(image);
    let n = (image.rgba.len() / 4) as f64;
    (image
        .rgba
        .chunks_exact(4)
        .map(|p| (brightness(p) - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
}

/// A site on the hills database and the eye 250 m above the ground 1.5 km south-west of it.
fn hills_eye() -> Geodetic {
    let site = Geodetic::new(36.0159, -121.1854, 0.0);
    let g = EnuFrame::new(site).enu_to_geodetic(DVec3::new(-1500.0, -1500.0, 0.0));
    let ground = cig_terrain::QuerySession::new(cache(&hills()))
        .hot(g.lat_deg, g.lon_deg)
        .expect("inside the test database")
        .height_ellipsoid_m();
    Geodetic::new(g.lat_deg, g.lon_deg, ground + 250.0)
}

fn frame(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    adaptation: Adaptation,
) -> (Image, FrameStats) {
    render_adapted(renderer, cache, snapshot, false, adaptation)
}

#[test]
fn a_moonless_night_is_dark_and_a_full_moon_night_dim_against_noon() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // Looking north-east a little down: terrain below, sky above the ridges.
    let v = view(hills_eye(), (40.0, -4.0, 0.0), 60.0, (128, 96));
    let shot = |renderer: &mut Renderer, unix_s: f64| {
        let snapshot = FrameSnapshot::new(unix_s, vec![v]);
        let (image, stats) = frame(renderer, &cache, &snapshot, Adaptation::Settled);
        eprintln!(
            "{unix_s}: adapted {:+.2} EV, exposure {:.2} EV",
            stats.view_adaptation_ev, stats.exposure_ev
        );
        image
    };
    let noon = shot(&mut renderer, unix(2024, 6, 21, 20.0));
    // Full moon 2024-06-22 01:08 UTC, high at local midnight; new moon 2024-07-05 22:57 UTC.
    let full_moon = shot(&mut renderer, unix(2024, 6, 22, 8.0));
    let moonless = shot(&mut renderer, unix(2024, 7, 6, 8.0));
    for (name, image) in [
        ("noon", &noon),
        ("full_moon", &full_moon),
        ("moonless", &moonless),
    ] {
        write_png(image, &out_dir().join(format!("picture_night_{name}.png")));
    }
    let (n, f, m) = (
        mean_brightness(&noon),
        mean_brightness(&full_moon),
        mean_brightness(&moonless),
    );
    eprintln!("mean brightness: noon {n:.1}, full moon {f:.1}, moonless {m:.1}");
    assert!(m <= 0.25 * n, "moonless {m:.1} against noon {n:.1}");
    assert!(f <= 0.5 * n, "full moon {f:.1} against noon {n:.1}");
    // Yet the full-moon night is readable: the terrain is not black.
    assert!(f > 0.1 * n && f > 8.0, "full moon {f:.1}");
    // The moonless sky is nearly black: its brightest tenth of the top rows (stars apart: they
    // are a few pixels) stays dark.
    let mut sky: Vec<f64> = rows(&moonless, 0..12)
        .rgba
        .chunks_exact(4)
        .map(brightness)
        .collect();
    sky.sort_by(f64::total_cmp);
    let p90 = sky[sky.len() * 9 / 10];
    assert!(p90 < 24.0, "moonless sky, 90th percentile {p90:.1}");
}

/// The hills database at the demo's dusk: the eye 250 m up looking at the sun 3 degrees above
/// the horizon.
fn dusk_toward_the_sun() -> (FrameSnapshot, f64) {
    let eye = hills_eye();
    // The evening's first minute with the sun 3 degrees up, and its azimuth.
    let t = (0..24 * 60)
        .map(|m| unix(2026, 6, 22, 1.0) + 60.0 * f64::from(m))
        .find(|&t| sun_at(eye, t).1 < 3.0)
        .expect("the sun sets within a day");
    let azimuth = sun_at(eye, t).0;
    (
        FrameSnapshot::new(t, vec![view(eye, (azimuth, -2.0, 0.0), 60.0, (160, 120))]),
        azimuth,
    )
}

#[test]
fn the_dusk_view_toward_the_sun_keeps_its_sky_and_the_terrains_contrast() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (snapshot, _) = dusk_toward_the_sun();
    let (fixed, fixed_stats) = frame(&mut renderer, &cache, &snapshot, Adaptation::Off);
    let (adapted, stats) = frame(&mut renderer, &cache, &snapshot, Adaptation::Settled);
    write_png(&fixed, &out_dir().join("picture_dusk_natural.png"));
    write_png(&adapted, &out_dir().join("picture_dusk_adapted.png"));
    let (c_fixed, c_adapted) = (clipped_share(&fixed), clipped_share(&adapted));
    eprintln!(
        "dusk: clipped {:.1} % natural, {:.1} % adapted ({:.2} EV)",
        100.0 * c_fixed,
        100.0 * c_adapted,
        stats.view_adaptation_ev
    );
    // The view reproduces the complaint: exposed for the natural light it washes out.
    assert!(
        c_fixed > 0.10,
        "natural exposure clips {:.1} %",
        100.0 * c_fixed
    );
    assert!(
        c_adapted <= 0.10,
        "clipped {:.1} % adapted ({:.1} % with the natural exposure)",
        100.0 * c_adapted,
        100.0 * c_fixed
    );
    // The view darkened the exposure, and says so.
    assert!(stats.view_adaptation_ev < -0.5, "{stats:?}");
    assert!(stats.exposure_ev > fixed_stats.exposure_ev + 0.5);
    // The terrain (the lower third) keeps its contrast: not crushed to black.
    let terrain = rows(&adapted, 80..120);
    let (mean, sd) = (mean_brightness(&terrain), spread(&terrain));
    eprintln!("dusk terrain: mean {mean:.1}, spread {sd:.1}");
    assert!(
        mean > 6.0 && sd > 2.0,
        "terrain mean {mean:.1}, spread {sd:.1}"
    );
}

#[test]
fn a_turn_from_a_dark_view_to_the_bright_sky_adapts_over_time_faster_than_back() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = hills_eye();
    // An evening with the sun 10 degrees up: the sky around it is far brighter than the ground
    // on the other side, looking down.
    let t = (0..24 * 60)
        .map(|m| unix(2026, 6, 22, 0.0) + 60.0 * f64::from(m))
        .find(|&t| sun_at(eye, t).1 < 10.0)
        .expect("the sun sets within a day");
    let azimuth = sun_at(eye, t).0;
    let size = (64, 48);
    let ground = FrameSnapshot::new(
        t,
        vec![view(eye, (azimuth + 180.0, -60.0, 0.0), 40.0, size)],
    );
    let sky = FrameSnapshot::new(t, vec![view(eye, (azimuth + 25.0, 15.0, 0.0), 40.0, size)]);
    let settled = |renderer: &mut Renderer, s: &FrameSnapshot| {
        frame(renderer, &cache, s, Adaptation::Settled)
            .1
            .view_adaptation_ev
    };
    let sky_target = settled(&mut renderer, &sky);
    let ground_target = settled(&mut renderer, &ground);
    assert!(
        ground_target > sky_target + 0.5,
        "the ground view wants more exposure: {ground_target:.2} against {sky_target:.2} EV"
    );
    // Toward the sky in steps of 0.1 s: it takes time, each step moving it further.
    let mut toward_light = Vec::new();
    for _ in 0..40 {
        let (_, stats) = frame(&mut renderer, &cache, &sky, Adaptation::Step(0.1));
        toward_light.push(stats.view_adaptation_ev);
    }
    eprintln!("targets: ground {ground_target:.2} EV, sky {sky_target:.2} EV");
    let span = ground_target - sky_target;
    let moved = |ev: f64| (ground_target - ev) / span;
    assert!(moved(toward_light[0]) < 0.3, "{toward_light:?}");
    assert!(
        toward_light.windows(2).all(|w| w[1] <= w[0] + 1e-4),
        "monotone: {toward_light:?}"
    );
    assert!(moved(toward_light[39]) > 0.9, "after 4 s: {toward_light:?}");
    let after_1s_light = moved(toward_light[9]);
    // And back toward the ground: slower (dark adaptation).
    let mut toward_dark = Vec::new();
    for _ in 0..10 {
        let (_, stats) = frame(&mut renderer, &cache, &ground, Adaptation::Step(0.1));
        toward_dark.push(stats.view_adaptation_ev);
    }
    let back_after_1s = (toward_dark[9] - toward_light[39]) / (ground_target - toward_light[39]);
    eprintln!("after 1 s: {after_1s_light:.2} toward light, {back_after_1s:.2} toward dark");
    assert!(
        back_after_1s < 0.5 * after_1s_light && back_after_1s > 0.0,
        "after 1 s: {after_1s_light:.2} of the way toward light, {back_after_1s:.2} toward dark"
    );
}

#[test]
fn a_fixed_exposure_or_keyed_frame_is_not_adapted() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (mut snapshot, _) = dusk_toward_the_sun();
    snapshot.sky.fixed_exposure_ev = Some(8.0);
    let (_, stats) = frame(&mut renderer, &cache, &snapshot, Adaptation::Settled);
    assert_eq!(stats.view_adaptation_ev, 0.0);
    assert!(
        (stats.exposure_ev - 8.0).abs() < 1e-9,
        "{}",
        stats.exposure_ev
    );
}

const CLOUD_ORIGIN: CloudOrigin = CloudOrigin {
    lat_deg: 36.0,
    lon_deg: -122.0,
};

/// Luminance (display levels) of the central `n` x `n` pixels.
fn luma_crop(image: &Image, n: usize) -> Vec<f64> {
    let (w, h) = (image.width as usize, image.height as usize);
    let (x0, y0) = ((w - n) / 2, (h - n) / 2);
    let mut out = Vec::with_capacity(n * n);
    for y in y0..y0 + n {
        for x in x0..x0 + n {
            out.push(brightness(&image.rgba[(y * w + x) * 4..]));
        }
    }
    out
}

/// Power spectrum of an `n` x `n` field (mean removed, Hann-windowed so the crop's edges add no
/// power along the axes), by separable DFT.
fn power_spectrum(field: &[f64], n: usize) -> Vec<f64> {
    let mean = field.iter().sum::<f64>() / field.len() as f64;
    let hann: Vec<f64> = (0..n)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos())
        .collect();
    let field: Vec<f64> = field
        .iter()
        .enumerate()
        .map(|(i, v)| (v - mean) * hann[i % n] * hann[i / n])
        .collect();
    let mean = 0.0;
    let (cos, sin): (Vec<f64>, Vec<f64>) = (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            (a.cos(), a.sin())
        })
        .unzip();
    // Rows first.
    let mut rows = vec![(0.0, 0.0); n * n];
    for y in 0..n {
        for u in 0..n {
            let (mut re, mut im) = (0.0, 0.0);
            for x in 0..n {
                let v = field[y * n + x] - mean;
                let k = (u * x) % n;
                re += v * cos[k];
                im -= v * sin[k];
            }
            rows[y * n + u] = (re, im);
        }
    }
    let mut power = vec![0.0; n * n];
    for u in 0..n {
        for v in 0..n {
            let (mut re, mut im) = (0.0, 0.0);
            for y in 0..n {
                let (a, b) = rows[y * n + u];
                let k = (v * y) % n;
                let (c, s) = (cos[k], -sin[k]);
                re += a * c - b * s;
                im += a * s + b * c;
            }
            power[v * n + u] = re * re + im * im;
        }
    }
    power
}

/// The highest power at spatial frequencies above 0.1 cycles a pixel over the median power at
/// the same radius in other directions (rings 1/64 cycle a pixel wide): a regular dot, dither
/// or checker pattern is a narrow peak far above its ring, where the grain of random sample
/// offsets and the clouds' own shapes are spread evenly over directions.
fn spectral_peak(field: &[f64], n: usize) -> f64 {
    let power = power_spectrum(field, n);
    let ring_of = |i: usize| {
        let f = |k: usize| (k.min(n - k) as f64) / n as f64;
        (f(i % n).hypot(f(i / n)) * 64.0).round() as usize
    };
    let rings = ring_of(n / 2 * n + n / 2) + 1;
    let mut by_ring: Vec<Vec<f64>> = vec![Vec::new(); rings];
    for (i, &p) in power.iter().enumerate() {
        by_ring[ring_of(i)].push(p);
    }
    let medians: Vec<f64> = by_ring
        .iter_mut()
        .map(|ring| {
            ring.sort_by(f64::total_cmp);
            ring.get(ring.len() / 2).copied().unwrap_or(0.0).max(1e-9)
        })
        .collect();
    let mut worst: (f64, usize) = (0.0, 0);
    for (i, &p) in power.iter().enumerate() {
        let ring = ring_of(i);
        if ring > 6 && by_ring[ring].len() >= 16 && p / medians[ring] > worst.0 {
            worst = (p / medians[ring], i);
        }
    }
    eprintln!(
        "spectral peak {:.1} at ({}, {}) of {n}",
        worst.0,
        worst.1 % n,
        worst.1 / n
    );
    worst.0
}

/// Mean step between neighbouring pixels across the borders of `block`-pixel blocks, over the
/// mean step inside them (both directions).
fn block_border_ratio(image: &Image, block: usize) -> f64 {
    let (w, h) = (image.width as usize, image.height as usize);
    let at = |x: usize, y: usize| brightness(&image.rgba[(y * w + x) * 4..]);
    let (mut across, mut inside) = ((0.0, 0.0), (0.0, 0.0));
    for y in 0..h {
        for x in 0..w {
            for (nx, ny, coordinate) in [(x + 1, y, x), (x, y + 1, y)] {
                if nx >= w || ny >= h {
                    continue;
                }
                let step = (at(nx, ny) - at(x, y)).abs();
                let sum = if (coordinate + 1) % block == 0 {
                    &mut across
                } else {
                    &mut inside
                };
                sum.0 += step;
                sum.1 += 1.0;
            }
        }
    }
    (across.0 / across.1) / (inside.0 / inside.1).max(1e-9)
}

#[test]
fn cumulus_seen_from_above_and_below_shows_no_sampling_pattern_or_blocks() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let at = Geodetic::new(36.0159, -121.1854, 0.0);
    let ground_m = cig_terrain::QuerySession::new(cache.clone())
        .hot(at.lat_deg, at.lon_deg)
        .expect("inside the database")
        .height_ellipsoid_m();
    let size = (160, 160);
    let base_m = ground_m + 1200.0;
    let layer = CloudLayer::new(base_m, 900.0, 0.8, CloudKind::Cumulus);
    let cases = [
        ("above", base_m + 2500.0, -70.0),
        ("below", base_m - 700.0, 60.0),
    ];
    for (name, alt_m, pitch_deg) in cases {
        let eye = Geodetic::new(at.lat_deg, at.lon_deg, alt_m);
        let mut snapshot = FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(eye, (30.0, pitch_deg, 0.0), 50.0, size)],
        );
        snapshot.cloud_layers = vec![layer];
        snapshot.cloud_origin = CLOUD_ORIGIN;
        let (image, stats) = frame(&mut renderer, &cache, &snapshot, Adaptation::Settled);
        write_png(
            &image,
            &out_dir().join(format!("picture_cumulus_{name}.png")),
        );
        assert_eq!(stats.cloud_layers_drawn, 1);
        let field = luma_crop(&image, 128);
        let peak = spectral_peak(&field, 128);
        assert!(
            peak < 150.0,
            "{name}: a spectral peak {peak:.1} times its ring's median (a regular pattern)"
        );
        for block in [2, 4] {
            let ratio = block_border_ratio(&image, block);
            assert!(
                ratio < 1.15,
                "{name}: steps across {block}-pixel block borders {ratio:.2} times those inside"
            );
        }
    }
}

/// A flat database of 257 x 257 posts 30 m apart at 100 m, centred on 36 N 121 W (where its
/// four finest tiles of 128 cells meet), with each post's material from its (row, column)
/// relative to the centre.
fn flat_database(
    material_at: impl Fn(f64, f64) -> cig_terrain::Material,
) -> std::sync::Arc<cig_terrain::TerrainDatabase> {
    let (n, e) = cig_geo::metres_per_degree(36.0);
    let posts = 257;
    let grid = cig_terrain::GeoGrid {
        south_lat_deg: 36.0 - 128.0 * 30.0 / n,
        west_lon_deg: -121.0 - 128.0 * 30.0 / e,
        dlat_deg: 30.0 / n,
        dlon_deg: 30.0 / e,
        rows: posts,
        cols: posts,
    };
    let material = (0..posts * posts)
        .map(|i| material_at((i / posts) as f64 - 128.0, (i % posts) as f64 - 128.0))
        .collect();
    let raster = cig_terrain::Raster {
        grid,
        elevation_m: vec![100.0; posts * posts],
        material: Some(material),
    };
    database_from(&raster, 0.0)
}

/// Grass and rock split along a straight line at `angle_deg` from east through the middle,
/// each post by which side its centre lies on: the classic stair-stepped border.
fn diagonal_border_database(angle_deg: f64) -> std::sync::Arc<cig_terrain::TerrainDatabase> {
    let (s, c) = angle_deg.to_radians().sin_cos();
    flat_database(|row, col| {
        if col * s - row * c > 0.0 {
            cig_terrain::Material::Rock
        } else {
            cig_terrain::Material::Grass
        }
    })
}

/// The share of strong edges (Sobel magnitude over a quarter of the largest) whose direction
/// lies within 10 degrees of the image axes: a stair-stepped border is mostly such edges, a
/// smooth border at 37 degrees has next to none.
fn axis_aligned_edge_share(image: &Image) -> f64 {
    let (w, h) = (image.width as usize, image.height as usize);
    let at = |x: usize, y: usize| brightness(&image.rgba[(y * w + x) * 4..]);
    let mut edges = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let gx = at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x - 1, y)
                - at(x - 1, y + 1);
            let gy = at(x - 1, y + 1) + 2.0 * at(x, y + 1) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x, y - 1)
                - at(x + 1, y - 1);
            edges.push((gx.hypot(gy), gy.atan2(gx).to_degrees()));
        }
    }
    let strongest = edges.iter().map(|e| e.0).fold(0.0, f64::max);
    let strong: Vec<f64> = edges
        .iter()
        .filter(|e| e.0 > 0.25 * strongest)
        .map(|e| e.1.rem_euclid(90.0))
        .collect();
    let aligned = strong
        .iter()
        .filter(|&&a| !(10.0..=80.0).contains(&a))
        .count();
    aligned as f64 / strong.len().max(1) as f64
}

#[test]
fn a_diagonal_material_border_is_a_smooth_line_not_the_post_grids_stairs() {
    let db = diagonal_border_database(37.0);
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // Nadir, north up, from 250 m and 120 m: posts of 30 m span tens of pixels.
    for alt_m in [250.0, 120.0] {
        let eye = Geodetic::new(36.0, -121.0, 100.0 + alt_m);
        let snapshot = FrameSnapshot::new(
            unix(2024, 6, 21, 20.0),
            vec![view(eye, (0.0, -90.0, 0.0), 60.0, (256, 256))],
        );
        let (image, _) = frame(&mut renderer, &cache, &snapshot, Adaptation::Settled);
        write_png(
            &image,
            &out_dir().join(format!("picture_border_{alt_m:.0}m.png")),
        );
        let share = axis_aligned_edge_share(&image);
        eprintln!(
            "border from {alt_m} m: {:.1} % of strong edges on the axes",
            100.0 * share
        );
        assert!(
            share < 0.25,
            "from {alt_m} m, {:.1} % of the border's edges lie along the post grid",
            100.0 * share
        );
    }
}

#[test]
fn the_ground_ten_metres_below_shows_detail_that_flows_past_and_fades_without_shimmer() {
    use cig_terrain::Material;
    for material in [Material::Grass, Material::Sand, Material::PavedRoad] {
        let db = flat_database(|_, _| material);
        let cache = cache(&db);
        let mut renderer = renderer(&cache);
        let size = (320, 240);
        let shot = |renderer: &mut Renderer, north_m: f64| {
            let eye = EnuFrame::new(Geodetic::new(36.0, -121.0, 110.0))
                .enu_to_geodetic(DVec3::new(0.0, north_m, 0.0));
            let snapshot = FrameSnapshot::new(
                unix(2024, 6, 21, 20.0),
                vec![view(eye, (0.0, -20.0, 0.0), 60.0, size)],
            );
            frame(renderer, &cache, &snapshot, Adaptation::Settled).0
        };
        let here = shot(&mut renderer, 0.0);
        let ahead = shot(&mut renderer, 0.5);
        write_png(
            &here,
            &out_dir().join(format!("picture_detail_{material:?}.png")),
        );
        // The near ground (the bottom quarter, 10-20 m away): texture.
        let near = |i: &Image| rows(i, 180..240);
        let texture = spread(&near(&here));
        // Half a metre on, the near texture has moved (it is fixed to the ground).
        let flow = mean_abs_diff(&near(&here), &near(&ahead));
        // The far ground (just below the horizon, kilometres away): steady, no shimmer.
        let far = |i: &Image| rows(i, 76..88);
        let shimmer = mean_abs_diff(&far(&here), &far(&ahead));
        eprintln!(
            "{material:?}: near spread {texture:.1}, flow {flow:.2}, far change {shimmer:.2}"
        );
        assert!(
            texture > 2.0,
            "{material:?}: the near ground is flat ({texture:.2})"
        );
        assert!(
            flow > 1.0,
            "{material:?}: the texture does not move ({flow:.2})"
        );
        assert!(
            shimmer < 0.5 * flow && shimmer < 1.5,
            "{material:?}: the far ground shimmers ({shimmer:.2} against {flow:.2} near)"
        );
    }
}

#[test]
fn a_material_border_runs_on_across_node_and_tile_edges_without_a_seam() {
    let db = diagonal_border_database(37.0);
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // Nadir from 700 m over the database's middle, where four nodes and four finest tiles
    // meet: about 800 m of ground.
    let eye = Geodetic::new(36.0, -121.0, 800.0);
    let snapshot = FrameSnapshot::new(
        unix(2024, 6, 21, 20.0),
        vec![view(eye, (0.0, -90.0, 0.0), 60.0, (256, 256))],
    );
    let (image, stats) = frame(&mut renderer, &cache, &snapshot, Adaptation::Settled);
    write_png(&image, &out_dir().join("picture_border_seams.png"));
    assert!(
        stats.terrain_nodes >= 4 && stats.tiles_resident >= 4,
        "{stats:?}"
    );
    // Grass is greener than rock: in each column, the border lies as many rows from the top
    // (north) as the column has grass pixels (robust to the warp's small overhangs).
    let (w, h) = (image.width as usize, image.height as usize);
    let greenness = |x: usize, y: usize| {
        let p = &image.rgba[(y * w + x) * 4..];
        f64::from(p[1]) - 0.5 * (f64::from(p[0]) + f64::from(p[2]))
    };
    let crossings: Vec<Option<usize>> = (0..w)
        .map(|x| {
            let grass = (0..h).filter(|&y| greenness(x, y) >= 8.0).count();
            (grass > 0 && grass < h).then_some(grass)
        })
        .collect();
    let rows: Vec<(usize, usize)> = crossings
        .iter()
        .enumerate()
        .filter_map(|(x, y)| y.map(|y| (x, y)))
        .collect();
    assert!(
        rows.len() > w / 2,
        "the border crosses the view: {crossings:?}"
    );
    // A 37 degree line climbs 0.75 px a column and the warp bends it a little. Where it
    // crosses the node edges through the middle of the view (column 128, and row 128), it
    // runs on as smoothly as anywhere: no step at the edge.
    let steps: Vec<(usize, usize, usize)> = rows
        .windows(2)
        .filter(|p| p[1].0 == p[0].0 + 1)
        .map(|p| (p[0].0, p[0].1, p[1].1.abs_diff(p[0].1)))
        .collect();
    let largest = steps.iter().map(|s| s.2).max().unwrap_or(0);
    assert!(largest <= 8, "the border jumps {largest} px: {steps:?}");
    let at_edges: Vec<&(usize, usize, usize)> = steps
        .iter()
        .filter(|s| s.0.abs_diff(127) <= 2 || s.1.abs_diff(128) <= 3)
        .collect();
    assert!(
        at_edges.len() >= 3,
        "the border crosses the node edges: {steps:?}"
    );
    let at_edge = at_edges.iter().map(|s| s.2).max().unwrap_or(0);
    eprintln!(
        "border steps: {at_edge} px at the node and tile edges, {largest} px at most anywhere"
    );
    assert!(
        at_edge <= 4,
        "a step of {at_edge} px where the border crosses a node or tile edge: {at_edges:?}"
    );
}

#[test]
fn a_lightning_flash_brightens_the_adapted_frame_and_the_eye_keeps_its_state() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let v = view(hills_eye(), (40.0, -4.0, 0.0), 60.0, (96, 64));
    // A moonless night, then a strike 20,000 lux bright.
    let night = FrameSnapshot::new(unix(2024, 7, 6, 8.0), vec![v]);
    let mut flash = night.clone();
    flash.flash_lux = 20_000.0;
    let brightness = |image: &Image| mean_brightness(image);
    for adaptation in [Adaptation::Settled, Adaptation::Step(1.0 / 60.0)] {
        let (dark, before) = frame(&mut renderer, &cache, &night, adaptation);
        let (lit, during) = frame(&mut renderer, &cache, &flash, adaptation);
        let (_, after) = frame(&mut renderer, &cache, &night, adaptation);
        assert!(
            brightness(&lit) > 3.0 * brightness(&dark).max(1.0),
            "{adaptation:?}: the flash brightens the frame ({:.1} against {:.1})",
            brightness(&lit),
            brightness(&dark)
        );
        // The eye held its night state through the flash.
        assert!(
            (during.view_adaptation_ev - before.view_adaptation_ev).abs() < 1e-4
                && (after.view_adaptation_ev - before.view_adaptation_ev).abs() < 0.05,
            "{adaptation:?}: {before:?} / {during:?} / {after:?}"
        );
    }
}

#[test]
fn a_keyed_frame_is_not_adapted() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (snapshot, _) = dusk_toward_the_sun();
    let (_, stats) = render_adapted(&mut renderer, &cache, &snapshot, true, Adaptation::Settled);
    assert_eq!(stats.view_adaptation_ev, 0.0);
}

#[test]
fn each_view_of_a_snapshot_adapts_on_its_own() {
    let db = hills();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (dusk, azimuth) = dusk_toward_the_sun();
    let eye = dusk.views[0].eye;
    // View 0 into the low sun, view 1 down at the ground on the other side.
    let mut snapshot = dusk.clone();
    snapshot.views = vec![
        view(eye, (azimuth, -2.0, 0.0), 60.0, (64, 48)),
        view(eye, (azimuth + 180.0, -60.0, 0.0), 60.0, (64, 48)),
    ];
    cache.update(&[eye]);
    cache.wait_idle();
    let mut draw = |index: usize, adaptation: Adaptation| {
        cig_render::load_for_view(&mut renderer, &cache, &snapshot, index, 64).expect("load");
        cig_render::render_image_with(
            &mut renderer,
            &cache,
            &snapshot,
            index,
            cig_render::FrameOptions {
                mesh_budget: usize::MAX,
                key_background: false,
                fade_in_s: 0.0,
                adaptation,
            },
        )
        .expect("render")
        .1
        .view_adaptation_ev
    };
    let sun = draw(0, Adaptation::Settled);
    let ground = draw(1, Adaptation::Settled);
    assert!(
        sun < ground - 1.0,
        "into the sun {sun:.2} EV, the ground {ground:.2} EV"
    );
    // Drawn in turn, frame after frame, neither pulls the other's state.
    for _ in 0..5 {
        let (a, b) = (
            draw(0, Adaptation::Step(0.5)),
            draw(1, Adaptation::Step(0.5)),
        );
        assert!(
            (a - sun).abs() < 0.05 && (b - ground).abs() < 0.05,
            "{a:.2} and {b:.2} against {sun:.2} and {ground:.2}"
        );
    }
}
