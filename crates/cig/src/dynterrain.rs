//! `cig db crater`, `cig db edits`, `cig query soil`, and a database opened with its edits.

use crate::cli::{CraterArgs, EditsArgs, SoilArgs};
use crate::config::Config;
use anyhow::Context;
use cig_dynterrain::crater::CraterDimensions;
use cig_dynterrain::soil::{RunningGear, SoilMoisture, VehicleLoad};
use cig_ig::terrain_edits::{crater_at, CraterSize};
use cig_terrain::edits::{EditAuthor, EditError, EditId, EditLayer, TerrainEdit};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use cig_terrain_io::edits::{
    layer_of, read_database_edits, read_edits, write_edits, EditAppender, EDITS_FILE,
};
use cig_terrain_io::store::open_database;
use std::collections::HashSet;
use std::path::Path;
use std::sync::Arc;

/// The operator at the command line, as an edit's author.
pub const OPERATOR: EditAuthor = EditAuthor {
    site: 0,
    application: 0,
};

/// Opens a database with a paging cache that holds the database's edits.
pub fn open_cache(db: &Path, paging: &PagingConfig) -> anyhow::Result<Arc<TileCache>> {
    let database = Arc::new(open_database(db)?);
    let cache = Arc::new(TileCache::new(database, paging.clone())?);
    let layer = database_layer(db, &cache)?;
    if !layer.is_empty() {
        tracing::info!(edits = layer.len(), "terrain edits loaded");
        cache.set_edits(Arc::new(layer));
    }
    Ok(cache)
}

/// The edits kept in a database directory, as a layer of its lattice.
fn database_layer(db: &Path, cache: &TileCache) -> anyhow::Result<EditLayer> {
    let layout = *cache.database().layout();
    let edits = read_database_edits(db, &layout.grid)?;
    layer_of(&layout.grid, layout.tile_cells, edits)
        .with_context(|| format!("bad terrain edits in {}", db.join(EDITS_FILE).display()))
}

/// `cig serve --edits FILE`: the edits made while serving, appended to FILE as they come.
pub struct EditJournal {
    appender: EditAppender,
    written: HashSet<EditId>,
    revision: u64,
}

impl EditJournal {
    /// Opens (or creates) the journal and adds its edits to the cache's.
    pub fn open(path: &Path, cache: &TileCache) -> anyhow::Result<EditJournal> {
        let grid = cache.database().layout().grid;
        let (appender, existing) = EditAppender::open(path, &grid)?;
        let count = existing.len();
        cache
            .update_edits(|layer| -> Result<(), EditError> {
                for edit in existing {
                    layer.apply(edit)?;
                }
                Ok(())
            })
            .with_context(|| format!("edit refused: {}", path.display()))?;
        let edits = cache.edits();
        tracing::info!(
            from_file = count,
            in_all = edits.len(),
            "terrain edits journal: {}",
            path.display()
        );
        Ok(EditJournal {
            appender,
            written: edits.edits().map(TerrainEdit::id).collect(),
            revision: cache.edits_revision(),
        })
    }

    /// Appends the edits made and the heals done since the last call; how many lines.
    pub fn record(&mut self, cache: &TileCache) -> anyhow::Result<usize> {
        let revision = cache.edits_revision();
        if revision == self.revision {
            return Ok(0);
        }
        self.revision = revision;
        let edits = cache.edits();
        let mut lines = 0;
        for edit in edits.edits() {
            if self.written.insert(edit.id()) {
                self.appender.append(edit)?;
                lines += 1;
            }
        }
        if self.written.len() > edits.len() {
            let mut healed: Vec<EditId> = self
                .written
                .iter()
                .filter(|id| !edits.contains(**id))
                .copied()
                .collect();
            healed.sort();
            for id in healed {
                self.appender.append_heal(id)?;
                self.written.remove(&id);
                lines += 1;
            }
        }
        Ok(lines)
    }
}

fn moisture(wet: bool) -> SoilMoisture {
    if wet {
        SoilMoisture::Wet
    } else {
        SoilMoisture::Dry
    }
}

/// Parses "LAT,LON" in degrees.
fn lat_lon(text: &str) -> anyhow::Result<(f64, f64)> {
    let v = crate::render::parse_numbers(text, "--at", &[2])?;
    let (lat, lon) = (v[0], v[1]);
    anyhow::ensure!(
        lat.abs() <= 90.0,
        "--at \"{text}\": latitude {lat} is not on the earth"
    );
    Ok((lat, lon))
}

/// `cig db crater`: adds a crater to the database's edits.
pub fn crater(args: &CraterArgs, config: &Config) -> anyhow::Result<()> {
    let (lat, lon) = lat_lon(&args.at)?;
    let size = match (args.charge_kg, args.radius_m, args.depth_m) {
        (Some(charge_kg), None, None) => CraterSize::Charge { charge_kg },
        (None, Some(radius_m), Some(depth_m)) => CraterSize::Explicit { radius_m, depth_m },
        _ => anyhow::bail!("give either --charge-kg, or both --radius-m and --depth-m"),
    };
    let cache = open_cache(&args.db, &config.paging)?;
    let mut q = QuerySession::new(Arc::clone(&cache));
    let crater = crater_at(&mut q, lat, lon, size, moisture(args.wet))
        .with_context(|| format!("no crater at --at {} in {}", args.at, args.db.display()))?;
    let mut layer = (*cache.edits()).clone();
    let edit = TerrainEdit {
        author: OPERATOR,
        sequence: layer
            .last_sequence(OPERATOR)
            .map_or(1, |s| s.saturating_add(1)),
        time_utc_s: crate::serve::unix_now_s(),
        shape: crater.shape(),
    };
    let CraterDimensions {
        radius_m,
        depth_m,
        lip_radius_m,
        lip_height_m,
    } = crater.dimensions;
    layer
        .apply(edit)
        .with_context(|| format!("crater refused: {}", args.db.display()))?;
    let grid = cache.database().layout().grid;
    let path = args.db.join(EDITS_FILE);
    write_edits(&path, &grid, layer.edits())?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "lat": lat, "lon": lon, "material": crater.material.name(),
                "radius_m": radius_m, "depth_m": depth_m,
                "lip_radius_m": lip_radius_m, "lip_height_m": lip_height_m,
                "edits": layer.len(),
            })
        );
    } else {
        println!(
            "crater {:.2} m across, {:.2} m deep (lip {:.2} m high to {:.2} m) at {lat:.6}, {lon:.6} in {}; {} edits in {}",
            2.0 * radius_m,
            depth_m,
            lip_height_m,
            lip_radius_m,
            crater.material,
            layer.len(),
            path.display()
        );
    }
    Ok(())
}

/// `cig db edits`: lists, exports, imports or clears a database's edits.
pub fn edits(args: &EditsArgs, config: &Config) -> anyhow::Result<()> {
    let cache = open_cache(&args.db, &config.paging)?;
    let layout = *cache.database().layout();
    let path = args.db.join(EDITS_FILE);
    let mut layer = (*cache.edits()).clone();
    if args.clear {
        if path.exists() {
            std::fs::remove_file(&path)
                .with_context(|| format!("cannot remove {}", path.display()))?;
        }
        println!("{} edits removed from {}", layer.len(), args.db.display());
        return Ok(());
    }
    if let Some(file) = &args.import {
        let incoming = read_edits(file, &layout.grid)?;
        let mut added = 0;
        for edit in incoming {
            if layer
                .apply(edit)
                .with_context(|| format!("edit refused: {}", file.display()))?
                == cig_terrain::edits::Applied::Added
            {
                added += 1;
            }
        }
        write_edits(&path, &layout.grid, layer.edits())?;
        println!(
            "{added} edits imported ({} in all) into {}",
            layer.len(),
            path.display()
        );
    }
    if let Some(file) = &args.export {
        write_edits(file, &layout.grid, layer.edits())?;
        println!("{} edits exported to {}", layer.len(), file.display());
    }
    if args.import.is_none() && args.export.is_none() {
        if args.json {
            let list: Vec<serde_json::Value> = layer
                .edits()
                .filter_map(|e| serde_json::to_value(e).ok())
                .collect();
            println!("{}", serde_json::json!({ "edits": list }));
        } else {
            println!("{} edits in {}", layer.len(), args.db.display());
            for e in layer.edits() {
                let kind = serde_json::to_value(&e.shape)
                    .ok()
                    .and_then(|v| v["kind"].as_str().map(str::to_owned))
                    .unwrap_or_default();
                println!(
                    "  {}:{} #{} {kind}",
                    e.author.site, e.author.application, e.sequence
                );
            }
        }
    }
    Ok(())
}

/// `cig query soil`: sinkage, compaction resistance and go/no-go for a vehicle at a point.
pub fn soil(args: &SoilArgs, config: &Config) -> anyhow::Result<()> {
    let gear = match args.gear.as_str() {
        "tracked" => RunningGear::Tracked,
        "wheeled" => RunningGear::Wheeled,
        "foot" => RunningGear::Foot,
        other => anyhow::bail!("--gear {other}: expected tracked, wheeled or foot"),
    };
    let load = VehicleLoad::new(args.vehicle_mass_kg, args.contact_area_m2, gear)?;
    let cache = open_cache(&args.db, &config.paging)?;
    let mut q = QuerySession::new(cache);
    let ground = q
        .hot(args.lat, args.lon)
        .with_context(|| format!("no terrain answer from {}", args.db.display()))?;
    let t = cig_dynterrain::soil::trafficability(ground.material, moisture(args.wet), &load);
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "material": ground.material.name(),
                "sinkage_m": t.sinkage_m,
                "resistance_n": t.resistance_n,
                "max_thrust_n": t.max_thrust_n,
                "trafficable": t.trafficable,
                "reason": t.reason,
                "ground_pressure_pa": load.ground_pressure_pa(),
            })
        );
    } else {
        println!(
            "{}: sinkage {:.3} m, compaction resistance {:.0} N, thrust up to {:.0} N: {}",
            ground.material,
            t.sinkage_m,
            t.resistance_n,
            t.max_thrust_n,
            if t.trafficable {
                "go".to_owned()
            } else {
                format!("no go ({})", t.reason)
            }
        );
    }
    Ok(())
}
