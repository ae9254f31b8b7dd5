//! Draped imagery: georeferencing at nadir, level fallback and blending, tile and level seams.
//!
//! The databases here carry imagery tiles made in the test from a colour function of latitude
//! and longitude, so the renderer's clipmap is tested apart from the importer (whose own tests,
//! and the end-to-end test of `cig db import --imagery`, cover reading GeoTIFFs).

mod common;

use cig_geo::Geodetic;
use cig_render::{Adaptation, Image};
use cig_scene::FrameSnapshot;
use cig_terrain::database::TerrainDatabase;
use cig_terrain::imagery::ImageryKey;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::Material;
use common::*;
use std::sync::Arc;

const CENTRE: (f64, f64) = (36.0, -121.0);

/// A flat database of 257 x 257 posts 30 m apart at 100 m around [`CENTRE`], of one
/// material, with imagery of level-0 texels `30 / 2^fine_shift` m whose colour at a texel
/// centre is `colour(lat, lon)`; `skip(key)` leaves tiles out.
fn imagery_database(
    material: Material,
    fine_shift: u8,
    colour: impl Fn(f64, f64) -> [u8; 4] + Sync,
    skip: impl Fn(ImageryKey) -> bool,
) -> Arc<TerrainDatabase> {
    let (n, e) = cig_geo::metres_per_degree(CENTRE.0);
    let posts = 257;
    let grid = GeoGrid {
        south_lat_deg: CENTRE.0 - 128.0 * 30.0 / n,
        west_lon_deg: CENTRE.1 - 128.0 * 30.0 / e,
        dlat_deg: 30.0 / n,
        dlon_deg: 30.0 / e,
        rows: posts,
        cols: posts,
    };
    let raster = Raster {
        grid,
        elevation_m: vec![100.0; posts * posts],
        material: Some(vec![material; posts * posts]),
    };
    database_with_imagery(&raster, fine_shift, colour, skip)
}

/// The marks: (north, east) metres from the centre.
const MARKS_M: [(f64, f64); 5] = [
    (0.0, 0.0),
    (61.3, -47.9),
    (-83.2, 22.6),
    (38.7, 91.1),
    (-55.5, -101.4),
];

/// Grey ground with a white disc 3 m across at each mark.
fn marks(lat: f64, lon: f64) -> [u8; 4] {
    let (n, e) = cig_geo::metres_per_degree(CENTRE.0);
    let north = (lat - CENTRE.0) * n;
    let east = (lon - CENTRE.1) * e;
    let on_mark = MARKS_M
        .iter()
        .any(|&(mn, me)| (north - mn).hypot(east - me) < 1.6);
    if on_mark {
        [255, 255, 255, 255]
    } else {
        [60, 60, 60, 255]
    }
}

fn brightness(px: &[u8]) -> f64 {
    f64::from(px[0]) + f64::from(px[1]) + f64::from(px[2])
}

/// The brightness-weighted centroid of the pixels brighter than halfway between the
/// background and the brightest, within `radius` pixels of `(x, y)`.
fn centroid_near(image: &Image, x: f64, y: f64, radius: i64) -> Option<(f64, f64)> {
    let (w, h) = (image.width as i64, image.height as i64);
    let at = |px: i64, py: i64| brightness(&image.rgba[((py * w + px) * 4) as usize..]);
    let mut pixels = Vec::new();
    for py in (y as i64 - radius).max(0)..(y as i64 + radius + 1).min(h) {
        for px in (x as i64 - radius).max(0)..(x as i64 + radius + 1).min(w) {
            pixels.push((px, py, at(px, py)));
        }
    }
    let lo = pixels.iter().map(|p| p.2).fold(f64::MAX, f64::min);
    let hi = pixels.iter().map(|p| p.2).fold(0.0, f64::max);
    if hi - lo < 60.0 {
        return None;
    }
    let cut = 0.5 * (lo + hi);
    let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
    for (px, py, b) in pixels {
        if b > cut {
            let weight = b - cut;
            sx += (px as f64 + 0.5) * weight;
            sy += (py as f64 + 0.5) * weight;
            sw += weight;
        }
    }
    Some((sx / sw, sy / sw))
}

fn nadir(alt_m: f64, size: u32) -> FrameSnapshot {
    let eye = Geodetic::new(CENTRE.0, CENTRE.1, 100.0 + alt_m);
    FrameSnapshot::new(
        unix(2024, 6, 21, 20.0),
        vec![view(eye, (0.0, -90.0, 0.0), 60.0, (size, size))],
    )
}

fn frame(db: &Arc<TerrainDatabase>, snapshot: &FrameSnapshot) -> Image {
    let cache = cache(db);
    let mut renderer = renderer(&cache);
    render_adapted(&mut renderer, &cache, snapshot, false, Adaptation::Off).0
}

/// Where a point `north_m, east_m` from the centre appears in a nadir, north-up view from
/// `alt_m` above flat ground with a 60 degree field of view `size` pixels square.
fn predicted_px(north_m: f64, east_m: f64, alt_m: f64, size: u32) -> (f64, f64) {
    let half = f64::from(size) * 0.5;
    let px_per_m = half / (alt_m * 30f64.to_radians().tan());
    (half + east_m * px_per_m, half - north_m * px_per_m)
}

#[test]
fn imagery_marks_appear_at_their_coordinates_within_a_pixel_at_nadir() {
    // 30 m posts over 16: 1.9 m texels, so a 3 m mark spans a few texels and pixels.
    let db = imagery_database(Material::Grass, 4, marks, |_| false);
    let (alt_m, size) = (250.0, 320);
    let image = frame(&db, &nadir(alt_m, size));
    write_png(&image, &out_dir().join("imagery_marks.png"));
    for (north, east) in MARKS_M {
        let (px, py) = predicted_px(north, east, alt_m, size);
        let (cx, cy) = centroid_near(&image, px, py, 8)
            .unwrap_or_else(|| panic!("no mark near pixel ({px:.1}, {py:.1})"));
        let miss = (cx - px).hypot(cy - py);
        eprintln!("mark ({north}, {east}) m: predicted ({px:.2}, {py:.2}), drawn ({cx:.2}, {cy:.2}), {miss:.2} px");
        assert!(
            miss < 1.0,
            "the mark {north} m north, {east} m east is drawn {miss:.2} px from where it lies"
        );
    }
}

/// A smooth colour ramp: red grows eastward, green northward (within 640 m and 1280 m of the
/// centre).
fn ramp(lat: f64, lon: f64) -> [u8; 4] {
    let (n, e) = cig_geo::metres_per_degree(CENTRE.0);
    let north = (lat - CENTRE.0) * n;
    let east = (lon - CENTRE.1) * e;
    let r = (128.0 + east * 0.2).clamp(0.0, 255.0) as u8;
    let g = (128.0 + north * 0.1).clamp(0.0, 255.0) as u8;
    [r, g, 90, 255]
}

/// The largest step between a pixel and the mean of its four neighbours over the image's
/// lower two thirds (the ground), per channel.
fn largest_laplacian(image: &Image) -> f64 {
    let (w, h) = (image.width as usize, image.height as usize);
    let at = |x: usize, y: usize, c: usize| f64::from(image.rgba[(y * w + x) * 4 + c]);
    let mut largest: f64 = 0.0;
    for y in h / 3..h - 1 {
        for x in 1..w - 1 {
            for c in 0..3 {
                let mean =
                    0.25 * (at(x - 1, y, c) + at(x + 1, y, c) + at(x, y - 1, c) + at(x, y + 1, c));
                largest = largest.max((at(x, y, c) - mean).abs());
            }
        }
    }
    largest
}

#[test]
fn tiles_and_levels_join_without_seams_and_a_missing_tile_falls_back_to_a_coarser_level() {
    // Water: the detail drawn under imagery is nearly flat there, so steps are the imagery's.
    let with_all = imagery_database(Material::Water, 3, ramp, |_| false);
    // The finest tiles around the centre left out: they are drawn from level 1.
    let with_holes = imagery_database(Material::Water, 3, ramp, |k| {
        k.level == 0 && (3..=4).contains(&k.row) && (3..=4).contains(&k.col)
    });
    let eye = Geodetic::new(CENTRE.0 - 0.0012, CENTRE.1, 160.0);
    let snapshot = FrameSnapshot::new(
        unix(2024, 6, 21, 20.0),
        vec![view(eye, (20.0, -25.0, 0.0), 70.0, (320, 240))],
    );
    let whole = frame(&with_all, &snapshot);
    let holes = frame(&with_holes, &snapshot);
    write_png(&whole, &out_dir().join("imagery_ramp.png"));
    write_png(&holes, &out_dir().join("imagery_ramp_holes.png"));
    for (name, image) in [("whole", &whole), ("holes", &holes)] {
        let step = largest_laplacian(image);
        eprintln!("{name}: largest step {step:.1}");
        assert!(
            step < 14.0,
            "{name}: a step of {step:.1} in a smooth ramp (a seam)"
        );
    }
    // The ramp shows (red grows to the east): imagery, not the material's colour.
    let px = |image: &Image, x: usize, y: usize, c: usize| {
        f64::from(image.rgba[(y * image.width as usize + x) * 4 + c])
    };
    assert!(px(&whole, 300, 200, 0) > px(&whole, 20, 200, 0) + 10.0);
    let differ = mean_abs_diff(&whole, &holes);
    eprintln!("mean difference with the finest centre tiles missing: {differ:.2}");
    assert!(
        differ < 2.0,
        "the coarser level differs by {differ:.2} on average"
    );
}

#[test]
fn transparent_imagery_shows_the_material_colour_beneath() {
    // Magenta imagery over the east half only (alpha 0 to the west).
    let half = |_lat: f64, lon: f64| {
        if lon > CENTRE.1 {
            [230, 20, 230, 255]
        } else {
            [0, 0, 0, 0]
        }
    };
    let db = imagery_database(Material::Grass, 2, half, |_| false);
    let image = frame(&db, &nadir(400.0, 128));
    write_png(&image, &out_dir().join("imagery_half.png"));
    let px = |x: usize, y: usize| {
        let i = (y * image.width as usize + x) * 4;
        [image.rgba[i], image.rgba[i + 1], image.rgba[i + 2]]
    };
    let (west, east) = (px(20, 64), px(108, 64));
    eprintln!("west {west:?}, east {east:?}");
    assert!(
        east[0] > east[1] + 40 && east[2] > east[1] + 40,
        "east is the imagery's magenta"
    );
    assert!(
        west[1] >= west[0] && west[1] >= west[2],
        "west is the grass beneath"
    );
}
