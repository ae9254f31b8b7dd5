//! Culture on the terrain: drawn instanced, standing on the ground, its level of detail managed
//! by the detail control parameter (issue 18).

mod common;

use cig_geo::Geodetic;
use cig_render::Renderer;
use cig_scene::FrameSnapshot;
use cig_terrain::raster::Raster;
use cig_terrain::{CultureKind, CulturePlacement, TerrainDatabase};
use common::*;
use std::sync::{Arc, OnceLock};

/// Centre of the wood and village, 4 km into the hills database.
const WOOD: (f64, f64) = (36.016, -121.186);

/// An eye `south_m` south of the wood's centre, `up_m` above the ground there.
fn south_of_wood(raster: &Raster, south_m: f64, up_m: f64) -> Geodetic {
    let (m_lat, _) = cig_geo::metres_per_degree(WOOD.0);
    let (lat, lon) = (WOOD.0 - south_m / m_lat, WOOD.1);
    Geodetic::new(lat, lon, ground_m(raster, lat, lon) + up_m)
}

fn ground_m(raster: &Raster, lat_deg: f64, lon_deg: f64) -> f64 {
    let g = &raster.grid;
    let i = ((lat_deg - g.south_lat_deg) / g.dlat_deg).round() as usize;
    let j = ((lon_deg - g.west_lon_deg) / g.dlon_deg).round() as usize;
    f64::from(raster.elevation_m[i.min(g.rows - 1) * g.cols + j.min(g.cols - 1)])
}

/// A 700 m square wood of mixed trees on a 9 m jittered grid, and a street of houses south
/// of it.
fn placements() -> Vec<CulturePlacement> {
    let (m_lat, m_lon) = cig_geo::metres_per_degree(WOOD.0);
    let mut out = Vec::new();
    let mut hash = 0x9e37_79b9_u32;
    let mut next = move || {
        hash ^= hash << 13;
        hash ^= hash >> 17;
        hash ^= hash << 5;
        f64::from(hash) / f64::from(u32::MAX)
    };
    for r in 0..78 {
        for c in 0..78 {
            let n = -350.0 + f64::from(r) * 9.0 + 6.0 * next();
            let e = -350.0 + f64::from(c) * 9.0 + 6.0 * next();
            let conifer = next() < 0.6;
            let h = 12.0 + 10.0 * next();
            out.push(CulturePlacement {
                kind: if conifer {
                    CultureKind::ConiferTree
                } else {
                    CultureKind::BroadleafTree
                },
                lat_deg: WOOD.0 + n / m_lat,
                lon_deg: WOOD.1 + e / m_lon,
                height_m: h as f32,
                width_m: (h * if conifer { 0.3 } else { 0.55 }) as f32,
                length_m: 0.0,
                heading_deg: (360.0 * next()) as f32,
                variant: (255.0 * next()) as u8,
            });
        }
    }
    for k in 0..12 {
        let e = -300.0 + f64::from(k) * 50.0;
        out.push(CulturePlacement {
            kind: if k % 3 == 2 {
                CultureKind::Shed
            } else {
                CultureKind::House
            },
            lat_deg: WOOD.0 - 420.0 / m_lat,
            lon_deg: WOOD.1 + e / m_lon,
            height_m: 8.5,
            width_m: 9.0,
            length_m: 12.0,
            heading_deg: 90.0,
            variant: k as u8 * 20,
        });
    }
    out
}

fn wood() -> (Arc<TerrainDatabase>, Raster) {
    static DB: OnceLock<(Arc<TerrainDatabase>, Raster)> = OnceLock::new();
    DB.get_or_init(|| {
        let raster = hills_raster();
        (database_with_culture(&raster, &placements()), raster)
    })
    .clone()
}

fn snapshot(eye: Geodetic, pitch_deg: f64, culture: bool, managed: bool) -> FrameSnapshot {
    let mut s = FrameSnapshot::new(
        MORNING_UNIX_S,
        vec![view(eye, (0.0, pitch_deg, 0.0), 60.0, (320, 240))],
    );
    s.culture = culture;
    s.culture_managed = managed;
    s
}

fn frame(
    renderer: &mut Renderer,
    cache: &cig_terrain::TileCache,
    snapshot: &FrameSnapshot,
) -> (cig_render::Image, cig_render::FrameStats) {
    render(renderer, cache, snapshot, false)
}

#[test]
fn a_wood_and_a_street_are_drawn_on_the_ground() {
    let (db, raster) = wood();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // 600 m south of the wood's centre, 12 m above the street, looking north.
    let eye = south_of_wood(&raster, 600.0, 12.0);
    let (with, stats) = frame(&mut renderer, &cache, &snapshot(eye, -2.0, true, true));
    let (without, bare) = frame(&mut renderer, &cache, &snapshot(eye, -2.0, false, true));
    write_png(&with, &out_dir().join("culture-wood.png"));
    write_png(&without, &out_dir().join("culture-wood-off.png"));
    assert!(stats.culture_drawn > 1000, "{stats:?}");
    assert!(stats.culture_triangles > 0);
    assert_eq!(bare.culture_drawn, 0);
    assert_eq!(
        stats.triangles,
        stats.terrain_triangles + stats.model_triangles + stats.culture_triangles
    );
    // The wood fills much of the middle band of the frame.
    let diff = mean_abs_diff(&with, &without);
    assert!(diff > 2.0, "culture changes the picture by only {diff}");
}

#[test]
fn managed_culture_draws_far_fewer_triangles_than_full_detail() {
    let (db, raster) = wood();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    // Over the wood's south edge at 150 m, looking down across it.
    let eye = south_of_wood(&raster, 380.0, 150.0);
    let (managed_image, managed) = frame(&mut renderer, &cache, &snapshot(eye, -20.0, true, true));
    let (full_image, full) = frame(&mut renderer, &cache, &snapshot(eye, -20.0, true, false));
    write_png(&managed_image, &out_dir().join("culture-managed.png"));
    write_png(&full_image, &out_dir().join("culture-full.png"));
    assert!(full.culture_drawn >= managed.culture_drawn);
    let ratio = full.culture_triangles as f64 / managed.culture_triangles.max(1) as f64;
    assert!(
        ratio > 3.0,
        "full {} vs managed {} triangles",
        full.culture_triangles,
        managed.culture_triangles
    );
    // The managed picture is the same picture: the levels are chosen for the pixels.
    let flip = flip_mean(&full_image, &managed_image);
    assert!(
        flip < 0.12,
        "managed culture looks different from full detail: FLIP {flip}"
    );
}

/// A flat grass plain 6 km square at 30 m posts, 100 m above the sea, south-west corner
/// 36 N 121 W.
fn plain() -> Raster {
    let (n, e) = cig_geo::metres_per_degree(36.0);
    let posts = 201;
    Raster {
        grid: cig_terrain::GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: 30.0 / n,
            dlon_deg: 30.0 / e,
            rows: posts,
            cols: posts,
        },
        elevation_m: vec![100.0; posts * posts],
        material: Some(vec![cig_terrain::Material::Grass; posts * posts]),
    }
}

#[test]
fn a_slowly_approached_tree_never_pops() {
    let raster = plain();
    let g = raster.grid;
    let (tree_lat, tree_lon) = (
        g.south_lat_deg + 150.0 * g.dlat_deg,
        g.west_lon_deg + 100.0 * g.dlon_deg,
    );
    let tree = CulturePlacement {
        kind: CultureKind::BroadleafTree,
        lat_deg: tree_lat,
        lon_deg: tree_lon,
        height_m: 20.0,
        width_m: 12.0,
        length_m: 12.0,
        heading_deg: 0.0,
        variant: 128,
    };
    let db = database_with_culture(&raster, &[tree]);
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let size = (200, 150);
    let (m_lat, _) = cig_geo::metres_per_degree(tree_lat);
    let klod = renderer.detail.klod_for(&view(
        Geodetic::new(0.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
        30.0,
        size,
    ));
    let radius_m = 0.5 * (20.0f64 * 20.0 + 2.0 * 12.0 * 12.0).sqrt();
    // The tree's pixels: where the frame with culture differs from the frame without.
    let coverage = |renderer: &mut Renderer, ne: f64| {
        let distance_m = klod * radius_m / ne;
        let eye = Geodetic::new(tree_lat - distance_m / m_lat, tree_lon, 110.0);
        let on = snapshot_at(eye, size, true);
        let off = snapshot_at(eye, size, false);
        let with = render(renderer, &cache, &on, false).0;
        let without = render(renderer, &cache, &off, false).0;
        with.pixels_differing(&without, 2) as f64
    };
    let mut ne = 0.6;
    let mut previous = coverage(&mut renderer, ne);
    assert_eq!(previous, 0.0, "removed below half the first step");
    let mut largest_step: f64 = 0.0;
    while ne < 40.0 {
        ne *= 1.04;
        let now = coverage(&mut renderer, ne);
        // The projected area grows as N_e squared (1.0816 a frame); 15 % either side of that
        // and 4 px for the pixel grid and the dissolve's dither.
        let expected = previous * 1.0816;
        assert!(
            now <= expected * 1.15 + 4.0 && now >= expected / 1.15 - 4.0,
            "at N_e {ne:.2} the tree's coverage went from {previous} to {now} px in one frame"
        );
        if previous > 20.0 {
            largest_step = largest_step.max(now / previous);
        }
        previous = now;
    }
    eprintln!("largest growth between frames {largest_step:.3}");
    assert!(previous > 300.0, "the tree ends large: {previous} px");
}

fn snapshot_at(eye: Geodetic, size: (u32, u32), culture: bool) -> FrameSnapshot {
    let mut s = FrameSnapshot::new(MORNING_UNIX_S, vec![view(eye, (0.0, 0.0, 0.0), 30.0, size)]);
    s.culture = culture;
    s.fog = cig_scene::Fog::from_visibility(cig_scene::FogMode::Exponential, 200_000.0);
    s
}

#[test]
fn cue_important_culture_keeps_its_detail_under_overload() {
    let (db, raster) = wood();
    let cache = cache(&db);
    // Looking north across the street of houses from 600 m south of the wood, 12 m up.
    let eye = south_of_wood(&raster, 900.0, 12.0);
    let loaded = snapshot(eye, -2.0, true, true);
    // A budget every frame exceeds: K_LOD falls to its floor within a few frames.
    let overload = cig_scene::overload::OverloadSettings {
        triangles: Some(cig_scene::overload::CounterLimits {
            capacity: 1000.0,
            begin_decrement: 900.0,
            begin_increment: 500.0,
        }),
        models: None,
        gpu_ms: None,
        decrement_step: 0.3,
        ..Default::default()
    };
    let drawn_under_load = |cue: Vec<CultureKind>| {
        let mut renderer = renderer(&cache);
        renderer.set_overload(Some(overload)).expect("overload");
        renderer.culture_cue_important = cue;
        let mut last = None;
        for _ in 0..6 {
            last = Some(frame(&mut renderer, &cache, &loaded).1);
        }
        last.expect("frames")
    };
    let plain = drawn_under_load(Vec::new());
    let cued = drawn_under_load(vec![CultureKind::House, CultureKind::Shed]);
    assert!(plain.klod < 0.2 * plain.klod_nominal, "{plain:?}");
    assert!(cued.klod < 0.2 * cued.klod_nominal, "{cued:?}");
    // The street's buildings in view (11 of its 12), 480 m away, keep the nominal K_LOD and
    // stay drawn; without the mark they are removed with the trees' detail.
    assert!(
        cued.culture_drawn >= plain.culture_drawn + 8,
        "cue-important {} against {} objects",
        cued.culture_drawn,
        plain.culture_drawn
    );
}

/// The plain with an east-west ridge 60 m high (a Gaussian of 250 m) 1.5 km north of its south
/// edge, a wood in front of it and a wood behind it.
fn ridge_and_woods() -> (Raster, Vec<CulturePlacement>) {
    let mut raster = plain();
    let g = raster.grid;
    for i in 0..g.rows {
        let north_m = i as f64 * 30.0;
        let h = 100.0 + 60.0 * (-((north_m - 1500.0) / 250.0).powi(2)).exp();
        for j in 0..g.cols {
            raster.elevation_m[i * g.cols + j] = h as f32;
        }
    }
    let (m_lat, m_lon) = cig_geo::metres_per_degree(g.south_lat_deg);
    let mut trees = Vec::new();
    // In front of the ridge (centre 1 km north, 700 m from the eye) and behind it (2.4 km).
    for (centre_n, side_m) in [(1000.0, 200.0), (2400.0, 400.0)] {
        let rows = (side_m / 10.0) as i32;
        for r in 0..rows {
            for c in 0..rows {
                let n = centre_n - side_m / 2.0 + f64::from(r) * 10.0;
                let e = 3000.0 - side_m / 2.0 + f64::from(c) * 10.0;
                trees.push(CulturePlacement {
                    kind: CultureKind::ConiferTree,
                    lat_deg: g.south_lat_deg + n / m_lat,
                    lon_deg: g.west_lon_deg + e / m_lon,
                    height_m: 18.0,
                    width_m: 6.0,
                    length_m: 0.0,
                    heading_deg: 0.0,
                    variant: ((r * 7 + c * 13) % 256) as u8,
                });
            }
        }
    }
    (raster, trees)
}

#[test]
fn culture_behind_a_ridge_is_culled_without_changing_the_picture() {
    let (raster, trees) = ridge_and_woods();
    let g = raster.grid;
    let db = database_with_culture(&raster, &trees);
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let (m_lat, m_lon) = cig_geo::metres_per_degree(g.south_lat_deg);
    let at = |north_m: f64, up_m: f64| {
        let lat = g.south_lat_deg + north_m / m_lat;
        let lon = g.west_lon_deg + 3000.0 / m_lon;
        Geodetic::new(lat, lon, ground_m(&raster, lat, lon) + up_m)
    };
    let shot = |renderer: &mut Renderer, eye: Geodetic, pitch_deg: f64, occlusion: bool| {
        renderer.culture_occlusion = occlusion;
        let mut s = FrameSnapshot::new(
            MORNING_UNIX_S,
            vec![view(eye, (0.0, pitch_deg, 0.0), 40.0, (640, 480))],
        );
        s.culture = true;
        render(renderer, &cache, &s, false)
    };
    // From the foot of the ridge's south side, 2 m up: the far wood is behind the crest.
    let low = at(300.0, 2.0);
    let (culled, culled_stats) = shot(&mut renderer, low, 0.0, true);
    let (all, all_stats) = shot(&mut renderer, low, 0.0, false);
    write_png(&culled, &out_dir().join("culture-ridge-culled.png"));
    write_png(&all, &out_dir().join("culture-ridge-all.png"));
    assert!(
        culled_stats.culture_blocks_occluded >= 4,
        "{culled_stats:?}"
    );
    assert_eq!(all_stats.culture_blocks_occluded, 0);
    // The far wood's trees are not drawn; the near wood's are.
    assert!(
        culled_stats.culture_drawn + 1000 <= all_stats.culture_drawn,
        "{} drawn against {} without occlusion",
        culled_stats.culture_drawn,
        all_stats.culture_drawn
    );
    assert!(culled_stats.culture_drawn >= 300, "{culled_stats:?}");
    eprintln!(
        "occluded {} blocks: {} objects drawn against {}",
        culled_stats.culture_blocks_occluded, culled_stats.culture_drawn, all_stats.culture_drawn
    );
    // Nothing the trainee sees changes.
    let changed = culled.pixels_differing(&all, 2);
    assert!(changed <= 4, "{changed} pixels changed by culling");
    // From 400 m up the far wood shows over the ridge: nothing is culled.
    let high = at(300.0, 400.0);
    let (_, high_stats) = shot(&mut renderer, high, -8.0, true);
    assert_eq!(high_stats.culture_blocks_occluded, 0, "{high_stats:?}");
    assert!(high_stats.culture_drawn >= all_stats.culture_drawn / 2);
}

#[test]
fn real_time_frames_get_their_culture_from_the_selector_thread_soon_after() {
    let (db, raster) = wood();
    let cache = cache(&db);
    let eye = south_of_wood(&raster, 600.0, 12.0);
    let shot = snapshot(eye, -2.0, true, true);
    // A one-off frame makes every tile's culture first.
    let complete = frame(&mut renderer(&cache), &cache, &shot).1;
    assert!(complete.culture_drawn > 1000, "{complete:?}");
    // Real-time frames never wait: the tiles are made on the selector's thread and their
    // culture shows a few frames later, the same objects as the one-off frame's.
    let mut live = renderer(&cache);
    let options = cig_render::FrameOptions {
        fade_in_s: 0.0,
        ..cig_render::FrameOptions::default()
    };
    let first = cig_render::render_image_with(&mut live, &cache, &shot, 0, options)
        .expect("frame")
        .1;
    // The first frame asked for the tiles and did not wait for them.
    assert_eq!(first.culture_drawn, 0, "{first:?}");
    let mut drawn = first.culture_drawn;
    for _ in 0..200 {
        if drawn == complete.culture_drawn {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
        drawn = cig_render::render_image_with(&mut live, &cache, &shot, 0, options)
            .expect("frame")
            .1
            .culture_drawn;
    }
    assert_eq!(drawn, complete.culture_drawn);
}

#[test]
fn street_lights_are_on_at_night_and_off_at_noon() {
    let (db, raster) = wood();
    let cache = cache(&db);
    let mut renderer = renderer(&cache);
    let eye = south_of_wood(&raster, 600.0, 12.0);
    let mut counts = Vec::new();
    // 22:00 and noon in California.
    for unix_s in [
        MORNING_UNIX_S + 13.0 * 3600.0,
        MORNING_UNIX_S + 4.0 * 3600.0,
    ] {
        let mut s = snapshot(eye, -2.0, true, true);
        s.unix_time_s = unix_s;
        let (_, stats) = frame(&mut renderer, &cache, &s);
        counts.push(stats.light_points);
    }
    assert!(counts[0] >= 1, "porch lights at night: {counts:?}");
    assert_eq!(counts[1], 0, "{counts:?}");
}
