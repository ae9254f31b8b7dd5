//! `cig bench dynterrain`: the dynamic terrain's costs (issue 22's targets), each against a
//! baseline of the same run.
//!
//! 1. Applying a crater (`crater_apply_ms`, the median of 300 155 mm craters applied one by
//!    one in a 1 km square at the database's centre: the shape laid out, its cells refined,
//!    the fine posts summed, the tiles' bounds updated, the snapshot published to the queries).
//! 2. Height above terrain and line of sight inside that square once it holds 1000 edits
//!    (700 craters of 1 to 450 kg, 300 ruts), against the same queries on the unedited
//!    terrain (`hat_ratio`, `los_ratio`: edited rate over plain rate; target at least 0.5).
//!    HAT: 200 000 points; LOS: 4000 sightlines 200-900 m long, 2 m above the ground at both
//!    ends, in the square.
//!
//! Limits: the renderer's rebuild of the patches over a new crater and the picture's stall
//! under 100 craters a second during `cig bench render`'s pass are not measured yet.

use crate::report::{date_utc, machine, median};
use crate::{BenchError, Report};
use cig_geo::Geodetic;
use cig_terrain::edits::{EditAuthor, EditLayer, EditShape, GeoPoint, TerrainEdit};
use cig_terrain::{PagingConfig, QuerySession, TileCache};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// What `cig bench dynterrain` measures.
#[derive(Clone, Debug)]
pub struct DynTerrainOptions {
    pub db: PathBuf,
    pub paging: PagingConfig,
    pub commit: String,
}

fn step_error(what: &str, e: impl std::fmt::Display) -> BenchError {
    BenchError::Step {
        what: what.into(),
        reason: e.to_string(),
    }
}

/// A small deterministic generator for the places: SplitMix64 over a counter.
struct Places(u64);

impl Places {
    fn next(&mut self) -> f64 {
        self.0 += 1;
        (cig_dis::detonation::splitmix64(self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
}

pub fn run(options: &DynTerrainOptions) -> Result<Report, BenchError> {
    let database = Arc::new(cig_terrain_io::store::open_database(&options.db)?);
    let layout = *database.layout();
    let cache = Arc::new(
        TileCache::new(Arc::clone(&database), options.paging.clone())
            .map_err(|e| step_error("the paging cache", e))?,
    );
    let mut query = QuerySession::new(Arc::clone(&cache));
    let (lat0, lon0) = layout.grid.centre_deg();
    let (mn, me) = cig_geo::metres_per_degree(lat0);
    let mut places = Places(22);
    let point = |half_m: f64, places: &mut Places| GeoPoint {
        lat_deg: lat0 + (places.next() * 2.0 - 1.0) * half_m / mn,
        lon_deg: lon0 + (places.next() * 2.0 - 1.0) * half_m / me,
    };
    let author = EditAuthor {
        site: 9,
        application: 9,
    };
    let crater = |sequence: u32, centre: GeoPoint, charge_kg: f64, query: &mut QuerySession| {
        let material = query
            .hot(centre.lat_deg, centre.lon_deg)
            .map_or(cig_terrain::Material::Grass, |s| s.material);
        let dims = cig_dynterrain::crater::dimensions(
            material,
            cig_dynterrain::soil::SoilMoisture::Dry,
            charge_kg,
        )
        .ok()
        .flatten()?;
        Some(TerrainEdit {
            author,
            sequence,
            time_utc_s: 1.9e9,
            shape: EditShape::Crater {
                centre,
                radius_m: dims.radius_m,
                depth_m: dims.depth_m,
                lip_radius_m: dims.lip_radius_m,
                lip_height_m: dims.lip_height_m,
            },
        })
    };

    // 1. Craters applied one by one.
    let mut apply_ms = Vec::with_capacity(300);
    for k in 0..300u32 {
        let centre = point(500.0, &mut places);
        let Some(edit) = crater(k, centre, 7.0, &mut query) else {
            continue;
        };
        let started = Instant::now();
        let applied = cache.update_edits(|layer| layer.apply(edit));
        apply_ms.push(started.elapsed().as_secs_f64() * 1e3);
        applied.map_err(|e| step_error("a crater", e))?;
    }
    cache.set_edits(Arc::new(EditLayer::new(layout.grid, layout.tile_cells)));

    // 2. The queries, plain and then with 1000 edits.
    let hat_points: Vec<Geodetic> = (0..200_000)
        .map(|_| {
            let p = point(500.0, &mut places);
            Geodetic::new(p.lat_deg, p.lon_deg, 2000.0)
        })
        .collect();
    let mut sightlines = Vec::with_capacity(4000);
    while sightlines.len() < 4000 {
        let a = point(500.0, &mut places);
        let b = point(500.0, &mut places);
        let d = ((a.lat_deg - b.lat_deg) * mn).hypot((a.lon_deg - b.lon_deg) * me);
        if !(200.0..=900.0).contains(&d) {
            continue;
        }
        let (Ok(ha), Ok(hb)) = (
            query.hot(a.lat_deg, a.lon_deg),
            query.hot(b.lat_deg, b.lon_deg),
        ) else {
            continue;
        };
        sightlines.push((
            Geodetic::new(a.lat_deg, a.lon_deg, ha.height_ellipsoid_m() + 2.0),
            Geodetic::new(b.lat_deg, b.lon_deg, hb.height_ellipsoid_m() + 2.0),
        ));
    }
    let mut edits = Vec::with_capacity(1000);
    let mut sequence = 1000u32;
    while edits.len() < 1000 {
        sequence += 1;
        let centre = point(500.0, &mut places);
        if edits.len() < 700 {
            let charge_kg = [1.0, 7.0, 7.0, 100.0, 450.0][sequence as usize % 5];
            if let Some(e) = crater(sequence, centre, charge_kg, &mut query) {
                edits.push(e);
            }
        } else {
            let heading = places.next() * std::f64::consts::TAU;
            let to = GeoPoint {
                lat_deg: centre.lat_deg + 8.0 * heading.cos() / mn,
                lon_deg: centre.lon_deg + 8.0 * heading.sin() / me,
            };
            edits.push(TerrainEdit {
                author,
                sequence,
                time_utc_s: 1.9e9,
                shape: EditShape::Rut {
                    from: centre,
                    to,
                    width_m: 0.64,
                    depth_m: 0.08,
                },
            });
        }
    }
    let rates = |query: &mut QuerySession| -> (f64, f64, f64, usize) {
        let mut out = Vec::with_capacity(hat_points.len());
        let mut hat_s = Vec::new();
        let mut sum = 0.0;
        for _ in 0..5 {
            let started = Instant::now();
            query.hat_batch_m(&hat_points, &mut out);
            hat_s.push(started.elapsed().as_secs_f64());
            sum = out.iter().filter_map(|r| r.as_ref().ok()).sum::<f64>();
        }
        let mut los_s = Vec::new();
        let mut blocked = 0;
        for _ in 0..3 {
            blocked = 0;
            let started = Instant::now();
            for (a, b) in &sightlines {
                if query.los(*a, *b).is_ok_and(|r| !r.visible) {
                    blocked += 1;
                }
            }
            los_s.push(started.elapsed().as_secs_f64());
        }
        (
            hat_points.len() as f64 / median(&hat_s),
            sightlines.len() as f64 / median(&los_s),
            sum,
            blocked,
        )
    };
    let (hat_plain, los_plain, _, blocked_plain) = rates(&mut query);
    let mut layer = EditLayer::new(layout.grid, layout.tile_cells);
    for e in edits {
        layer.apply(e).map_err(|e| step_error("an edit", e))?;
    }
    let refined = layer.cells().count();
    cache.set_edits(Arc::new(layer));
    let (hat_edited, los_edited, hat_checksum, blocked_edited) = rates(&mut query);
    let json = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "database": options.db.display().to_string(),
        "crater_apply_ms": median(&apply_ms),
        "crater_apply_max_ms": apply_ms.iter().copied().fold(0.0, f64::max),
        "craters_applied": apply_ms.len(),
        "edits": 1000,
        "refined_cells": refined,
        "hat_per_s_plain": hat_plain,
        "hat_per_s_edited": hat_edited,
        "hat_ratio": hat_edited / hat_plain,
        "hat_checksum_m": hat_checksum,
        "los_per_s_plain": los_plain,
        "los_per_s_edited": los_edited,
        "los_ratio": los_edited / los_plain,
        "los_blocked_plain": blocked_plain,
        "los_blocked_edited": blocked_edited,
        "targets": {
            "crater_apply_ms": 1.0,
            "hat_ratio": 0.5,
            "los_ratio": 0.5,
        },
    });
    let summary = format!(
        "a crater applied in {:.3} ms (median of {}; target <= 1), at most {:.3} ms\n\
         HAT with 1000 edits: {:.0}/s against {:.0}/s plain: ratio {:.3} (target >= 0.5)\n\
         LOS with 1000 edits: {:.0}/s against {:.0}/s plain: ratio {:.3} (target >= 0.5); blocked {} then {} of {}",
        median(&apply_ms),
        apply_ms.len(),
        apply_ms.iter().copied().fold(0.0, f64::max),
        hat_edited,
        hat_plain,
        hat_edited / hat_plain,
        los_edited,
        los_plain,
        los_edited / los_plain,
        blocked_plain,
        blocked_edited,
        sightlines.len(),
    );
    Ok(Report { json, summary })
}
