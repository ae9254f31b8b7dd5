//! `cig bench imagery`: importing an orthoimage into a database.
//!
//! Writes a synthetic `size` x `size` RGB 8-bit GeoTIFF (EPSG:4326, uncompressed strips of 16
//! rows, generated strip by strip, never whole in memory) of pixels 1/32 of the posts of a
//! scratch database it covers exactly (1 arc-second posts, so about 0.96 m x 0.79 m pixels at
//! 35 degrees north), then times `add_imagery` over it: seconds, megabytes of decoded image per
//! second, the tiles written and the process's peak resident memory during the import (VmHWM
//! from /proc/self/status, reset before the import where the kernel allows). Targets: 20,000 x
//! 20,000 (1.2 GB of pixels) in at most 120 s and 2 GB.

use crate::database::BuildProgress;
use crate::report::{date_utc, machine, memory_kb};
use crate::{require, BenchError, Step};
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain_io::imagery::add_imagery;
use cig_terrain_io::store::{write_database, BuildInputs};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

/// What `cig bench imagery` measures.
#[derive(Clone, Debug)]
pub struct ImageryOptions {
    /// Pixels along the square image's side.
    pub size: u32,
    /// Where the scratch files go (a temporary directory inside it); default the system's.
    pub scratch: Option<PathBuf>,
    /// Cells along a tile side of the scratch database.
    pub tile_cells: u32,
    /// The commit the report names.
    pub commit: String,
}

/// Level-0 texels (and image pixels) per post spacing.
const PIXELS_PER_POST: u32 = 32;
const SOUTH: f64 = 35.0;
const WEST: f64 = -120.5;
const POST_DEG: f64 = 1.0 / 3600.0;

/// Runs the benchmark; `progress` hears the imagery build's progress.
///
/// # Errors
/// When the size is out of range, or writing or importing fails.
pub fn run(
    options: &ImageryOptions,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<serde_json::Value, BenchError> {
    require((64..=100_000).contains(&options.size), || {
        format!("--size {} must be between 64 and 100000", options.size)
    })?;
    let scratch = match &options.scratch {
        Some(dir) => tempfile::tempdir_in(dir)?,
        None => tempfile::tempdir()?,
    };
    let cells = options.size.div_ceil(PIXELS_PER_POST) as usize;
    let grid = GeoGrid {
        south_lat_deg: SOUTH,
        west_lon_deg: WEST,
        dlat_deg: POST_DEG,
        dlon_deg: POST_DEG,
        rows: cells + 1,
        cols: cells + 1,
    };
    let elevation_m = (0..grid.rows * grid.cols)
        .map(|i| 200.0 + ((i % grid.cols) as f32 * 0.1).sin() * 20.0)
        .collect();
    let mut raster = Raster {
        grid,
        elevation_m,
        material: None,
    };
    cig_terrain::build::prepare_raster(&mut raster).step("cannot prepare the scratch raster")?;
    let db = scratch.path().join("db");
    let inputs = BuildInputs {
        sources: vec!["cig bench imagery".into()],
        void_posts_filled: 0,
        tile_cells: options.tile_cells,
    };
    write_database(&db, &raster, &inputs, false, &mut |_, _| {})?;

    let image = scratch.path().join("ortho.tif");
    let write_started = Instant::now();
    write_image(&image, options.size).step_with(|| format!("cannot write {}", image.display()))?;
    let write_s = write_started.elapsed().as_secs_f64();
    let file_bytes = std::fs::metadata(&image)?.len();

    // Peak memory of the import alone: reset the high-water mark where the kernel allows.
    let hwm_reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    let (_, hwm_before_kb) = memory_kb();
    let started = Instant::now();
    let manifest = add_imagery(&db, &[image], &[], &mut |p| {
        progress(BuildProgress::Imagery(p));
    })?;
    let import_s = started.elapsed().as_secs_f64();
    progress(BuildProgress::End);
    let (rss_kb, hwm_kb) = memory_kb();
    let imagery = manifest
        .imagery
        .ok_or_else(|| BenchError::Scene("the import wrote no imagery section".into()))?;
    let pixels = u64::from(options.size) * u64::from(options.size);
    let decoded_mb = (pixels * 3) as f64 / 1e6;
    let peak_mb = hwm_kb.map(|kb| kb as f64 / 1024.0);
    Ok(serde_json::json!({
        "benchmark": "imagery",
        "machine": machine(),
        "date": date_utc(),
        "commit": options.commit,
        "image": {
            "width_px": options.size,
            "height_px": options.size,
            "layout": "RGB 8-bit, uncompressed strips of 16 rows, EPSG:4326",
            "file_mb": file_bytes as f64 / 1e6,
            "written_s": write_s,
        },
        "database_posts": cells + 1,
        "imagery": {
            "fine_shift": imagery.layout.fine_shift,
            "levels": imagery.layout.levels,
            "tiles": imagery.tile_count,
        },
        "import_s": import_s,
        "import_mb_per_s": decoded_mb / import_s,
        "peak_rss_mb": peak_mb,
        "peak_rss_reset_before_import": hwm_reset,
        "peak_rss_before_import_mb": hwm_before_kb.map(|kb| kb as f64 / 1024.0),
        "rss_after_import_mb": rss_kb.map(|kb| kb as f64 / 1024.0),
        "targets": {
            "import_s_max": 120.0,
            "peak_rss_mb_max": 2048.0,
            "met": import_s <= 120.0 && peak_mb.is_some_and(|mb| mb <= 2048.0),
        },
    }))
}

/// Colour of pixel (col, row from north): smooth bands and a grid, cheap to make.
fn pixel(col: u32, row: u32) -> [u8; 3] {
    let grid = col % 256 < 2 || row % 256 < 2;
    if grid {
        return [250, 250, 250];
    }
    let h = col.wrapping_mul(0x9E37_79B9) ^ row.wrapping_mul(0x85EB_CA6B);
    [
        (60 + (col / 97 % 64) + (h >> 28)) as u8,
        (80 + (row / 89 % 64) + ((h >> 24) & 15)) as u8,
        (40 + ((col + row) / 151 % 48)) as u8,
    ]
}

/// Writes the image strip by strip.
fn write_image(path: &Path, size: u32) -> Result<(), tiff::TiffError> {
    const ROWS_PER_STRIP: u32 = 16;
    let file = std::fs::File::create(path)?;
    let mut encoder = TiffEncoder::new(BufWriter::with_capacity(1 << 20, file))?;
    let mut image = encoder.new_image::<colortype::RGB8>(size, size)?;
    image.rows_per_strip(ROWS_PER_STRIP)?;
    let pixel_deg = POST_DEG / f64::from(PIXELS_PER_POST);
    let north = SOUTH + f64::from(size) * pixel_deg;
    let dir = image.encoder();
    // GeoKeys: geographic, PixelIsArea, EPSG:4326, degrees.
    let keys: [u16; 20] = [
        1, 1, 0, 4, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326, 2054, 0, 1, 9102,
    ];
    dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..])?;
    dir.write_tag(Tag::ModelPixelScaleTag, &[pixel_deg, pixel_deg, 0.0][..])?;
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[0.0, 0.0, 0.0, WEST, north, 0.0][..],
    )?;
    let mut strip = Vec::with_capacity((size * ROWS_PER_STRIP * 3) as usize);
    let mut row = 0;
    while row < size {
        strip.clear();
        for r in row..(row + ROWS_PER_STRIP).min(size) {
            for c in 0..size {
                strip.extend_from_slice(&pixel(c, r));
            }
        }
        image.write_strip(&strip)?;
        row += ROWS_PER_STRIP;
    }
    image.finish()
}
