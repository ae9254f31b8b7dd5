//! Test-side writers for the imagery tests: small databases and GeoTIFF images written by hand
//! through the `tiff` crate's directory encoder (strips or tiles, any sample layout).

#![allow(
    dead_code,
    reason = "each test file uses a different part of the support module"
)]

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{ImageryTile, Manifest};
use cig_terrain_io::store::{imagery_tile_path, open_database, write_database, BuildInputs};
use tiff::encoder::compression::{CompressionAlgorithm, Deflate, Lzw, Uncompressed};
use tiff::encoder::TiffEncoder;
use tiff::tags::Tag;

/// A database of `cells` x `cells` cells at 1 arc-second over a gentle slope.
pub fn small_database(dir: &Path, name: &str, south: f64, west: f64, cells: usize) -> PathBuf {
    let d = 1.0 / 3600.0;
    let grid = GeoGrid {
        south_lat_deg: south,
        west_lon_deg: west,
        dlat_deg: d,
        dlon_deg: d,
        rows: cells + 1,
        cols: cells + 1,
    };
    let elevation_m = (0..grid.rows * grid.cols)
        .map(|i| 100.0 + (i % grid.cols) as f32 * 0.5)
        .collect();
    let mut raster = Raster {
        grid,
        elevation_m,
        material: None,
    };
    cig_terrain::build::prepare_raster(&mut raster).expect("prepare");
    let out = dir.join(name);
    let inputs = BuildInputs {
        sources: vec!["test".into()],
        void_posts_filled: 0,
        tile_cells: 64,
    };
    write_database(&out, &raster, &inputs, false, &mut |_, _| {}).expect("database");
    out
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chunks {
    Strips(u32),
    Tiles(u32),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Comp {
    None,
    Lzw,
    Deflate,
}

/// Samples of an image, north row first, interleaved.
#[derive(Clone, Debug)]
pub enum Samples {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

#[derive(Clone, Debug)]
pub struct ImageSpec {
    pub width: u32,
    pub height: u32,
    pub bands: u16,
    pub photometric: u16,
    pub chunks: Chunks,
    pub comp: Comp,
    pub geokeys: Option<Vec<u16>>,
    pub pixel_scale: [f64; 3],
    pub tiepoint: [f64; 6],
    pub nodata: Option<String>,
    pub extra_samples: Option<u16>,
}

impl ImageSpec {
    /// An RGB image in EPSG:4326, PixelIsArea, corner of pixel (0, 0) at (`north`, `west`).
    pub fn geographic(width: u32, height: u32, north: f64, west: f64, pixel_deg: f64) -> Self {
        ImageSpec {
            width,
            height,
            bands: 3,
            photometric: 2,
            chunks: Chunks::Strips(7),
            comp: Comp::None,
            geokeys: Some(geokeys_geographic(4326, 1)),
            pixel_scale: [pixel_deg, pixel_deg, 0.0],
            tiepoint: [0.0, 0.0, 0.0, west, north, 0.0],
            nodata: None,
            extra_samples: None,
        }
    }
}

pub fn geokeys_geographic(epsg: u16, raster_type: u16) -> Vec<u16> {
    vec![
        1,
        1,
        0,
        4,
        1024,
        0,
        1,
        2,
        1025,
        0,
        1,
        raster_type,
        2048,
        0,
        1,
        epsg,
        2054,
        0,
        1,
        9102,
    ]
}

pub fn geokeys_projected(epsg: u16, raster_type: u16) -> Vec<u16> {
    vec![
        1,
        1,
        0,
        4,
        1024,
        0,
        1,
        1,
        1025,
        0,
        1,
        raster_type,
        3072,
        0,
        1,
        epsg,
        3076,
        0,
        1,
        9001,
    ]
}

fn bytes_of(samples: &Samples, from: usize, to: usize) -> Vec<u8> {
    match samples {
        Samples::U8(v) => v[from..to].to_vec(),
        Samples::U16(v) => v[from..to].iter().flat_map(|s| s.to_le_bytes()).collect(),
        Samples::F32(v) => v[from..to].iter().flat_map(|s| s.to_le_bytes()).collect(),
    }
}

fn compress(comp: Comp, raw: &[u8]) -> Vec<u8> {
    let mut packed = Vec::new();
    match comp {
        Comp::None => Uncompressed.write_to(&mut packed, raw),
        Comp::Lzw => Lzw.write_to(&mut packed, raw),
        Comp::Deflate => Deflate::default().write_to(&mut packed, raw),
    }
    .expect("compress");
    packed
}

/// Writes a little-endian classic TIFF of `samples` as `spec` says.
pub fn write_image(spec: &ImageSpec, samples: &Samples) -> Vec<u8> {
    let (w, h, b) = (
        spec.width as usize,
        spec.height as usize,
        usize::from(spec.bands),
    );
    let (bits, format): (u16, u16) = match samples {
        Samples::U8(_) => (8, 1),
        Samples::U16(_) => (16, 1),
        Samples::F32(_) => (32, 3),
    };
    let mut cursor = Cursor::new(Vec::new());
    {
        let mut encoder = TiffEncoder::new(&mut cursor).expect("encoder");
        let mut dir = encoder.new_directory().expect("directory");
        let mut offsets = Vec::new();
        let mut counts = Vec::new();
        match spec.chunks {
            Chunks::Strips(rows) => {
                let rows = rows as usize;
                for s in 0..h.div_ceil(rows) {
                    let (r0, r1) = (s * rows, ((s + 1) * rows).min(h));
                    let raw = bytes_of(samples, r0 * w * b, r1 * w * b);
                    let packed = compress(spec.comp, &raw);
                    let offset = dir.write_data(&packed[..]).expect("strip");
                    offsets.push(u32::try_from(offset).expect("small"));
                    counts.push(packed.len() as u32);
                }
                dir.write_tag(Tag::RowsPerStrip, rows as u32).expect("tag");
            }
            Chunks::Tiles(size) => {
                let size = size as usize;
                for ty in 0..h.div_ceil(size) {
                    for tx in 0..w.div_ceil(size) {
                        let mut raw = Vec::new();
                        for r in 0..size {
                            for c in 0..size {
                                let (row, col) = (ty * size + r, tx * size + c);
                                if row < h && col < w {
                                    let at = (row * w + col) * b;
                                    raw.extend(bytes_of(samples, at, at + b));
                                } else {
                                    raw.extend(vec![0u8; b * usize::from(bits / 8)]);
                                }
                            }
                        }
                        let packed = compress(spec.comp, &raw);
                        let offset = dir.write_data(&packed[..]).expect("tile");
                        offsets.push(u32::try_from(offset).expect("small"));
                        counts.push(packed.len() as u32);
                    }
                }
                dir.write_tag(Tag::TileWidth, size as u32).expect("tag");
                dir.write_tag(Tag::TileLength, size as u32).expect("tag");
            }
        }
        let compression: u16 = match spec.comp {
            Comp::None => 1,
            Comp::Lzw => 5,
            Comp::Deflate => 8,
        };
        dir.write_tag(Tag::ImageWidth, spec.width).expect("tag");
        dir.write_tag(Tag::ImageLength, spec.height).expect("tag");
        dir.write_tag(Tag::BitsPerSample, &vec![bits; b][..])
            .expect("tag");
        dir.write_tag(Tag::Compression, compression).expect("tag");
        dir.write_tag(Tag::PhotometricInterpretation, spec.photometric)
            .expect("tag");
        dir.write_tag(Tag::SamplesPerPixel, spec.bands)
            .expect("tag");
        dir.write_tag(Tag::SampleFormat, &vec![format; b][..])
            .expect("tag");
        if let Some(extra) = spec.extra_samples {
            dir.write_tag(Tag::ExtraSamples, extra).expect("tag");
        }
        match spec.chunks {
            Chunks::Strips(_) => {
                dir.write_tag(Tag::StripOffsets, &offsets[..]).expect("tag");
                dir.write_tag(Tag::StripByteCounts, &counts[..])
                    .expect("tag");
            }
            Chunks::Tiles(_) => {
                dir.write_tag(Tag::TileOffsets, &offsets[..]).expect("tag");
                dir.write_tag(Tag::TileByteCounts, &counts[..])
                    .expect("tag");
            }
        }
        if let Some(keys) = &spec.geokeys {
            dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
                .expect("tag");
            dir.write_tag(Tag::ModelPixelScaleTag, &spec.pixel_scale[..])
                .expect("tag");
            dir.write_tag(Tag::ModelTiepointTag, &spec.tiepoint[..])
                .expect("tag");
        }
        if let Some(nodata) = &spec.nodata {
            dir.write_tag(Tag::GdalNodata, nodata.as_str())
                .expect("tag");
        }
        dir.finish().expect("finish");
    }
    cursor.into_inner()
}

pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// RGB8 samples of `w` x `h` pixels from `f(col, row_from_north)`.
pub fn rgb8(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Samples {
    let mut v = Vec::with_capacity((w * h * 3) as usize);
    for r in 0..h {
        for c in 0..w {
            v.extend_from_slice(&f(c, r));
        }
    }
    Samples::U8(v)
}

/// Every stored imagery tile, decoded (key checked), by key.
pub fn read_tiles(db: &Path) -> (Manifest, BTreeMap<cig_terrain::ImageryKey, Vec<u8>>) {
    let database = open_database(db).expect("open");
    let manifest = database.manifest().clone();
    let imagery = manifest.imagery.clone().expect("imagery section");
    let mut tiles = BTreeMap::new();
    for level in 0..imagery.layout.levels {
        let (rows, cols) = imagery.layout.tiles_at(level);
        for row in 0..rows {
            for col in 0..cols {
                let key = cig_terrain::ImageryKey { level, row, col };
                if imagery_tile_path(db, key).exists() {
                    let tile = database
                        .load_imagery_tile(key)
                        .expect("load")
                        .expect("present");
                    tiles.insert(key, ImageryTile::to_rgba(&tile));
                }
            }
        }
    }
    assert_eq!(tiles.len() as u64, imagery.tile_count, "tile count");
    (manifest, tiles)
}

/// The texel of level 0 at (row, col) in level-0 texel coordinates, if its tile is stored.
pub fn texel(
    manifest: &Manifest,
    tiles: &BTreeMap<cig_terrain::ImageryKey, Vec<u8>>,
    level: u8,
    row: u64,
    col: u64,
) -> Option<[u8; 4]> {
    let layout = manifest.imagery.as_ref()?.layout;
    let t = u64::from(layout.tile_texels);
    let key = cig_terrain::ImageryKey {
        level,
        row: (row / t) as u32,
        col: (col / t) as u32,
    };
    let tile = tiles.get(&key)?;
    let at = (((row % t) * t + col % t) * 4) as usize;
    Some([tile[at], tile[at + 1], tile[at + 2], tile[at + 3]])
}

/// The colour at a point: the finest stored level's opaque texel there.
pub fn colour_at(
    manifest: &Manifest,
    tiles: &BTreeMap<cig_terrain::ImageryKey, Vec<u8>>,
    lat: f64,
    lon: f64,
) -> Option<[u8; 4]> {
    let layout = manifest.imagery.as_ref()?.layout;
    let (r, c) = layout.texel_coordinates(lat, lon);
    for level in 0..layout.levels {
        let s = f64::from(1u32 << level);
        if let Some(px) = texel(
            manifest,
            tiles,
            level,
            (r / s).floor() as u64,
            (c / s).floor() as u64,
        ) {
            if px[3] >= 128 {
                return Some(px);
            }
        }
    }
    None
}

/// Every file under `dir` with its bytes.
pub fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("read dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.insert(path.clone(), std::fs::read(&path).expect("read"));
            }
        }
    }
    out
}
