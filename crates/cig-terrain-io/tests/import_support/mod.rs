//! Test-side writers for the importer tests: GeoTIFF (through the `tiff` crate's encoder for
//! strips, by hand for tiles), SRTM .hgt, DTED and ESRI ASCII, plus an analytic elevation field.
#![allow(
    dead_code,
    reason = "each test file uses a different subset of these helpers"
)]

use std::io::Cursor;
use std::path::{Path, PathBuf};

use tiff::encoder::colortype::{self, ColorType};
use tiff::encoder::compression::{Compression, CompressionAlgorithm, Deflate, Lzw, Uncompressed};
use tiff::encoder::{TiffEncoder, TiffValue};
use tiff::tags::Tag;

/// Smooth analytic terrain, metres, with negative values (about -500 to 1900 m).
pub fn field_m(lat_deg: f64, lon_deg: f64) -> f64 {
    700.0
        + 1000.0 * (lat_deg * 7.0).sin() * (lon_deg * 5.0).cos()
        + 150.0 * (lat_deg * 31.0 + lon_deg * 17.0).sin()
}

/// Deterministic void pattern (about 4% of posts).
pub fn is_void(row: usize, col: usize) -> bool {
    (row * 7 + col * 3).is_multiple_of(23)
}

/// Asserts two floats agree within `tol` (for grid coordinates).
#[track_caller]
pub fn assert_close(actual: f64, expected: f64, tol: f64, what: &str) {
    assert!(
        (actual - expected).abs() <= tol,
        "{what}: {actual} != {expected} (tolerance {tol})"
    );
}

/// Asserts every post of `raster` equals `expected(row, col)` exactly (south-first rows),
/// `None` meaning a void.
#[track_caller]
pub fn assert_posts(
    raster: &cig_terrain::raster::Raster,
    mut expected: impl FnMut(usize, usize) -> Option<f32>,
) {
    let g = raster.grid;
    assert_eq!(raster.elevation_m.len(), g.rows * g.cols);
    for row in 0..g.rows {
        for col in 0..g.cols {
            let got = raster.elevation_at(row, col);
            match expected(row, col) {
                None => assert!(
                    got.is_nan(),
                    "post ({row}, {col}) should be void, got {got}"
                ),
                Some(want) => assert_eq!(got, want, "post ({row}, {col})"),
            }
        }
    }
}

pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

// ---------------------------------------------------------------------------------------------
// GeoTIFF

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleKind {
    I16,
    U16,
    F32,
    I32,
    F64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Strips { rows_per_strip: u32 },
    Tiles { size: u32 },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Comp {
    None,
    Lzw,
    Deflate,
}

#[derive(Clone, Debug)]
pub struct TiffSpec {
    pub width: u32,
    pub height: u32,
    pub sample: SampleKind,
    pub layout: Layout,
    pub comp: Comp,
    /// Horizontal differencing (TIFF predictor 2); tiles and integer samples only.
    pub predictor: bool,
    pub geokeys: Vec<u16>,
    pub pixel_scale: Option<[f64; 3]>,
    pub tiepoint: Option<[f64; 6]>,
    pub transformation: Option<[f64; 16]>,
    pub nodata: Option<String>,
}

pub const PIXEL_IS_AREA: u16 = 1;
pub const PIXEL_IS_POINT: u16 = 2;

/// GeoKeyDirectory for a geographic CRS.
pub fn geokeys_geographic(epsg: u16, raster_type: u16) -> Vec<u16> {
    vec![
        1,
        1,
        0,
        4, //
        1024,
        0,
        1,
        2, //
        1025,
        0,
        1,
        raster_type, //
        2048,
        0,
        1,
        epsg, //
        2054,
        0,
        1,
        9102,
    ]
}

/// GeoKeyDirectory for a projected CRS.
pub fn geokeys_projected(epsg: u16, raster_type: u16) -> Vec<u16> {
    vec![
        1,
        1,
        0,
        4, //
        1024,
        0,
        1,
        1, //
        1025,
        0,
        1,
        raster_type, //
        3072,
        0,
        1,
        epsg, //
        3076,
        0,
        1,
        9001,
    ]
}

/// One sample type of the test writer.
pub trait Px: Copy + Default {
    const BITS: u16;
    /// TIFF SampleFormat: 1 unsigned, 2 signed, 3 float.
    const FORMAT: u16;
    fn from_f64(v: f64) -> Self;
    fn to_f32(self) -> f32;
    fn push_ne(self, out: &mut Vec<u8>);
    fn diff(self, previous: Self) -> Self;
}

macro_rules! px_int {
    ($t:ty, $bits:expr, $format:expr) => {
        impl Px for $t {
            const BITS: u16 = $bits;
            const FORMAT: u16 = $format;
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            fn to_f32(self) -> f32 {
                self as f32
            }
            fn push_ne(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_ne_bytes());
            }
            fn diff(self, previous: Self) -> Self {
                self.wrapping_sub(previous)
            }
        }
    };
}
macro_rules! px_float {
    ($t:ty, $bits:expr) => {
        impl Px for $t {
            const BITS: u16 = $bits;
            const FORMAT: u16 = 3;
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            fn to_f32(self) -> f32 {
                self as f32
            }
            fn push_ne(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_ne_bytes());
            }
            fn diff(self, _: Self) -> Self {
                panic!("no horizontal predictor for floats")
            }
        }
    };
}
px_int!(i16, 16, 2);
px_int!(u16, 16, 1);
px_int!(i32, 32, 2);
px_float!(f32, 32);
px_float!(f64, 64);

/// Converts north-first heights (`NaN` = void) to samples: voids become the no-data value
/// (or NaN for floats without one).
fn samples<T: Px>(values: &[f64], nodata: Option<f64>) -> Vec<T> {
    values
        .iter()
        .map(|&v| {
            if v.is_nan() {
                T::from_f64(nodata.unwrap_or(f64::NAN))
            } else {
                T::from_f64(v)
            }
        })
        .collect()
}

/// Writes a GeoTIFF of `values` (north row first, `NaN` = void).
pub fn write_geotiff(spec: &TiffSpec, values: &[f64]) -> Vec<u8> {
    assert_eq!(values.len(), (spec.width * spec.height) as usize);
    let nodata = spec
        .nodata
        .as_ref()
        .map(|s| s.parse::<f64>().expect("nodata"));
    match (spec.sample, spec.layout) {
        (SampleKind::I16, Layout::Strips { .. }) => {
            strips::<colortype::GrayI16>(spec, &samples::<i16>(values, nodata))
        }
        (SampleKind::U16, Layout::Strips { .. }) => {
            strips::<colortype::Gray16>(spec, &samples::<u16>(values, nodata))
        }
        (SampleKind::F32, Layout::Strips { .. }) => {
            strips::<colortype::Gray32Float>(spec, &samples::<f32>(values, nodata))
        }
        (SampleKind::I32, Layout::Strips { .. }) => {
            strips::<colortype::GrayI32>(spec, &samples::<i32>(values, nodata))
        }
        (SampleKind::F64, Layout::Strips { .. }) => {
            strips::<colortype::Gray64Float>(spec, &samples::<f64>(values, nodata))
        }
        (SampleKind::I16, Layout::Tiles { .. }) => tiles(spec, &samples::<i16>(values, nodata)),
        (SampleKind::U16, Layout::Tiles { .. }) => tiles(spec, &samples::<u16>(values, nodata)),
        (SampleKind::F32, Layout::Tiles { .. }) => tiles(spec, &samples::<f32>(values, nodata)),
        (SampleKind::I32, Layout::Tiles { .. }) => tiles(spec, &samples::<i32>(values, nodata)),
        (SampleKind::F64, Layout::Tiles { .. }) => tiles(spec, &samples::<f64>(values, nodata)),
    }
}

fn geo_tags<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    dir: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    spec: &TiffSpec,
) {
    dir.write_tag(Tag::GeoKeyDirectoryTag, &spec.geokeys[..])
        .expect("geokeys");
    if let Some(scale) = spec.pixel_scale {
        dir.write_tag(Tag::ModelPixelScaleTag, &scale[..])
            .expect("scale");
    }
    if let Some(tie) = spec.tiepoint {
        dir.write_tag(Tag::ModelTiepointTag, &tie[..])
            .expect("tiepoint");
    }
    if let Some(m) = spec.transformation {
        dir.write_tag(Tag::ModelTransformationTag, &m[..])
            .expect("transformation");
    }
    if let Some(nodata) = &spec.nodata {
        dir.write_tag(Tag::GdalNodata, nodata.as_str())
            .expect("nodata");
    }
}

fn strips<C: ColorType>(spec: &TiffSpec, data: &[C::Inner]) -> Vec<u8>
where
    [C::Inner]: TiffValue,
{
    assert!(!spec.predictor, "the tiff encoder writes no predictor");
    let mut cursor = Cursor::new(Vec::new());
    {
        let mut encoder = TiffEncoder::new(&mut cursor).expect("encoder");
        match spec.comp {
            Comp::None => strips_with::<C, _, _>(&mut encoder, spec, data, Uncompressed),
            Comp::Lzw => strips_with::<C, _, _>(&mut encoder, spec, data, Lzw),
            Comp::Deflate => strips_with::<C, _, _>(&mut encoder, spec, data, Deflate::default()),
        }
    }
    cursor.into_inner()
}

fn strips_with<C: ColorType, W: std::io::Write + std::io::Seek, D: Compression>(
    encoder: &mut TiffEncoder<W>,
    spec: &TiffSpec,
    data: &[C::Inner],
    compression: D,
) where
    [C::Inner]: TiffValue,
{
    let mut image = encoder
        .new_image_with_compression::<C, D>(spec.width, spec.height, compression)
        .expect("image");
    if let Layout::Strips { rows_per_strip } = spec.layout {
        image
            .rows_per_strip(rows_per_strip)
            .expect("rows per strip");
    }
    geo_tags(image.encoder(), spec);
    image.write_data(data).expect("write strips");
}

/// A tiled TIFF written tag by tag (the `tiff` encoder writes strips only).
fn tiles<T: Px>(spec: &TiffSpec, data: &[T]) -> Vec<u8> {
    let Layout::Tiles { size } = spec.layout else {
        unreachable!()
    };
    let (w, h, size_us) = (spec.width as usize, spec.height as usize, size as usize);
    let across = w.div_ceil(size_us);
    let down = h.div_ceil(size_us);
    let mut cursor = Cursor::new(Vec::new());
    {
        let mut encoder = TiffEncoder::new(&mut cursor).expect("encoder");
        let mut dir = encoder.new_directory().expect("directory");
        let mut offsets = Vec::new();
        let mut counts = Vec::new();
        for ty in 0..down {
            for tx in 0..across {
                let mut raw = Vec::new();
                for r in 0..size_us {
                    let mut previous = T::default();
                    for c in 0..size_us {
                        let (row, col) = (ty * size_us + r, tx * size_us + c);
                        let v = if row < h && col < w {
                            data[row * w + col]
                        } else {
                            T::default()
                        };
                        let stored = if spec.predictor { v.diff(previous) } else { v };
                        previous = v;
                        stored.push_ne(&mut raw);
                    }
                }
                let mut packed = Vec::new();
                match spec.comp {
                    Comp::None => Uncompressed.write_to(&mut packed, &raw),
                    Comp::Lzw => Lzw.write_to(&mut packed, &raw),
                    Comp::Deflate => Deflate::default().write_to(&mut packed, &raw),
                }
                .expect("compress tile");
                let offset = dir.write_data(&packed[..]).expect("tile data");
                offsets.push(u32::try_from(offset).expect("small file"));
                counts.push(packed.len() as u32);
            }
        }
        let compression: u16 = match spec.comp {
            Comp::None => 1,
            Comp::Lzw => 5,
            Comp::Deflate => 8,
        };
        dir.write_tag(Tag::ImageWidth, spec.width).expect("tag");
        dir.write_tag(Tag::ImageLength, spec.height).expect("tag");
        dir.write_tag(Tag::BitsPerSample, T::BITS).expect("tag");
        dir.write_tag(Tag::Compression, compression).expect("tag");
        dir.write_tag(Tag::PhotometricInterpretation, 1u16)
            .expect("tag");
        dir.write_tag(Tag::SamplesPerPixel, 1u16).expect("tag");
        dir.write_tag(Tag::SampleFormat, T::FORMAT).expect("tag");
        dir.write_tag(Tag::TileWidth, size).expect("tag");
        dir.write_tag(Tag::TileLength, size).expect("tag");
        dir.write_tag(Tag::TileOffsets, &offsets[..]).expect("tag");
        dir.write_tag(Tag::TileByteCounts, &counts[..])
            .expect("tag");
        dir.write_tag(Tag::Predictor, if spec.predictor { 2u16 } else { 1u16 })
            .expect("tag");
        geo_tags(&mut dir, spec);
        dir.finish().expect("finish directory");
    }
    cursor.into_inner()
}

// ---------------------------------------------------------------------------------------------
// SRTM .hgt

/// An SRTM tile of `n x n` posts; `value(row_from_north, col)` (`None` = void).
pub fn write_hgt(n: usize, value: impl Fn(usize, usize) -> Option<i16>) -> Vec<u8> {
    let mut out = Vec::with_capacity(2 * n * n);
    for row in 0..n {
        for col in 0..n {
            out.extend_from_slice(&value(row, col).unwrap_or(-32768).to_be_bytes());
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// DTED

#[derive(Clone, Copy, Debug)]
pub struct DtedSpec {
    /// South-west post, whole arc-seconds.
    pub origin_lat_arcsec: i64,
    pub origin_lon_arcsec: i64,
    /// Intervals, tenths of arc-seconds.
    pub lat_interval: u32,
    pub lon_interval: u32,
    /// Points per longitude line (rows) and number of lines (columns).
    pub lat_points: usize,
    pub lon_lines: usize,
    /// DTED level written in the DSI (0, 1 or 2).
    pub level: u8,
}

impl DtedSpec {
    pub fn south_lat_deg(&self) -> f64 {
        self.origin_lat_arcsec as f64 / 3600.0
    }
    pub fn west_lon_deg(&self) -> f64 {
        self.origin_lon_arcsec as f64 / 3600.0
    }
    pub fn dlat_deg(&self) -> f64 {
        f64::from(self.lat_interval) / 36000.0
    }
    pub fn dlon_deg(&self) -> f64 {
        f64::from(self.lon_interval) / 36000.0
    }
    /// Latitude and longitude of post (row from south, col from west).
    pub fn post(&self, row: usize, col: usize) -> (f64, f64) {
        (
            self.south_lat_deg() + row as f64 * self.dlat_deg(),
            self.west_lon_deg() + col as f64 * self.dlon_deg(),
        )
    }
}

fn dms(arcsec: i64, positive: char, negative: char) -> String {
    let h = if arcsec < 0 { negative } else { positive };
    let a = arcsec.unsigned_abs();
    format!("{:03}{:02}{:02}{h}", a / 3600, (a / 60) % 60, a % 60)
}

pub fn signed_magnitude(v: i16) -> [u8; 2] {
    let m = v.unsigned_abs() & 0x7fff;
    (if v < 0 { m | 0x8000 } else { m }).to_be_bytes()
}

/// A DTED file; `value(row_from_south, col)` (`None` = void, written as 0xFFFF).
pub fn write_dted(spec: &DtedSpec, value: impl Fn(usize, usize) -> Option<i16>) -> Vec<u8> {
    let mut out = Vec::new();
    let mut uhl = format!(
        "UHL1{}{}{:04}{:04}{:>4}{:<3}{:<12}{:04}{:04}{}",
        dms(spec.origin_lon_arcsec, 'E', 'W'),
        dms(spec.origin_lat_arcsec, 'N', 'S'),
        spec.lon_interval,
        spec.lat_interval,
        "NA",
        "U",
        "",
        spec.lon_lines,
        spec.lat_points,
        "0"
    );
    while uhl.len() < 80 {
        uhl.push(' ');
    }
    assert_eq!(uhl.len(), 80, "{uhl}");
    out.extend_from_slice(uhl.as_bytes());
    let mut dsi = format!("DSIU{:<27}DTED{}", "", spec.level).into_bytes();
    dsi.resize(648, b' ');
    out.extend_from_slice(&dsi);
    let mut acc = b"ACC".to_vec();
    acc.resize(2700, b' ');
    out.extend_from_slice(&acc);
    for col in 0..spec.lon_lines {
        let start = out.len();
        out.push(0xAA);
        out.extend_from_slice(&(col as u32).to_be_bytes()[1..]);
        out.extend_from_slice(&(col as u16).to_be_bytes());
        out.extend_from_slice(&0u16.to_be_bytes());
        for row in 0..spec.lat_points {
            let raw = match value(row, col) {
                Some(v) => signed_magnitude(v),
                None => [0xFF, 0xFF],
            };
            out.extend_from_slice(&raw);
        }
        let sum: u32 = out[start..].iter().map(|&b| u32::from(b)).sum();
        out.extend_from_slice(&sum.to_be_bytes());
    }
    out
}

// ---------------------------------------------------------------------------------------------
// ESRI ASCII grid

pub struct AscSpec {
    pub ncols: usize,
    pub nrows: usize,
    pub xll: f64,
    pub yll: f64,
    /// `xllcorner`/`yllcorner` (true) or `xllcenter`/`yllcenter`.
    pub corner: bool,
    pub cellsize: f64,
    pub nodata: f64,
}

/// An ESRI ASCII grid of `values` (north row first, `NaN` = void, written as `nodata`).
pub fn write_asc(spec: &AscSpec, values: &[f64]) -> String {
    let reg = if spec.corner { "corner" } else { "center" };
    let mut text = format!(
        "ncols {}\nnrows {}\nxll{reg} {}\nyll{reg} {}\ncellsize {}\nNODATA_value {}\n",
        spec.ncols, spec.nrows, spec.xll, spec.yll, spec.cellsize, spec.nodata
    );
    for row in values.chunks(spec.ncols) {
        let line: Vec<String> = row
            .iter()
            .map(|v| {
                if v.is_nan() {
                    format!("{}", spec.nodata)
                } else {
                    format!("{v}")
                }
            })
            .collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    text
}

/// A DTED level 0 tile of 121 x 121 posts (30" spacing) from N35 W122.
pub fn small_dted_spec() -> DtedSpec {
    DtedSpec {
        origin_lat_arcsec: 35 * 3600,
        origin_lon_arcsec: -122 * 3600,
        lat_interval: 300,
        lon_interval: 300,
        lat_points: 121,
        lon_lines: 121,
        level: 0,
    }
}
