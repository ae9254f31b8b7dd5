//! Shared helpers of the renderer tests: in-memory databases, one GPU, images.
#![allow(dead_code, reason = "each test file uses a different subset")]

use cig_geo::Geodetic;
use cig_render::{Gpu, Image, Renderer};
use cig_scene::{FovDeg, FrameSnapshot, Hpr, View};
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{Material, PagingConfig, TileCache};
use std::sync::{Arc, OnceLock};

/// The one GPU device of the test process (lavapipe when there is no GPU). A machine with no
/// adapter at all fails here, loudly: scripts/setup.sh installs Mesa's lavapipe.
pub fn gpu() -> Arc<Gpu> {
    static GPU: OnceLock<Arc<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| Gpu::headless().expect("a GPU adapter (install mesa-vulkan-drivers)"))
        .clone()
}

pub fn database_from(raster: &Raster, geoid_m: f32) -> Arc<TerrainDatabase> {
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(raster, 128, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = geoid_m);
    let manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    Arc::new(TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db"))
}

/// A database of `raster` (no geoid) with imagery of level-0 texels the post spacing over
/// `2^fine_shift`, whose colour at a texel centre is `colour(lat, lon)` (straight alpha);
/// `skip(key)` leaves tiles out.
pub fn database_with_imagery(
    raster: &Raster,
    fine_shift: u8,
    colour: impl Fn(f64, f64) -> [u8; 4] + Sync,
    skip: impl Fn(cig_terrain::ImageryKey) -> bool,
) -> Arc<TerrainDatabase> {
    use cig_terrain::imagery::{ImageryKey, ImageryLayout, ImageryManifest, ImageryTile};
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(raster, 128, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let layout = ImageryLayout::new(&raster.grid, fine_shift);
    let mut tiles = 0;
    for level in 0..layout.levels {
        let (rows, cols) = layout.tiles_at(level);
        for row in 0..rows {
            for col in 0..cols {
                let key = ImageryKey { level, row, col };
                if skip(key) {
                    continue;
                }
                let t = u64::from(layout.tile_texels);
                let mut rgba = Vec::with_capacity((t * t * 4) as usize);
                for r in 0..t {
                    for c in 0..t {
                        let (lat, lon) = layout.texel_centre_deg(
                            level,
                            u64::from(row) * t + r,
                            u64::from(col) * t + c,
                        );
                        rgba.extend_from_slice(&colour(lat, lon));
                    }
                }
                let tile = ImageryTile::from_rgba(key, layout.tile_texels, &rgba);
                store.insert_imagery(key, tile.encode());
                tiles += 1;
            }
        }
    }
    let mut manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec!["test".into()]);
    manifest.imagery = Some(ImageryManifest {
        layout,
        tile_count: tiles,
        sources: vec!["test pattern".into()],
    });
    Arc::new(TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db"))
}

/// A synthetic 8 km hilly database at 30 m posts, south-west corner 35.98 N 121.23 W.
pub fn hills() -> Arc<TerrainDatabase> {
    static DB: OnceLock<Arc<TerrainDatabase>> = OnceLock::new();
    DB.get_or_init(|| database_from(&hills_raster(), -33.0))
        .clone()
}

/// The raster of [`hills`], voids filled and materials set.
pub fn hills_raster() -> Raster {
    let params = cig_synth::SynthParams {
        origin_lat_deg: 35.98,
        origin_lon_deg: -121.23,
        size_km: 8.0,
        spacing_m: 30.0,
        seed: 7,
    };
    let mut raster = cig_synth::synthesize(&params, &mut |_, _| {}).expect("synth");
    cig_terrain::build::prepare_raster(&mut raster).expect("prepare");
    raster
}

/// A flat sea at mean sea level, 80 km x 80 km at 500 m posts, centred on 36 N 122 W.
pub fn sea() -> Arc<TerrainDatabase> {
    let (n, e) = cig_geo::metres_per_degree(36.0);
    let posts = 161;
    let grid = GeoGrid {
        south_lat_deg: 36.0 - 40_000.0 / n,
        west_lon_deg: -122.0 - 40_000.0 / e,
        dlat_deg: 500.0 / n,
        dlon_deg: 500.0 / e,
        rows: posts,
        cols: posts,
    };
    let raster = Raster {
        grid,
        elevation_m: vec![0.0; posts * posts],
        material: Some(vec![Material::Water; posts * posts]),
    };
    database_from(&raster, 0.0)
}

/// A point of the test hills `north_m`, `east_m` from their reference, `agl_m` above the
/// ground.
pub fn hills_point(north_m: f64, east_m: f64, agl_m: f64) -> cig_geo::Geodetic {
    let frame = cig_geo::EnuFrame::new(cig_geo::Geodetic::new(36.0159, -121.1854, 0.0));
    let g = frame.enu_to_geodetic(glam::DVec3::new(east_m, north_m, 0.0));
    let mut q = cig_terrain::QuerySession::new(cache(&hills()));
    let ground = q
        .hot(g.lat_deg, g.lon_deg)
        .expect("inside the test database");
    cig_geo::Geodetic::new(g.lat_deg, g.lon_deg, ground.height_ellipsoid_m() + agl_m)
}

pub fn cache(db: &Arc<TerrainDatabase>) -> Arc<TileCache> {
    Arc::new(TileCache::new(Arc::clone(db), PagingConfig::default()).expect("cache"))
}

pub fn renderer(cache: &TileCache) -> Renderer {
    Renderer::new(gpu(), cache, cig_render::FRAME_FORMAT)
}

pub fn view(eye: Geodetic, hpr: (f64, f64, f64), fov_deg: f64, size: (u32, u32)) -> View {
    View {
        eye,
        orientation: Hpr {
            heading_deg: hpr.0,
            pitch_deg: hpr.1,
            roll_deg: hpr.2,
        },
        fov: FovDeg::from_horizontal(fov_deg, size.0, size.1),
        width_px: size.0,
        height_px: size.1,
    }
}

/// 2026-06-21 19:00 UTC: mid-morning sun over California.
pub const MORNING_UNIX_S: f64 = 1_782_068_400.0;

/// Seconds since 1970 of a UTC date plus `h` hours.
pub fn unix(y: i32, m: u32, d: u32, h: f64) -> f64 {
    cig_environment::UtcTime::from_calendar(y, m, d, 0, 0, 0.0)
        .expect("a date")
        .unix_seconds()
        + h * 3600.0
}

/// The sun's (azimuth, altitude) in degrees at `eye` and `unix_s`.
pub fn sun_at(eye: Geodetic, unix_s: f64) -> (f64, f64) {
    let observer =
        cig_environment::Observer::new(eye.lat_deg, eye.lon_deg, eye.alt_m).expect("observer");
    let time = cig_environment::UtcTime::from_unix_seconds(unix_s).expect("time");
    let e = cig_environment::ephemeris(&observer, time);
    (e.sun.azimuth_deg, e.sun.altitude_deg)
}

/// Renders one complete frame (all tiles it wants loaded first) at the natural illuminance's
/// exposure, not the view's: frames of one test compare with each other and with their goldens
/// (tests/picture.rs tests the adaptation).
pub fn render(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    key_background: bool,
) -> (Image, cig_render::FrameStats) {
    render_adapted(
        renderer,
        cache,
        snapshot,
        key_background,
        cig_render::Adaptation::Off,
    )
}

/// [`render`] with the eye's adaptation as given.
pub fn render_adapted(
    renderer: &mut Renderer,
    cache: &TileCache,
    snapshot: &FrameSnapshot,
    key_background: bool,
    adaptation: cig_render::Adaptation,
) -> (Image, cig_render::FrameStats) {
    cache.update(&[snapshot.views[0].eye]);
    cache.wait_idle();
    cig_render::load_for_view(renderer, cache, snapshot, 0, 64).expect("load");
    cig_render::render_image_with(
        renderer,
        cache,
        snapshot,
        0,
        cig_render::FrameOptions {
            mesh_budget: usize::MAX,
            key_background,
            fade_in_s: 0.0,
            adaptation,
        },
    )
    .expect("render")
}

pub fn is_key(px: &[u8]) -> bool {
    px[0] > 250 && px[1] < 5 && px[2] > 250
}

/// Mean absolute difference of two images, in 0..255 units per channel.
pub fn mean_abs_diff(a: &Image, b: &Image) -> f64 {
    let sum: u64 = a
        .rgba
        .iter()
        .zip(&b.rgba)
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    sum as f64 / a.rgba.len() as f64
}

/// Mean FLIP error (0 identical .. 1) of two images.
pub fn flip_mean(reference: &Image, test: &Image) -> f32 {
    let rgb = |img: &Image| -> Vec<u8> {
        img.rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect()
    };
    let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &rgb(test));
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let pool = nv_flip::FlipPool::from_image(&error);
    pool.mean()
}

pub fn write_png(image: &Image, path: &std::path::Path) {
    let file = std::fs::File::create(path).expect("create png");
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), image.width, image.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .expect("png header")
        .write_image_data(&image.rgba)
        .expect("png data");
}

pub fn read_png(path: &std::path::Path) -> Option<Image> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).ok()?));
    let mut reader = decoder.read_info().ok()?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).ok()?;
    if info.color_type != png::ColorType::Rgba || info.bit_depth != png::BitDepth::Eight {
        return None;
    }
    buf.truncate(info.buffer_size());
    Some(Image {
        width: info.width,
        height: info.height,
        rgba: buf,
    })
}

/// Where tests write the images they made, for a human to look at after a failure.
pub fn out_dir() -> std::path::PathBuf {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render-tests");
    std::fs::create_dir_all(&dir).expect("out dir");
    dir
}

/// Compares an image with its golden (`tests/golden/NAME.png`) by mean FLIP error; with
/// `CIG_UPDATE_GOLDENS` set, writes the golden instead.
pub fn check_golden(name: &str, image: &Image) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{name}.png"));
    write_png(image, &out_dir().join(format!("{name}.png")));
    if std::env::var_os("CIG_UPDATE_GOLDENS").is_some() {
        write_png(image, &path);
        return;
    }
    let golden = read_png(&path).unwrap_or_else(|| panic!("missing golden {}", path.display()));
    assert_eq!((golden.width, golden.height), (image.width, image.height));
    let flip = flip_mean(&golden, image);
    assert!(
        flip < 0.05,
        "{name}: mean FLIP error {flip:.4} against {} (image written to {})",
        path.display(),
        out_dir().display()
    );
}

/// A database of `raster` (no geoid) with `placements` as its culture.
pub fn database_with_culture(
    raster: &Raster,
    placements: &[cig_terrain::CulturePlacement],
) -> Arc<TerrainDatabase> {
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(raster, 128, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec!["test".into()]);
    let (tiles, culture) =
        cig_terrain::culture::bin_placements(&manifest.layout, placements).expect("culture");
    for tile in &tiles {
        store.insert_culture(tile.key, tile.encode());
    }
    manifest.culture = Some(culture);
    Arc::new(TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db"))
}
