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
    let (m_lat, _) = cig_geo::metres_per_degree(WOOD.0);
    let (lat, lon) = (WOOD.0 - 600.0 / m_lat, WOOD.1);
    let eye = Geodetic::new(lat, lon, ground_m(&raster, lat, lon) + 12.0);
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
    let (m_lat, _) = cig_geo::metres_per_degree(WOOD.0);
    let (lat, lon) = (WOOD.0 - 380.0 / m_lat, WOOD.1);
    let eye = Geodetic::new(lat, lon, ground_m(&raster, lat, lon) + 150.0);
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
