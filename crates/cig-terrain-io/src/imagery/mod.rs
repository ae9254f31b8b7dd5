//! Orthoimagery import: GeoTIFF images read as a stream ([`reader`]), built into the database's
//! imagery pyramid ([`pyramid`]; layout and tile format in `cig_terrain::imagery`) and written
//! all-or-nothing.
//!
//! Read: 8- and 16-bit unsigned grey, grey-alpha, RGB and RGBA, strips or tiles, uncompressed,
//! LZW, Deflate or PackBits (what the `tiff` crate decodes), georeferenced in WGS84 geographic
//! (EPSG:4326) or WGS84 UTM (EPSG:326zz/327zz) with the DEM importer's GeoTIFF georeferencing
//! (PixelIsArea and PixelIsPoint honoured). A pixel whose colour bands all equal the GDAL_NODATA
//! value (tag 42113) is transparent, as is alpha 0; a fourth band is alpha unless ExtraSamples
//! says it is unspecified (0), premultiplied alpha (1) is divided out. 16-bit images are scaled
//! linearly so the 99.9th percentile of their colour samples maps to 255 (a histogram pass).
//! Images are read a chunk row (a strip, or a row of tiles) at a time into a small cache, never
//! whole; a chunk row that decodes to more than [`reader::MAX_CHUNK_ROW_BYTES`] is refused.
//!
//! Writing: `cig db import --imagery` builds the pyramid into the database's staging directory
//! ([`write_imagery`] through `store::write_database_with`); [`add_imagery`] adds or replaces
//! the imagery of an existing database in a staging sibling (its tiles hard-linked, or copied)
//! renamed over it only when everything is written, so a failure leaves the database as it was.

use std::path::{Path, PathBuf};

use cig_terrain::{ImageryManifest, Manifest};

use crate::import::ImportError;
use crate::store::{imagery_tile_path, DbError};

pub mod pyramid;
pub mod reader;

pub use pyramid::{build_pyramid, imagery_layout, native_level, OverlayLayer, PyramidSummary};
pub use reader::ImageSource;

/// Why imagery could not be imported. One line: the reason first, the path last.
#[derive(Debug, thiserror::Error)]
pub enum ImageryError {
    #[error("cannot read image ({reason}): {}", .path.display())]
    Io { reason: String, path: PathBuf },
    #[error("not a TIFF image (no \"II*\" or \"MM*\" byte-order mark): {}", .0.display())]
    NotTiff(PathBuf),
    #[error("corrupt or truncated image ({reason}): {}", .path.display())]
    Corrupt { reason: String, path: PathBuf },
    #[error("unsupported image ({reason}): {}", .path.display())]
    Unsupported { reason: String, path: PathBuf },
    #[error("image too large ({reason}): {}", .path.display())]
    TooLarge { reason: String, path: PathBuf },
    #[error("bad image georeference ({reason}): {}", .path.display())]
    Georeference { reason: String, path: PathBuf },
    /// Georeference errors of the shared GeoTIFF reader (no georeference, unsupported CRS…).
    #[error("image georeference: {0}")]
    Import(#[from] ImportError),
    #[error(
        "image does not overlap the database (image {image:?}, database {database:?} degrees \
         south, west, north, east): {}",
        .path.display()
    )]
    NoOverlap {
        image: (f64, f64, f64, f64),
        database: (f64, f64, f64, f64),
        path: PathBuf,
    },
    #[error("no image files or overlays given")]
    NoInput,
    #[error(transparent)]
    Database(#[from] DbError),
}

/// What an imagery build reports as it goes.
#[derive(Clone, Copy, Debug)]
pub enum ImageryProgress {
    /// Images opened (16-bit ones read once for their histogram), of `total`.
    Open { done: u64, total: u64 },
    /// Bands of tile rows built over all levels, of `total`.
    Build { done: u64, total: u64 },
}

/// Opens every image and checks it overlaps the database's grid.
pub fn open_images(
    manifest: &Manifest,
    images: &[PathBuf],
    progress: &mut dyn FnMut(ImageryProgress),
) -> Result<Vec<ImageSource>, ImageryError> {
    let g = manifest.layout.grid;
    let database = (
        g.south_lat_deg,
        g.west_lon_deg,
        g.north_lat_deg(),
        g.east_lon_deg(),
    );
    let total = images.len() as u64;
    let mut sources = Vec::with_capacity(images.len());
    for (i, path) in images.iter().enumerate() {
        let source = ImageSource::open(path)?;
        let image = source.footprint_deg();
        let overlaps = image.0 < database.2
            && database.0 < image.2
            && image.1 < database.3
            && database.1 < image.3;
        if !overlaps {
            return Err(ImageryError::NoOverlap {
                image,
                database,
                path: path.clone(),
            });
        }
        sources.push(source);
        progress(ImageryProgress::Open {
            done: i as u64 + 1,
            total,
        });
    }
    Ok(sources)
}

/// Builds the imagery pyramid of `images` (and `overlays`) for the database whose `manifest`
/// is given into `root/imagery/` (which must not hold imagery yet), and returns the manifest's
/// imagery section. Writes no manifest.
pub fn write_imagery(
    root: &Path,
    manifest: &Manifest,
    images: &[PathBuf],
    overlays: &[&dyn OverlayLayer],
    progress: &mut dyn FnMut(ImageryProgress),
) -> Result<ImageryManifest, ImageryError> {
    if images.is_empty() && overlays.is_empty() {
        return Err(ImageryError::NoInput);
    }
    let sources = open_images(manifest, images, progress)?;
    let layout = imagery_layout(
        &manifest.layout.grid,
        manifest.spacing_m,
        &sources,
        overlays,
    );
    let mut made_dirs = vec![false; usize::from(layout.levels)];
    let summary = build_pyramid(
        &layout,
        manifest.spacing_m,
        &sources,
        overlays,
        &mut |tile| {
            let path = imagery_tile_path(root, tile.key);
            let level = usize::from(tile.key.level);
            if !made_dirs.get(level).copied().unwrap_or(true) {
                if let Some(dir) = path.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| ImageryError::Io {
                        reason: e.to_string(),
                        path: dir.to_path_buf(),
                    })?;
                }
                made_dirs[level] = true;
            }
            std::fs::write(&path, tile.encode()).map_err(|e| ImageryError::Io {
                reason: e.to_string(),
                path: path.clone(),
            })
        },
        &mut |done, total| progress(ImageryProgress::Build { done, total }),
    )?;
    let mut lines: Vec<String> = sources.iter().map(ImageSource::describe).collect();
    lines.extend(overlays.iter().map(|o| o.describe()));
    Ok(ImageryManifest {
        layout,
        tile_count: summary.tiles,
        sources: lines,
    })
}

/// Adds imagery to (or replaces the imagery of) the database at `db`, its own features (the
/// roads, rivers and lakes it was built with) painted over it again: the new database is
/// assembled in a staging sibling directory (elevation tiles hard-linked, or copied where links
/// are refused) and renamed over `db` only when complete. On any error `db` is unchanged.
pub fn add_imagery(
    db: &Path,
    images: &[PathBuf],
    overlays: &[&dyn OverlayLayer],
    progress: &mut dyn FnMut(ImageryProgress),
) -> Result<Manifest, ImageryError> {
    crate::store::change_in_staging::<ImageryError>(db, "imagery", &mut |staging, manifest| {
        // The database's own roads, rivers and lakes are painted over the new imagery too.
        let stored = stored_features(staging)?;
        let mut all: Vec<&dyn OverlayLayer> = overlays.to_vec();
        if let Some(layer) = &stored {
            all.push(layer);
        }
        manifest.imagery = Some(write_imagery(staging, manifest, images, &all, progress)?);
        Ok(())
    })
}

/// The feature layer of the features a database keeps
/// ([`crate::features::DATABASE_FEATURES_FILE`]), when it has any.
fn stored_features(
    root: &Path,
) -> Result<Option<cig_terrain::features::FeatureLayer>, ImageryError> {
    let path = root.join(crate::features::DATABASE_FEATURES_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let bad = |reason: String| ImageryError::Corrupt {
        reason: format!("the database's feature file: {reason}"),
        path: path.clone(),
    };
    let features = crate::features::read_features(&path).map_err(|e| bad(e.to_string()))?;
    let layer =
        cig_terrain::features::FeatureLayer::new(&features).map_err(|e| bad(e.to_string()))?;
    Ok((!layer.is_empty()).then_some(layer))
}
