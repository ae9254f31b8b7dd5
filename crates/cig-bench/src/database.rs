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
/// ground levelled under them, painted into the imagery) and its culture (settlements, power
/// poles, trees and bushes by [`cig_synth::culture::place_culture`] with the default rules).
///
/// # Errors
/// When `out` exists (without `force`), the parameters are refused, or writing fails.
pub fn synthesize_database(
    params: &cig_synth::SynthParams,
    options: &cig_synth::SynthOptions,
    out: &Path,
    force: bool,
    tile_cells: u32,
    progress: &mut dyn FnMut(BuildProgress<'_>),
) -> Result<cig_terrain::Manifest, BenchError> {
    check_output(out, force)?;
    progress(BuildProgress::Begin(BuildStage::Synthesize));
    let (mut raster, report, features) =
        cig_synth::synthesize_with_options(params, options, &mut |step, fraction| {
            progress(BuildProgress::Synthesize { step, fraction });
        })
        .step("cannot synthesize terrain")?;
    progress(BuildProgress::Synthesize {
        step: "culture",
        fraction: 0.0,
    });
    let culture = cig_synth::culture::place_culture(
        &raster,
        &report,
        &features,
        &cig_synth::culture::CultureRules::default(),
        params.seed,
    )
    .step("cannot place culture")?;
    progress(BuildProgress::Synthesize {
        step: "culture",
        fraction: 1.0,
    });
    progress(BuildProgress::End);
    tracing::info!("culture: {} objects placed", culture.len());
    let mut source = format!(
        "cig-synth seed={} origin={},{} size_km={} spacing_m={}",
        params.seed, params.origin_lat_deg, params.origin_lon_deg, params.size_km, params.spacing_m
    );
    if let Some(side) = options.sea_side {
        source.push_str(&format!(" sea_side={side}"));
    }
    // Its roads, rivers and lakes as shapes, painted into the imagery.
    build_database_with_imagery(
        &mut raster,
        vec![source],
        Drape {
            images: &[],
            features: &features,
            culture: &culture,
            culture_rules: None,
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
    /// Trees and bushes to scatter by material ([`cig_synth::culture::scatter_by_material`],
    /// seeded with [`SCATTERED_CULTURE_SEED`]) once the materials are derived and the ground
    /// levelled under the features; added to `culture`.
    pub culture_rules: Option<&'a cig_synth::culture::CultureRules>,
}

/// Seed of the vegetation [`Drape::culture_rules`] scatters (the same database and rules give
/// the same trees).
pub const SCATTERED_CULTURE_SEED: u64 = 1;

/// [`build_database`] with the ground under `drape`'s features levelled (roads without cross
/// slope, lakes flat at their level: part of the database's one surface), vegetation scattered
/// by `drape.culture_rules` (when given) on the materials then, and the culture and the
/// imagery pyramid of its images and features (when any) built into the same staging
/// directory before the database is moved into place: a failure writes nothing.
///
/// # Errors
/// As [`build_database`], and when an image, a placement or the culture rules are refused.
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
    let scattered;
    let culture = match drape.culture_rules {
        Some(rules) => {
            let trees =
                cig_synth::culture::scatter_by_material(raster, rules, SCATTERED_CULTURE_SEED)
                    .step("cannot place culture")?;
            tracing::info!(
                "culture: {} trees and bushes scattered by material",
                trees.len()
            );
            let mut all = Vec::with_capacity(drape.culture.len() + trees.len());
            all.extend_from_slice(drape.culture);
            all.extend(trees);
            scattered = all;
            scattered.as_slice()
        }
        None => drape.culture,
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
            let culture = fit_culture_to_tiles(&manifest.layout, culture);
            manifest.culture =
                cig_terrain_io::store::write_culture(staging, &manifest.layout, &culture)?;
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

/// `placements`, thinned where a finest tile of `layout` would hold more than
/// [`cig_terrain::culture::MAX_ITEMS_PER_TILE`] objects (very large tiles over dense
/// vegetation): such a tile keeps its buildings, walls, fences and poles and an even share of
/// its trees and bushes, chosen in placement order (deterministic).
fn fit_culture_to_tiles<'a>(
    layout: &cig_terrain::PyramidLayout,
    placements: &'a [cig_terrain::CulturePlacement],
) -> std::borrow::Cow<'a, [cig_terrain::CulturePlacement]> {
    use cig_terrain::culture::MAX_ITEMS_PER_TILE;
    use std::collections::BTreeMap;
    if placements.len() <= MAX_ITEMS_PER_TILE {
        return placements.into();
    }
    let grid = &layout.grid;
    let tile_of = |p: &cig_terrain::CulturePlacement| {
        let row_f = (p.lat_deg - grid.south_lat_deg) / grid.dlat_deg;
        let col_f = (p.lon_deg - grid.west_lon_deg) / grid.dlon_deg;
        layout.locate(0, row_f, col_f).0
    };
    let is_vegetation = |p: &cig_terrain::CulturePlacement| {
        p.kind.is_tree() || p.kind == cig_terrain::CultureKind::Bush
    };
    // Per tile: objects, and vegetation among them.
    let mut counts: BTreeMap<cig_terrain::TileKey, (usize, usize)> = BTreeMap::new();
    for p in placements {
        let entry = counts.entry(tile_of(p)).or_default();
        entry.0 += 1;
        entry.1 += usize::from(is_vegetation(p));
    }
    // Share of vegetation kept in each over-full tile.
    let keep: BTreeMap<cig_terrain::TileKey, f64> = counts
        .iter()
        .filter(|(_, &(all, _))| all > MAX_ITEMS_PER_TILE)
        .map(|(&key, &(all, vegetation))| {
            let room = MAX_ITEMS_PER_TILE.saturating_sub(all - vegetation);
            (key, room as f64 / vegetation.max(1) as f64)
        })
        .collect();
    if keep.is_empty() {
        return placements.into();
    }
    tracing::warn!(
        "culture: {} finest tile(s) would hold more than {MAX_ITEMS_PER_TILE} objects; their \
         trees and bushes are thinned",
        keep.len()
    );
    let mut seen: BTreeMap<cig_terrain::TileKey, usize> = BTreeMap::new();
    let mut out = Vec::with_capacity(placements.len());
    for p in placements {
        let key = tile_of(p);
        if let (Some(&share), true) = (keep.get(&key), is_vegetation(p)) {
            let k = seen.entry(key).or_default();
            // The k-th object is kept when the running count of kept ones steps up.
            let kept = ((*k + 1) as f64 * share).floor() > (*k as f64 * share).floor();
            *k += 1;
            if !kept {
                continue;
            }
        }
        out.push(*p);
    }
    out.into()
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
pub fn demo_or(
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
        synthesize_database(
            &demo_params(),
            &cig_synth::SynthOptions::default(),
            &path,
            false,
            tile_cells,
            progress,
        )?;
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cig_terrain::{CultureKind, CulturePlacement, GeoGrid, PyramidLayout};

    fn grid(posts: usize, spacing_deg: f64) -> GeoGrid {
        GeoGrid {
            south_lat_deg: 36.0,
            west_lon_deg: -121.0,
            dlat_deg: spacing_deg,
            dlon_deg: spacing_deg,
            rows: posts,
            cols: posts,
        }
    }

    #[test]
    fn a_synthetic_database_stands_its_culture() {
        let dir = tempfile::tempdir().unwrap();
        let params = cig_synth::SynthParams {
            size_km: 8.0,
            spacing_m: 60.0,
            seed: 2,
            ..demo_params()
        };
        let manifest = synthesize_database(
            &params,
            &cig_synth::SynthOptions::default(),
            &dir.path().join("db"),
            false,
            64,
            &mut |_| {},
        )
        .unwrap();
        let culture = manifest.culture.expect("culture in the manifest");
        assert!(culture.trees() > 1_000, "{culture:?}");
        assert!(culture.buildings() > 10, "{culture:?}");
        assert!(culture.counts.get("power_pole").copied().unwrap_or(0) > 10);
        let files = std::fs::read_dir(dir.path().join("db").join("culture"))
            .unwrap()
            .count();
        assert_eq!(files as u64, culture.tiles);
    }

    #[test]
    fn an_imported_raster_gets_trees_by_its_material_rules() {
        // Hills steep enough for the derived materials to hold forest (10-35 degrees).
        let g = grid(161, 1.0 / 3600.0);
        let hills = |r: usize, c: usize| {
            let (x, y) = (c as f64 * 25.0, r as f64 * 30.0);
            (300.0 + 80.0 * (x / 150.0).sin() * (y / 200.0).cos()) as f32
        };
        let dir = tempfile::tempdir().unwrap();
        let rules = cig_synth::culture::CultureRules::default();
        let house = CulturePlacement {
            kind: CultureKind::House,
            lat_deg: 36.01,
            lon_deg: -120.99,
            height_m: 7.0,
            width_m: 8.0,
            length_m: 11.0,
            heading_deg: 30.0,
            variant: 1,
        };
        let build = |name: &str, rules| {
            let mut raster = Raster::from_fn(g, hills);
            build_database_with_imagery(
                &mut raster,
                vec!["test".into()],
                Drape {
                    culture: &[house],
                    culture_rules: rules,
                    ..Drape::default()
                },
                &dir.path().join(name),
                false,
                64,
                &mut |_| {},
            )
            .unwrap()
        };
        let with = build("with", Some(&rules)).culture.expect("culture");
        assert!(with.trees() > 500, "{with:?}");
        assert_eq!(with.buildings(), 1, "the drape's own culture is kept");
        let without = build("without", None).culture.expect("culture");
        assert_eq!((without.trees(), without.buildings()), (0, 1));
        // Bad rules are refused, naming the rule.
        let bad = cig_synth::culture::CultureRules {
            conifer_fraction: 2.0,
            ..rules.clone()
        };
        let mut raster = Raster::from_fn(g, hills);
        let err = build_database_with_imagery(
            &mut raster,
            vec!["test".into()],
            Drape {
                culture_rules: Some(&bad),
                ..Drape::default()
            },
            &dir.path().join("bad"),
            false,
            64,
            &mut |_| {},
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("conifer_fraction"), "{err}");
        assert!(!dir.path().join("bad").exists());
    }

    #[test]
    fn overfull_tiles_are_thinned_keeping_their_buildings() {
        let layout = PyramidLayout::new(grid(65, 1e-4), 64);
        let max = cig_terrain::culture::MAX_ITEMS_PER_TILE;
        let tree = |k: usize| CulturePlacement {
            kind: CultureKind::ConiferTree,
            lat_deg: 36.0 + (k % 997) as f64 * 6e-6,
            lon_deg: -121.0 + (k / 997) as f64 * 6e-6,
            height_m: 15.0,
            width_m: 5.0,
            length_m: 5.0,
            heading_deg: 0.0,
            variant: 0,
        };
        let house = CulturePlacement {
            kind: CultureKind::House,
            ..tree(5)
        };
        let mut placements: Vec<CulturePlacement> = (0..max + 1_000).map(tree).collect();
        placements.insert(10, house);
        placements.push(house);
        let fitted = fit_culture_to_tiles(&layout, &placements);
        assert!(fitted.len() <= max, "{}", fitted.len());
        assert!(fitted.len() > max - 10, "{}", fitted.len());
        assert_eq!(
            fitted
                .iter()
                .filter(|p| p.kind == CultureKind::House)
                .count(),
            2
        );
        assert_eq!(fit_culture_to_tiles(&layout, &placements), fitted);
        cig_terrain::culture::bin_placements(&layout, &fitted).expect("fits");
        // Below the limit nothing changes.
        let few = &placements[..1_000];
        assert!(matches!(
            fit_culture_to_tiles(&layout, few),
            std::borrow::Cow::Borrowed(_)
        ));
    }
}
