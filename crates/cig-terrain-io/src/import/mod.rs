//! DEM importers: reading the user's elevation files into one geographic [`Raster`].
//!
//! Formats (each module's documentation gives the specification and the limits):
//!
//! | format | module | extensions | detected by |
//! | --- | --- | --- | --- |
//! | GeoTIFF (OGC GeoTIFF 1.1 subset) | [`geotiff`] | `.tif`, `.tiff` | `II*\0` / `MM\0*` |
//! | SRTM height file | [`hgt`] | `.hgt` | extension and size only (no magic) |
//! | DTED levels 0-2 (MIL-PRF-89020B) | [`dted`] | `.dt0`, `.dt1`, `.dt2` | `UHL1` |
//! | ESRI ASCII grid | [`asc`] | `.asc` | a leading `ncols`/`nrows` keyword |
//!
//! The extension decides first; a file whose extension is unknown is recognised by its magic
//! bytes. Every reader returns posts on a WGS84 latitude/longitude lattice ([`GeoGrid`]), south
//! row first, heights in metres with `NaN` for voids and no material. UTM GeoTIFFs are resampled
//! once onto a geographic lattice ([`utm`]).
//!
//! [`mosaic`] merges several such rasters into one, [`import_files`] does both for the
//! `cig db import` command.
//!
//! Bad input never panics: a missing, truncated or corrupt file, an impossible header or an
//! unsupported projection is an [`ImportError`] whose one-line message gives the reason first
//! and the path last. Each reader has a byte-level entry point (for the fuzz targets in
//! `fuzz/`): [`read_geotiff_bytes`], [`read_hgt_bytes`], [`read_dted_bytes`], [`read_asc_str`].

use std::fmt;
use std::fs::File;
use std::path::{Path, PathBuf};

use cig_terrain::raster::{GeoGrid, Raster};

pub mod asc;
pub mod dted;
pub mod geotiff;
pub mod hgt;
mod mosaic;
pub mod utm;

pub use asc::read_asc_str;
pub use dted::read_dted_bytes;
pub use geotiff::read_geotiff_bytes;
pub use hgt::read_hgt_bytes;
pub use mosaic::mosaic;

/// Largest raster, in posts, that a reader or [`mosaic`] produces (1.6 GB of `f32`).
pub const MAX_POSTS: u64 = 400_000_000;

/// The file formats [`read_source`] understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum SourceFormat {
    GeoTiff,
    SrtmHgt,
    Dted,
    EsriAscii,
}

impl SourceFormat {
    /// Human-readable name, as used in error messages.
    pub fn name(self) -> &'static str {
        match self {
            SourceFormat::GeoTiff => "GeoTIFF",
            SourceFormat::SrtmHgt => "SRTM .hgt",
            SourceFormat::Dted => "DTED",
            SourceFormat::EsriAscii => "ESRI ASCII grid",
        }
    }
}

impl fmt::Display for SourceFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What was read from one input file.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SourceInfo {
    /// The file (or, for the byte-level readers, the name they were given).
    pub path: PathBuf,
    pub format: SourceFormat,
    /// The geographic grid as imported (after resampling for UTM sources).
    pub grid: GeoGrid,
    /// Number of void (`NaN`) posts in the imported raster.
    pub void_posts: usize,
    /// `Some(326zz/327zz)` when the source was UTM and was resampled onto `grid`.
    pub reprojected_from_epsg: Option<u32>,
}

/// Why an input could not be imported. Messages are one line: the reason first, the path last.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("cannot read file ({source}): {}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "unrecognised DEM format (expected a GeoTIFF .tif/.tiff, SRTM .hgt, DTED .dt0/.dt1/.dt2 \
         or ESRI ASCII .asc file): {}",
        .path.display()
    )]
    UnknownFormat { path: PathBuf },
    #[error("not a {format} file ({reason}): {}", .path.display())]
    BadMagic {
        format: SourceFormat,
        reason: String,
        path: PathBuf,
    },
    #[error("truncated {what} (expected {expected} bytes, found {found}): {}", .path.display())]
    Truncated {
        what: String,
        expected: u64,
        found: u64,
        path: PathBuf,
    },
    #[error(
        "bad DTED checksum in data record {record} (stored {stored:#010x}, computed {computed:#010x}): {}",
        .path.display()
    )]
    Checksum {
        /// Zero-based index of the data record (longitude line).
        record: usize,
        stored: u32,
        computed: u32,
        path: PathBuf,
    },
    #[error("invalid {format} header ({reason}): {}", .path.display())]
    InvalidHeader {
        format: SourceFormat,
        reason: String,
        path: PathBuf,
    },
    #[error("corrupt {format} data ({reason}): {}", .path.display())]
    Corrupt {
        format: SourceFormat,
        reason: String,
        path: PathBuf,
    },
    #[error(
        "SRTM .hgt file size {size} bytes is neither 2884802 (1201 x 1201 posts, 3 arc-second) \
         nor 25934402 (3601 x 3601 posts, 1 arc-second): {}",
        .path.display()
    )]
    HgtSize { size: u64, path: PathBuf },
    #[error(
        "SRTM .hgt file name does not start with the tile's south-west corner such as \
         N35W122: {}",
        .path.display()
    )]
    HgtName { path: PathBuf },
    #[error("ESRI ASCII grid line {line}: {reason}: {}", .path.display())]
    Parse {
        /// One-based line number.
        line: usize,
        reason: String,
        path: PathBuf,
    },
    #[error(
        "unsupported projection {crs} (supported: WGS84 geographic EPSG:4326 and UTM WGS84 \
         EPSG:326zz/327zz): {}",
        .path.display()
    )]
    UnsupportedProjection {
        /// The EPSG code, when the file gave one.
        epsg: Option<u32>,
        /// Description, e.g. `EPSG:3857`.
        crs: String,
        path: PathBuf,
    },
    #[error("unsupported {format} ({reason}): {}", .path.display())]
    Unsupported {
        format: SourceFormat,
        reason: String,
        path: PathBuf,
    },
    #[error("TIFF decoding failed ({reason}): {}", .path.display())]
    Tiff { reason: String, path: PathBuf },
    #[error(
        "raster of {rows} x {cols} posts exceeds the limit of {limit} posts: {}",
        .path.display()
    )]
    RasterTooLarge {
        rows: u64,
        cols: u64,
        limit: u64,
        path: PathBuf,
    },
    #[error(
        "mosaic of {rows} x {cols} posts exceeds the limit of {limit} posts (import fewer, \
         smaller or coarser files)"
    )]
    MosaicTooLarge { rows: u64, cols: u64, limit: u64 },
    #[error("mosaic source {index} is invalid ({reason})")]
    InvalidSource {
        /// Index of the source in the slice given to [`mosaic`].
        index: usize,
        reason: String,
    },
    #[error("no input files to import")]
    NoInput,
}

impl ImportError {
    /// The file the error is about, when there is one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            ImportError::Io { path, .. }
            | ImportError::UnknownFormat { path }
            | ImportError::BadMagic { path, .. }
            | ImportError::Truncated { path, .. }
            | ImportError::Checksum { path, .. }
            | ImportError::InvalidHeader { path, .. }
            | ImportError::Corrupt { path, .. }
            | ImportError::HgtSize { path, .. }
            | ImportError::HgtName { path }
            | ImportError::Parse { path, .. }
            | ImportError::UnsupportedProjection { path, .. }
            | ImportError::Unsupported { path, .. }
            | ImportError::Tiff { path, .. }
            | ImportError::RasterTooLarge { path, .. } => Some(path),
            ImportError::MosaicTooLarge { .. }
            | ImportError::InvalidSource { .. }
            | ImportError::NoInput => None,
        }
    }
}

/// The format a file's extension names, if any (case-insensitive; `N35W122.SRTMGL1.hgt` is HGT).
pub fn format_from_extension(path: &Path) -> Option<SourceFormat> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "tif" | "tiff" => Some(SourceFormat::GeoTiff),
        "hgt" => Some(SourceFormat::SrtmHgt),
        "dt0" | "dt1" | "dt2" => Some(SourceFormat::Dted),
        "asc" => Some(SourceFormat::EsriAscii),
        _ => None,
    }
}

/// The format the first bytes of a file announce, if any. SRTM files have no magic.
pub fn format_from_magic(head: &[u8]) -> Option<SourceFormat> {
    if geotiff::has_tiff_magic(head) {
        return Some(SourceFormat::GeoTiff);
    }
    if head.starts_with(b"UHL1") {
        return Some(SourceFormat::Dted);
    }
    if asc::looks_like_asc(head) {
        return Some(SourceFormat::EsriAscii);
    }
    None
}

fn io_error(path: &Path, source: std::io::Error) -> ImportError {
    ImportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn read_head(path: &Path) -> Result<Vec<u8>, ImportError> {
    use std::io::Read;
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let mut head = Vec::with_capacity(64);
    file.take(64)
        .read_to_end(&mut head)
        .map_err(|e| io_error(path, e))?;
    Ok(head)
}

fn read_all(path: &Path) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|e| io_error(path, e))
}

/// Detects the format from the extension and the file's magic bytes; reads it into a geographic
/// [`Raster`] (`NaN` = void, material `None`).
pub fn read_source(path: &Path) -> Result<(Raster, SourceInfo), ImportError> {
    let format = match format_from_extension(path) {
        Some(format) => format,
        None => format_from_magic(&read_head(path)?).ok_or_else(|| ImportError::UnknownFormat {
            path: path.to_path_buf(),
        })?,
    };
    tracing::debug!(path = %path.display(), %format, "reading DEM source");
    match format {
        SourceFormat::GeoTiff => geotiff::read_geotiff_file(path),
        SourceFormat::SrtmHgt => read_hgt_bytes(&read_all(path)?, path),
        SourceFormat::Dted => read_dted_bytes(&read_all(path)?, path),
        SourceFormat::EsriAscii => {
            let bytes = read_all(path)?;
            read_asc_str(&String::from_utf8_lossy(&bytes), path)
        }
    }
}

/// Several files read and mosaicked into one raster.
#[derive(Clone, Debug)]
pub struct ImportedArea {
    pub raster: Raster,
    /// One entry per input file, in the order given.
    pub sources: Vec<SourceInfo>,
}

/// [`read_source`] on each path (in parallel; the result does not depend on the scheduling)
/// then [`mosaic`]. `progress(done_files, total_files)` is called on the caller's thread after
/// each file is read. When several files fail, the error of the first failing path is returned.
pub fn import_files(
    paths: &[PathBuf],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<ImportedArea, ImportError> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::mpsc;

    if paths.is_empty() {
        return Err(ImportError::NoInput);
    }
    let total = paths.len();
    let workers = std::thread::available_parallelism()
        .map(usize::from)
        .unwrap_or(1)
        .clamp(1, total);
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<Result<(Raster, SourceInfo), ImportError>>> =
        (0..total).map(|_| None).collect();
    std::thread::scope(|scope| {
        let (sender, receiver) = mpsc::channel();
        for _ in 0..workers {
            let sender = sender.clone();
            let next = &next;
            scope.spawn(move || loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                let Some(path) = paths.get(index) else {
                    break;
                };
                if sender.send((index, read_source(path))).is_err() {
                    break;
                }
            });
        }
        drop(sender);
        let mut done = 0;
        for (index, result) in receiver {
            if let Some(slot) = results.get_mut(index) {
                *slot = Some(result);
            }
            done += 1;
            progress(done, total);
        }
    });

    let mut rasters = Vec::with_capacity(total);
    let mut sources = Vec::with_capacity(total);
    for (result, path) in results.into_iter().zip(paths) {
        // A worker that panicked leaves its slot empty: report it as an I/O failure of the file.
        let (raster, info) = result.unwrap_or_else(|| {
            Err(io_error(
                path,
                std::io::Error::other("the reader thread stopped unexpectedly"),
            ))
        })?;
        rasters.push(raster);
        sources.push(info);
    }
    let raster = if rasters.len() == 1 {
        rasters.pop().ok_or(ImportError::NoInput)?
    } else {
        mosaic(&rasters)?
    };
    Ok(ImportedArea { raster, sources })
}

/// Checks a reader's grid: finite, positive spacing, at least one post, on the globe, and no
/// more than [`MAX_POSTS`] posts.
pub(crate) fn check_grid(
    grid: &GeoGrid,
    format: SourceFormat,
    path: &Path,
) -> Result<(), ImportError> {
    let invalid = |reason: String| ImportError::InvalidHeader {
        format,
        reason,
        path: path.to_path_buf(),
    };
    check_post_count(grid.rows as u64, grid.cols as u64, path)?;
    if grid.rows == 0 || grid.cols == 0 {
        return Err(invalid(format!(
            "empty grid of {} x {} posts",
            grid.rows, grid.cols
        )));
    }
    let positive = |d: f64| d.is_finite() && d > 0.0;
    if !positive(grid.dlat_deg) || !positive(grid.dlon_deg) {
        return Err(invalid(format!(
            "post spacing {} x {} degrees is not positive",
            grid.dlat_deg, grid.dlon_deg
        )));
    }
    let (south, north) = (grid.south_lat_deg, grid.north_lat_deg());
    let (west, east) = (grid.west_lon_deg, grid.east_lon_deg());
    let eps = 1e-6;
    if !(south.is_finite() && north.is_finite() && south >= -90.0 - eps && north <= 90.0 + eps) {
        return Err(invalid(format!(
            "latitudes {south} to {north} degrees are not on the globe"
        )));
    }
    if !(west.is_finite() && east.is_finite() && west >= -360.0 - eps && east <= 360.0 + eps) {
        return Err(invalid(format!(
            "longitudes {west} to {east} degrees are not on the globe"
        )));
    }
    Ok(())
}

/// Refuses a raster of more than [`MAX_POSTS`] posts.
pub(crate) fn check_post_count(rows: u64, cols: u64, path: &Path) -> Result<(), ImportError> {
    match rows.checked_mul(cols) {
        Some(posts) if posts <= MAX_POSTS => Ok(()),
        _ => Err(ImportError::RasterTooLarge {
            rows,
            cols,
            limit: MAX_POSTS,
            path: path.to_path_buf(),
        }),
    }
}

/// Builds the raster and its [`SourceInfo`] from a checked grid and south-first heights.
pub(crate) fn finish(
    grid: GeoGrid,
    elevation_m: Vec<f32>,
    format: SourceFormat,
    path: &Path,
    reprojected_from_epsg: Option<u32>,
) -> (Raster, SourceInfo) {
    let raster = Raster {
        grid,
        elevation_m,
        material: None,
    };
    let info = SourceInfo {
        path: path.to_path_buf(),
        format,
        grid,
        void_posts: raster.void_count(),
        reprojected_from_epsg,
    };
    (raster, info)
}

/// Reverses the order of the rows of a row-major array in place (north-first to south-first).
pub(crate) fn flip_rows(values: &mut [f32], cols: usize) {
    if cols == 0 {
        return;
    }
    let rows = values.len() / cols;
    for r in 0..rows / 2 {
        let (top, bottom) = values.split_at_mut((rows - 1 - r) * cols);
        if let (Some(a), Some(b)) = (
            top.get_mut(r * cols..(r + 1) * cols),
            bottom.get_mut(..cols),
        ) {
            a.swap_with_slice(b);
        }
    }
}
