//! Databases for the demo and the benchmarks: the demo database's parameters, and building a
//! database from a raster (or from synthesis) with its progress reported to a callback, so a
//! caller can draw progress bars (`cig db synth|import`, `cig demo`, `cig bench`).

use crate::{BenchError, Step};
use cig_terrain::build::prepare_raster;
use cig_terrain::features::{level_terrain, Feature, FeatureLayer};
use cig_terrain::raster::Raster;
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use cig_terrain_io::imagery::{write_imagery, ImageryError, ImageryProgress, OverlayLayer};
use cig_terrain_io::store::{check_output, open_database, write_database_with, BuildInputs};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The demo database: 50 km x 50 km at 30 m posts from near Fort Hunter Liggett, California.
#[must_use]
pub fn demo_params() -> cig_synth::SynthParams {
    cig_synth::SynthParams {
        origin_lat_deg: 35.98,
        origin_lon_deg: -121.23,
        size_km: 50.0,
        spacing_m: 30.0,
        seed: 1,
    }
}

/// The stages of a build, in order (synthesis only when synthesizing).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildStage {
    /// Generating the terrain: a known fraction.
    Synthesize,
    /// Filling voids and deriving materials: no fraction known.
    Prepare,
    /// Writing the pyramid's tiles: tiles written of tiles in all.
    Write,
    /// Building the imagery pyramid (`BuildProgress::Imagery`).
    Imagery,
}

/// What a build reports as it goes.
#[derive(Clone, Copy, Debug)]
pub enum BuildProgress<'a> {
    /// A stage begins.
    Begin(BuildStage),
    /// Synthesis: the step under way (`"landform"`, `"hydrology"` …) and the fraction done.
    Synthesize { step: &'a str, fraction: f32 },
    /// Tiles written so far, of `total`.
    Write { done: u64, total: u64 },
    /// Images opened, then bands of imagery tiles built.
    Imagery(ImageryProgress),
    /// The stage that began last is over.
    End,
}

/// Generates the terrain of `params` and writes it as a database at `out` (replaced only with
/// `force`), tiles of `tile_cells` cells, with its roads, rivers and lakes as shapes (the
/// ground levelled under them, painted into the imagery).
///
/// # Errors
/// When `out` exists (without `force`), the parameters are refused, or writing fails.
pub fn synthesize_database(
    params: &cig_synth::SynthParams,
    out: &Path,
    force: bool,
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<cig_terrain::Manifest, BenchError> {
    check_output(out, force)?;
    progress(BuildProgress::Begin(BuildStage::Synthesize));
    let (mut raster, _, features) =
        cig_synth::synthesize_with_features(params, &mut |step, fraction| {
            progress(BuildProgress::Synthesize { step, fraction });
        })
        .step("cannot synthesize terrain")?;
    progress(BuildProgress::End);
    let source = format!(
        "cig-synth seed={} origin={},{} size_km={} spacing_m={}",
        params.seed, params.origin_lat_deg, params.origin_lon_deg, params.size_km, params.spacing_m
    );
    // Its roads, rivers and lakes as shapes, painted into the imagery.
    build_database_with_imagery(
        &mut raster,
        vec![source],
        Drape {
            images: &[],
            features: &features,
            culture: &[],
        },
        out,
        force,
        tile_cells,
        progress,
    )
}

/// Fills voids, derives materials and writes a raster as a database at `out` (replaced only
/// with `force`), naming its `sources` in the manifest.
///
/// # Errors
/// When the raster has only voids, `out` exists (without `force`) or writing fails.
pub fn build_database(
    raster: &mut Raster,
    sources: Vec<String>,
    out: &Path,
    force: bool,
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<cig_terrain::Manifest, BenchError> {
    build_database_with_imagery(
        raster,
        sources,
        Drape::default(),
        out,
        force,
        tile_cells,
        progress,
    )
}

/// What is draped over a database as it is built: orthoimages, roads, rivers and lakes as
/// shapes, and the culture standing on it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Drape<'a> {
    pub images: &'a [PathBuf],
    pub features: &'a [Feature],
    /// Trees, buildings, walls, fences and poles (`cig_terrain::culture`).
    pub culture: &'a [cig_terrain::CulturePlacement],
}

/// [`build_database`] with the ground under `drape`'s features levelled (roads without cross
/// slope, lakes flat at their level: part of the database's one surface), then the imagery
/// pyramid of its images and features (when any) built into the same staging directory
/// before the database is moved into place: a failure writes nothing.
///
/// # Errors
/// As [`build_database`], and when an image is refused.
pub fn build_database_with_imagery(
    raster: &mut Raster,
    sources: Vec<String>,
    drape: Drape<'_>,
    out: &Path,
    force: bool,
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<cig_terrain::Manifest, BenchError> {
    progress(BuildProgress::Begin(BuildStage::Prepare));
    let report = prepare_raster(raster).step("cannot fill voids")?;
    progress(BuildProgress::End);
    if report.void_posts_filled > 0 {
        tracing::warn!("filled {} void posts", report.void_posts_filled);
    }
    let layer = if drape.features.is_empty() {
        None
    } else {
        let levelled = level_terrain(raster, drape.features).step("cannot lay the features")?;
        tracing::info!(
            "features: {} road posts levelled, {} lake posts set to their level",
            levelled.road_posts,
            levelled.lake_posts
        );
        Some(FeatureLayer::new(drape.features).step("cannot lay the features")?)
    };
    let overlays: Vec<&dyn OverlayLayer> = layer.iter().map(|l| l as &dyn OverlayLayer).collect();
    let images = drape.images;
    let inputs = BuildInputs {
        sources,
        void_posts_filled: report.void_posts_filled as u64,
        tile_cells,
    };
    progress(BuildProgress::Begin(BuildStage::Write));
    // Both callbacks report progress: share it through a cell.
    let progress = std::cell::RefCell::new(progress);
    let manifest = write_database_with::<ImageryError>(
        out,
        raster,
        &inputs,
        force,
        &mut |done, total| (progress.borrow_mut())(BuildProgress::Write { done, total }),
        &mut |staging, manifest| {
            (progress.borrow_mut())(BuildProgress::End);
            manifest.culture =
                cig_terrain_io::store::write_culture(staging, &manifest.layout, drape.culture)?;
            if images.is_empty() && overlays.is_empty() {
                return Ok(());
            }
            if !drape.features.is_empty() {
                // Kept with the database, so new imagery is painted with them again.
                let path = staging.join(cig_terrain_io::features::DATABASE_FEATURES_FILE);
                cig_terrain_io::features::write_features(&path, drape.features).map_err(|e| {
                    ImageryError::Io {
                        reason: e.to_string(),
                        path: path.clone(),
                    }
                })?;
            }
            (progress.borrow_mut())(BuildProgress::Begin(BuildStage::Imagery));
            let imagery = write_imagery(staging, manifest, images, &overlays, &mut |p| {
                (progress.borrow_mut())(BuildProgress::Imagery(p));
            })?;
            manifest.imagery = Some(imagery);
            (progress.borrow_mut())(BuildProgress::End);
            Ok(())
        },
    )
    .step("cannot build database")?;
    Ok(manifest)
}

/// Opens a database with a paging cache and a query session.
///
/// # Errors
/// When the database cannot be opened or the paging configuration is refused.
pub fn open_session(db: &Path, paging: &PagingConfig) -> Result<QuerySession, BenchError> {
    let db = Arc::new(open_database(db)?);
    let cache = TileCache::new(db, paging.clone())?;
    Ok(QuerySession::new(Arc::new(cache)))
}

/// `db`, or when none is given the demo database "demo-db" (built there first when missing,
/// logged with `label`).
pub(crate) fn demo_or(
    db: Option<&Path>,
    label: &str,
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<std::path::PathBuf, BenchError> {
    let path = db.map_or_else(|| Path::new("demo-db").to_path_buf(), Path::to_path_buf);
    if db.is_none() && !path.exists() {
        tracing::warn!(
            "{label}: building the demo database (50 km x 50 km, 30 m posts) at {}",
            path.display()
        );
        synthesize_database(&demo_params(), &path, false, tile_cells, progress)?;
    }
    Ok(path)
}
