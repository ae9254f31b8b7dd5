//! `cig db synth|import|imagery|culture|info`.

use crate::cli::{CultureArgs, ImageryArgs, ImportArgs, InfoArgs, SynthArgs};
use crate::config::Config;
use anyhow::Context;
use cig_scene::lod::{error_range_m, LevelErrors, NodeLayout};
use cig_scene::view::FovDeg;
use cig_terrain_io::store::{check_output, open_database};
use std::path::Path;
use std::time::Instant;

/// Parses "LAT,LON" in degrees.
pub fn parse_lat_lon(text: &str) -> anyhow::Result<(f64, f64)> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [lat, lon] = parts.as_slice() else {
        anyhow::bail!("--origin {text:?} must be LAT,LON in degrees");
    };
    let lat: f64 = lat
        .parse()
        .with_context(|| format!("--origin latitude {lat:?} is not a number"))?;
    let lon: f64 = lon
        .parse()
        .with_context(|| format!("--origin longitude {lon:?} is not a number"))?;
    anyhow::ensure!(
        (-90.0..=90.0).contains(&lat),
        "--origin latitude {lat} is outside -90..90"
    );
    anyhow::ensure!(
        (-180.0..=180.0).contains(&lon),
        "--origin longitude {lon} is outside -180..180"
    );
    Ok((lat, lon))
}

/// `--sea-side SIDE`: west, east, north or south.
fn parse_sea_side(text: &str) -> anyhow::Result<cig_synth::SeaSide> {
    text.parse::<cig_synth::SeaSide>().context("--sea-side")
}

pub fn synth(args: &SynthArgs, config: &Config) -> anyhow::Result<()> {
    let (lat, lon) = parse_lat_lon(&args.origin)?;
    let sea_side = args.sea_side.as_deref().map(parse_sea_side).transpose()?;
    let params = cig_synth::SynthParams {
        origin_lat_deg: lat,
        origin_lon_deg: lon,
        size_km: args.size_km,
        spacing_m: args.spacing_m,
        seed: args.seed,
    };
    let started = Instant::now();
    let options = cig_synth::SynthOptions::default().with_sea_side(sea_side);
    let summary = synthesize_database(&params, &options, &args.out, args.force, config)?;
    eprintln!(
        "built {} tiles in {:.1} s: {}",
        summary.tile_count,
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

/// Generates and writes a synthetic database with progress bars (shared with `demo`).
pub fn synthesize_database(
    params: &cig_synth::SynthParams,
    options: &cig_synth::SynthOptions,
    out: &Path,
    force: bool,
    config: &Config,
) -> anyhow::Result<cig_terrain::Manifest> {
    Ok(cig_bench::database::synthesize_database(
        params,
        options,
        out,
        force,
        config.database.tile_cells,
        &mut crate::output::build_progress(),
    )?)
}

/// `--culture-rules`: "default", or a TOML file of rules per material, checked.
fn read_culture_rules(text: &str) -> anyhow::Result<cig_synth::culture::CultureRules> {
    if text == "default" {
        return Ok(cig_synth::culture::CultureRules::default());
    }
    let path = std::path::Path::new(text);
    let source = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read culture rules {}", path.display()))?;
    let rules: cig_synth::culture::CultureRules = toml::from_str(&source).map_err(|e| {
        anyhow::anyhow!(
            "bad culture rules: {}: {}",
            e.message().trim(),
            path.display()
        )
    })?;
    rules
        .validate()
        .map_err(|e| anyhow::anyhow!("bad culture rules: {e}: {}", path.display()))?;
    Ok(rules)
}

pub fn import(args: &ImportArgs, config: &Config) -> anyhow::Result<()> {
    check_output(&args.out, args.force)?;
    // The feature file (roads, rivers, lakes and culture) is read before the DEMs, so a broken
    // one costs no import.
    let file = match &args.features {
        Some(path) => cig_terrain_io::features::read_feature_file(path)?,
        None => cig_terrain_io::features::FeatureFile::default(),
    };
    let culture_rules = args
        .culture_rules
        .as_deref()
        .map(read_culture_rules)
        .transpose()?;
    let started = Instant::now();
    let bar = crate::output::bar(args.inputs.len() as u64, "read DEMs");
    let area = cig_terrain_io::import::import_files(&args.inputs, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })
    .context("cannot import")?;
    bar.finish_and_clear();
    let mut raster = area.raster;
    // Culture outside the imported area is refused before anything is written.
    if let Some(path) = &args.features {
        cig_terrain_io::culture::check_culture_inside(path, &file.culture, &raster.grid)?;
    }
    let culture = cig_terrain_io::culture::placements(&file.culture);
    let sources = area
        .sources
        .iter()
        .map(|s| {
            let mut line = format!("{} {}", s.format.name(), s.path.display());
            if let Some(epsg) = s.reprojected_from_epsg {
                line.push_str(&format!(" (resampled from EPSG:{epsg})"));
            }
            if s.void_posts > 0 {
                line.push_str(&format!(" ({} void posts)", s.void_posts));
            }
            line
        })
        .collect();
    let manifest = cig_bench::database::build_database_with_imagery(
        &mut raster,
        sources,
        cig_bench::database::Drape {
            images: &args.imagery,
            features: &file.features,
            culture: &culture,
            culture_rules: culture_rules.as_ref(),
        },
        &args.out,
        args.force,
        config.database.tile_cells,
        &mut crate::output::build_progress(),
    )?;
    eprintln!(
        "imported {} file(s) into {} tiles in {:.1} s ({} void posts filled): {}",
        args.inputs.len(),
        manifest.tile_count,
        started.elapsed().as_secs_f64(),
        manifest.void_posts_filled,
        args.out.display()
    );
    if let Some(imagery) = &manifest.imagery {
        eprintln!(
            "draped {} image(s) as {} imagery tiles",
            args.imagery.len(),
            imagery.tile_count
        );
    }
    if let Some(culture) = &manifest.culture {
        eprintln!("placed {}", culture_summary(culture));
    }
    Ok(())
}

/// "1234 culture objects (1000 trees, 30 buildings) in 12 tiles".
fn culture_summary(culture: &cig_terrain::CultureManifest) -> String {
    format!(
        "{} culture objects ({} trees, {} buildings) in {} tiles",
        culture.total(),
        culture.trees(),
        culture.buildings(),
        culture.tiles
    )
}

/// `db info`'s culture section: always present, zeros without culture; every kind named.
fn culture_json(culture: Option<&cig_terrain::CultureManifest>) -> serde_json::Value {
    let empty = cig_terrain::CultureManifest::default();
    let c = culture.unwrap_or(&empty);
    let by_kind: serde_json::Map<String, serde_json::Value> = cig_terrain::CultureKind::ALL
        .iter()
        .map(|k| {
            let n = c.counts.get(k.name()).copied().unwrap_or(0);
            (k.name().to_string(), serde_json::Value::from(n))
        })
        .collect();
    serde_json::json!({
        "total": c.total(),
        "trees": c.trees(),
        "buildings": c.buildings(),
        "by_kind": by_kind,
        "tiles": c.tiles,
        "max_per_tile": c.max_items_per_tile,
    })
}

pub fn imagery(args: &ImageryArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let mut progress = crate::output::build_progress();
    progress(cig_bench::database::BuildProgress::Begin(
        cig_bench::database::BuildStage::Imagery,
    ));
    let manifest = cig_terrain_io::imagery::add_imagery(&args.db, &args.images, &[], &mut |p| {
        progress(cig_bench::database::BuildProgress::Imagery(p));
    })
    .context("cannot add imagery")?;
    progress(cig_bench::database::BuildProgress::End);
    let tiles = manifest.imagery.as_ref().map_or(0, |i| i.tile_count);
    eprintln!(
        "draped {} image(s) as {tiles} imagery tiles in {:.1} s: {}",
        args.images.len(),
        started.elapsed().as_secs_f64(),
        args.db.display()
    );
    Ok(())
}

pub fn culture(args: &CultureArgs) -> anyhow::Result<()> {
    let file = cig_terrain_io::features::read_feature_file(&args.features)?;
    let manifest = open_database(&args.db)?.manifest().clone();
    cig_terrain_io::culture::check_culture_inside(
        &args.features,
        &file.culture,
        &manifest.layout.grid,
    )?;
    if !file.features.is_empty() {
        tracing::warn!(
            "{} road, river and lake feature(s) of {} left out: they are laid only by `cig db \
             import`",
            file.features.len(),
            args.features.display()
        );
    }
    let placements = cig_terrain_io::culture::placements(&file.culture);
    let manifest = cig_terrain_io::store::replace_culture(&args.db, &placements)
        .with_context(|| format!("cannot replace the culture of {}", args.db.display()))?;
    match &manifest.culture {
        Some(culture) => eprintln!("placed {}: {}", culture_summary(culture), args.db.display()),
        None => eprintln!("removed the culture: {}", args.db.display()),
    }
    Ok(())
}

/// Level-0 texel size of the imagery, metres (north-south, east-west).
fn imagery_texel_m(manifest: &cig_terrain::Manifest, fine_shift: u8) -> [f64; 2] {
    let s = f64::from(1u32 << fine_shift);
    [manifest.spacing_m[0] / s, manifest.spacing_m[1] / s]
}

/// `db info` as JSON.
pub fn info_json(manifest: &cig_terrain::Manifest) -> serde_json::Value {
    let g = manifest.layout.grid;
    serde_json::json!({
        "origin": {"lat": g.south_lat_deg, "lon": g.west_lon_deg},
        "extent_deg": {
            "south": g.south_lat_deg, "west": g.west_lon_deg,
            "north": g.north_lat_deg(), "east": g.east_lon_deg(),
            "lat": g.north_lat_deg() - g.south_lat_deg, "lon": g.east_lon_deg() - g.west_lon_deg,
        },
        "spacing_m": 0.5 * (manifest.spacing_m[0] + manifest.spacing_m[1]),
        "spacing_m_north_east": manifest.spacing_m,
        "spacing_deg": {"lat": g.dlat_deg, "lon": g.dlon_deg},
        "posts": {"rows": g.rows, "cols": g.cols},
        "tile_cells": manifest.layout.tile_cells,
        "levels": manifest.layout.levels,
        "tiles": manifest.tile_count,
        "min_elev_m": manifest.min_elevation_m,
        "max_elev_m": manifest.max_elevation_m,
        "vertical_datum": manifest.vertical_datum,
        "void_posts_filled": manifest.void_posts_filled,
        "materials": manifest.material_posts,
        "sources": manifest.sources,
        "format_version": manifest.format_version,
        "imagery": manifest.imagery.as_ref().map(|i| serde_json::json!({
            "levels": i.layout.levels,
            "fine_shift": i.layout.fine_shift,
            "texel_m_north_east": imagery_texel_m(manifest, i.layout.fine_shift),
            "texels": {"rows": i.layout.rows, "cols": i.layout.cols},
            "tiles": i.tile_count,
            "sources": i.sources,
        })),
        "culture": culture_json(manifest.culture.as_ref()),
    })
}

/// The reference view of `db info --lod-errors`' refinement distances: 1920 x 1080 across 60
/// degrees at 1 px.
const LOD_REFERENCE_SIZE: (u32, u32) = (1920, 1080);
const LOD_REFERENCE_FOV_DEG: f64 = 60.0;
const LOD_REFERENCE_PX: f64 = 1.0;

/// Where a node of `error_m` refines on the reference view, metres.
fn reference_range_m(error_m: f32) -> f64 {
    let (w, h) = LOD_REFERENCE_SIZE;
    let fov = FovDeg::from_horizontal(LOD_REFERENCE_FOV_DEG, w, h);
    error_range_m(
        f64::from(error_m),
        fov.pixels_per_tangent(w, h),
        LOD_REFERENCE_PX,
    )
}

/// What `db info --lod-errors` reads from every tile.
struct LodReport {
    levels: Vec<LevelErrors>,
    /// Tiles without their posts' hierarchy errors (tile format 1), drawn as regular grids.
    tiles_without_post_errors: u64,
}

/// Per level, the error distribution of the level-of-detail nodes, and how many tiles lack the
/// posts' hierarchy errors (every tile is read, one at a time).
fn lod_errors(db: &cig_terrain::TerrainDatabase) -> anyhow::Result<LodReport> {
    let layout = NodeLayout::new(*db.layout());
    let mut report = LodReport {
        levels: Vec::new(),
        tiles_without_post_errors: 0,
    };
    for level in 0..layout.pyramid.levels {
        let mut node_errors = Vec::new();
        for key in layout.pyramid.keys_at(level) {
            let tile = db
                .load_tile(key)
                .with_context(|| format!("reading {}", db.tile_location(key)))?;
            layout.node_errors_in(key, &tile, &mut node_errors);
            report.tiles_without_post_errors += u64::from(tile.lod_errors.is_none());
        }
        report.levels.extend(LevelErrors::of(level, node_errors));
    }
    Ok(report)
}

fn lod_errors_json(report: &LodReport) -> serde_json::Value {
    let (width_px, height_px) = LOD_REFERENCE_SIZE;
    let levels = &report.levels;
    serde_json::json!({
        "tiles_without_post_errors": report.tiles_without_post_errors,
        "reference_view": {
            "width_px": width_px,
            "height_px": height_px,
            "fov_deg": LOD_REFERENCE_FOV_DEG,
            "max_pixel_error": LOD_REFERENCE_PX,
        },
        "levels": levels.iter().map(|l| serde_json::json!({
            "level": l.level,
            "nodes": l.nodes,
            "median_m": l.median_m,
            "p90_m": l.p90_m,
            "max_m": l.max_m,
            "median_node_refines_within_m": reference_range_m(l.median_m),
        })).collect::<Vec<_>>(),
    })
}

pub fn info(args: &InfoArgs) -> anyhow::Result<()> {
    let db = open_database(&args.db)?;
    let m = db.manifest();
    let levels = if args.lod_errors {
        Some(lod_errors(&db)?)
    } else {
        None
    };
    if args.json {
        let mut json = info_json(m);
        if let (Some(levels), Some(object)) = (&levels, json.as_object_mut()) {
            object.insert("lod_errors".into(), lod_errors_json(levels));
        }
        println!("{json}");
        return Ok(());
    }
    let g = m.layout.grid;
    println!("database      {}", args.db.display());
    println!(
        "origin        {:.6}, {:.6} (south-west post)",
        g.south_lat_deg, g.west_lon_deg
    );
    println!(
        "extent        {:.6} .. {:.6} N, {:.6} .. {:.6} E",
        g.south_lat_deg,
        g.north_lat_deg(),
        g.west_lon_deg,
        g.east_lon_deg()
    );
    println!(
        "posts         {} x {} at {:.2} m x {:.2} m",
        g.rows, g.cols, m.spacing_m[0], m.spacing_m[1]
    );
    println!(
        "pyramid       {} levels, {} tiles of {} cells",
        m.layout.levels, m.tile_count, m.layout.tile_cells
    );
    println!(
        "elevation     {:.1} .. {:.1} m ({})",
        m.min_elevation_m, m.max_elevation_m, m.vertical_datum
    );
    println!("voids filled  {}", m.void_posts_filled);
    let total: u64 = m.material_posts.values().sum();
    for (name, n) in &m.material_posts {
        if *n > 0 {
            println!(
                "  {name:<11} {:5.1} %",
                100.0 * *n as f64 / total.max(1) as f64
            );
        }
    }
    for s in &m.sources {
        println!("source        {s}");
    }
    if let Some(imagery) = &m.imagery {
        let [north_m, east_m] = imagery_texel_m(m, imagery.layout.fine_shift);
        println!(
            "imagery       {} levels, {} tiles of {} texels, finest texels {:.3} m x {:.3} m \
             ({} x {})",
            imagery.layout.levels,
            imagery.tile_count,
            imagery.layout.tile_texels,
            north_m,
            east_m,
            imagery.layout.rows,
            imagery.layout.cols
        );
        for s in &imagery.sources {
            println!("image         {s}");
        }
    }
    match &m.culture {
        Some(culture) if culture.total() > 0 => {
            println!("culture       {}", culture_summary(culture));
            let kinds: Vec<String> = culture
                .counts
                .iter()
                .filter(|(_, n)| **n > 0)
                .map(|(name, n)| format!("{name} {n}"))
                .collect();
            println!("  {}", kinds.join(", "));
        }
        _ => println!("culture       none"),
    }
    if let Some(report) = levels {
        let (width_px, height_px) = LOD_REFERENCE_SIZE;
        if report.tiles_without_post_errors > 0 {
            println!(
                "mesh errors   {} of {} tiles lack their posts' hierarchy errors (tile format 1): \
                 drawn as regular grids; rebuild the database for adaptive meshes",
                report.tiles_without_post_errors, m.tile_count
            );
        } else {
            println!(
                "mesh errors   every tile holds its posts' hierarchy errors (adaptive meshes)"
            );
        }
        let levels = report.levels;
        println!(
            "lod errors    per level: nodes, error median / p90 / max; a median node refines \
             within (at {LOD_REFERENCE_PX} px, {width_px} x {height_px} across \
             {LOD_REFERENCE_FOV_DEG} degrees)"
        );
        for l in &levels {
            println!(
                "  level {:<2} {:6} nodes {:8.2} / {:8.2} / {:8.2} m  {:8.1} km",
                l.level,
                l.nodes,
                l.median_m,
                l.p90_m,
                l.max_m,
                reference_range_m(l.median_m) / 1000.0
            );
        }
    }
    Ok(())
}
