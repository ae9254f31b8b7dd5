//! `cig bench dynterrain`: the dynamic terrain's costs (issue 22's targets), each against a
//! baseline of the same run.
//!
//! 1. Applying a crater (`crater_apply_ms`, the median of 300 155 mm craters applied one by
//!    one in a 1 km square at the database's centre: the shape laid out, its cells refined,
//!    the fine posts summed, the tiles' bounds and the level of detail's block pyramid
//!    updated, the snapshot published to the queries, and the drawn patches of the nodes its
//!    cells lie in remade as the renderer remakes them, reusing the cells it did not change;
//!    `crater_layer_ms` and `crater_patch_ms` are the two parts).
//! 2. Height above terrain and line of sight inside that square once it holds 1000 edits
//!    (700 craters of 1 to 450 kg, 300 ruts), against the same queries on the unedited
//!    terrain (`hat_ratio`, `los_ratio`: edited rate over plain rate; target at least 0.5).
//!    HAT: 200 000 points; LOS: 4000 sightlines 200-900 m long, 2 m above the ground at both
//!    ends, in the square.
//!
//! 3. The picture under fire: `cig bench render`'s streaming pass (300 m/s, 120 m above the
//!    terrain, 60 Hz, from a fresh cache) drawn twice, plain and with 100 craters a second
//!    (7 kg, 200 to 1500 m ahead of the eye and up to 300 m either side, applied in one change
//!    per frame inside the timed frame), `stall` being each pass's longest frame over its
//!    median after 10 frames of warm-up (`stall_plain`, `stall_with_craters`; target: no
//!    frame over twice the median), and the ratio of the passes' medians.
//!
//! 4. What ruts cost to keep: 20 tracked vehicles driving winding 600 m paths in the square
//!    leave their ruts as the IG's rut tracker lays them (8 m pieces, two lines 2.6 m apart,
//!    0.6 m wide, 8 cm deep): the edit layer's bytes and the drawn patches' bytes (every
//!    finest node they cross, made fresh) per metre of rut line, and the median time to
//!    apply one (`rut_apply_ms`, the layer's part).
//!
//! Limits: one run of each pass; the pass is short (`--frames`, 180 by default: 3 s and 300
//! craters), at `--size` (640 x 360 by default) so a software rasteriser finishes it.

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
    /// Frames of the pass under fire (60 Hz).
    pub frames: usize,
    /// Frame size of the pass under fire, pixels.
    pub size: (u32, u32),
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

    // 1. Craters applied one by one, and the patches of the nodes they fall in remade.
    let node_layout = cig_scene::lod::NodeLayout::new(layout);
    let geoid = cig_terrain::database::GeoidLookup::new(&database.manifest().geoid);
    let mut node_patches: std::collections::HashMap<
        cig_scene::lod::NodeKey,
        cig_scene::edit_patch::CellPatches,
    > = std::collections::HashMap::new();
    let (mut apply_ms, mut layer_ms, mut patch_ms) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..300u32 {
        let centre = point(500.0, &mut places);
        let Some(edit) = crater(k, centre, 7.0, &mut query) else {
            continue;
        };
        let reach_deg = match &edit.shape {
            EditShape::Crater { lip_radius_m, .. } => (lip_radius_m / mn, lip_radius_m / me),
            _ => (0.0, 0.0),
        };
        let started = Instant::now();
        let applied = cache.update_edits(|layer| layer.apply(edit));
        let layer_done = started.elapsed().as_secs_f64() * 1e3;
        applied.map_err(|e| step_error("a crater", e))?;
        // The finest nodes the crater's footprint reaches, remade (their tiles are resident in
        // the renderer; loaded here before the clock starts).
        let edits = cache.edits();
        let g = layout.grid;
        let span = u64::from(node_layout.node_cells);
        let mut nodes = Vec::new();
        for (lat, lon) in [
            (centre.lat_deg - reach_deg.0, centre.lon_deg - reach_deg.1),
            (centre.lat_deg + reach_deg.0, centre.lon_deg + reach_deg.1),
            (centre.lat_deg - reach_deg.0, centre.lon_deg + reach_deg.1),
            (centre.lat_deg + reach_deg.0, centre.lon_deg - reach_deg.1),
        ] {
            let row = ((lat - g.south_lat_deg) / g.dlat_deg).max(0.0) as u64 / span;
            let col = ((lon - g.west_lon_deg) / g.dlon_deg).max(0.0) as u64 / span;
            let key = cig_scene::lod::NodeKey {
                level: 0,
                row: row as u32,
                col: col as u32,
            };
            if !nodes.contains(&key) {
                nodes.push(key);
            }
        }
        let mut tiles = Vec::with_capacity(nodes.len());
        for key in nodes {
            let tile_key = node_layout.tile_of(key, 0);
            let tile = database
                .load_tile(tile_key)
                .map_err(|e| step_error("a tile under a crater", e))?;
            tiles.push((key, tile_key, tile));
        }
        let patch_started = Instant::now();
        for (key, tile_key, tile) in &tiles {
            let (key, tile_key) = (*key, *tile_key);
            let patch = cig_scene::edit_patch::PatchedNode {
                layout: &node_layout,
                geoid: &geoid,
                key,
                tile: (tile_key, tile),
                centre_ecef: Geodetic::new(centre.lat_deg, centre.lon_deg, 0.0).to_ecef(),
                edits: &edits,
                time_origin_utc_s: 1.9e9,
            }
            .build(node_patches.entry(key).or_default());
            std::hint::black_box(patch);
        }
        let patch_done = patch_started.elapsed().as_secs_f64() * 1e3;
        layer_ms.push(layer_done);
        patch_ms.push(patch_done);
        apply_ms.push(layer_done + patch_done);
    }
    drop(node_patches);
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
    drop(query);
    drop(cache);

    // 4. What ruts cost to keep.
    let ruts = rut_memory(&database, &node_layout, &geoid)?;

    // 3. The picture under fire.
    let fire = pass_under_fire(&database, options)?;
    let json = serde_json::json!({
        "machine": machine(),
        "date_utc": date_utc(),
        "commit": options.commit,
        "database": options.db.display().to_string(),
        "crater_apply_ms": median(&apply_ms),
        "crater_apply_max_ms": apply_ms.iter().copied().fold(0.0, f64::max),
        "crater_layer_ms": median(&layer_ms),
        "crater_patch_ms": median(&patch_ms),
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
        "pass": fire.json,
        "ruts": ruts.json,
        "targets": {
            "crater_apply_ms": 1.0,
            "hat_ratio": 0.5,
            "los_ratio": 0.5,
            "stall_with_craters": 2.0,
        },
    });
    let summary = format!(
        "a crater applied in {:.3} ms (median of {}; target <= 1: layer {:.3} ms, patches {:.3} ms), at most {:.3} ms\n\
         HAT with 1000 edits: {:.0}/s against {:.0}/s plain: ratio {:.3} (target >= 0.5)\n\
         LOS with 1000 edits: {:.0}/s against {:.0}/s plain: ratio {:.3} (target >= 0.5); blocked {} then {} of {}",
        median(&apply_ms),
        apply_ms.len(),
        median(&layer_ms),
        median(&patch_ms),
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
    ) + &ruts.summary
        + &fire.summary;
    Ok(Report { json, summary })
}

/// Part 4: the ruts' memory.
fn rut_memory(
    database: &Arc<cig_terrain::TerrainDatabase>,
    node_layout: &cig_scene::lod::NodeLayout,
    geoid: &cig_terrain::database::GeoidLookup,
) -> Result<PartReport, BenchError> {
    const VEHICLES: u32 = 20;
    const PIECES: u32 = 75;
    const PIECE_M: f64 = 8.0;
    const GAUGE_M: f64 = 2.6;
    let layout = *database.layout();
    let (lat0, lon0) = layout.grid.centre_deg();
    let (mn, me) = cig_geo::metres_per_degree(lat0);
    let mut places = Places(2222);
    let mut layer = EditLayer::new(layout.grid, layout.tile_cells);
    let empty_bytes = layer.memory_bytes();
    let author = EditAuthor {
        site: 9,
        application: 11,
    };
    let mut apply_ms = Vec::new();
    let mut sequence = 0u32;
    for _ in 0..VEHICLES {
        let (mut x, mut y) = (
            (places.next() * 2.0 - 1.0) * 500.0,
            (places.next() * 2.0 - 1.0) * 500.0,
        );
        let mut heading = places.next() * std::f64::consts::TAU;
        for _ in 0..PIECES {
            heading += (places.next() - 0.5) * 0.4;
            let (dx, dy) = (PIECE_M * heading.sin(), PIECE_M * heading.cos());
            // Across the travel, to the right.
            let (rx, ry) = (heading.cos(), -heading.sin());
            for side in [-0.5, 0.5] {
                let at = |x: f64, y: f64| GeoPoint {
                    lat_deg: lat0 + (y + side * GAUGE_M * ry) / mn,
                    lon_deg: lon0 + (x + side * GAUGE_M * rx) / me,
                };
                sequence += 1;
                let edit = TerrainEdit {
                    author,
                    sequence,
                    time_utc_s: 1.9e9,
                    shape: EditShape::Rut {
                        from: at(x, y),
                        to: at(x + dx, y + dy),
                        width_m: 0.6,
                        depth_m: 0.08,
                    },
                };
                let started = Instant::now();
                layer.apply(edit).map_err(|e| step_error("a rut", e))?;
                apply_ms.push(started.elapsed().as_secs_f64() * 1e3);
            }
            (x, y) = (x + dx, y + dy);
        }
    }
    let rut_m = f64::from(sequence) * PIECE_M;
    let layer_bytes = layer.memory_bytes() - empty_bytes;
    // Every finest node a rut crosses, its patches made fresh.
    let span = u64::from(node_layout.node_cells);
    let mut nodes: Vec<cig_scene::lod::NodeKey> = layer
        .cells()
        .map(|((r, c), _)| cig_scene::lod::NodeKey {
            level: 0,
            row: (u64::from(r) / span) as u32,
            col: (u64::from(c) / span) as u32,
        })
        .collect();
    nodes.sort_by_key(|k| (k.row, k.col));
    nodes.dedup();
    let (mut patch_bytes, mut patch_vertices) = (0usize, 0usize);
    for &key in &nodes {
        let tile_key = node_layout.tile_of(key, 0);
        let tile = database
            .load_tile(tile_key)
            .map_err(|e| step_error("a tile under a rut", e))?;
        let centre = layout.grid.centre_deg();
        let patches = cig_scene::edit_patch::PatchedNode {
            layout: node_layout,
            geoid,
            key,
            tile: (tile_key, &tile),
            centre_ecef: Geodetic::new(centre.0, centre.1, 0.0).to_ecef(),
            edits: &layer,
            time_origin_utc_s: 1.9e9,
        }
        .build(&mut cig_scene::edit_patch::CellPatches::default());
        for piece in patches.iter().flat_map(|p| &p.pieces) {
            patch_bytes += piece.bytes();
            patch_vertices += piece.vertices.len();
        }
    }
    let layer_per_m = layer_bytes as f64 / rut_m;
    let patch_per_m = patch_bytes as f64 / rut_m;
    Ok(PartReport {
        json: serde_json::json!({
            "ruts": sequence,
            "rut_line_m": rut_m,
            "refined_cells": layer.cells().count(),
            "nodes": nodes.len(),
            "rut_apply_ms": median(&apply_ms),
            "layer_bytes": layer_bytes,
            "layer_bytes_per_m": layer_per_m,
            "patch_bytes": patch_bytes,
            "patch_bytes_per_m": patch_per_m,
            "patch_vertices_per_m": patch_vertices as f64 / rut_m,
        }),
        summary: format!(
            "\n{sequence} ruts ({:.1} km of rut line): the edit layer {:.0} bytes a metre, the drawn patches {:.0} bytes a metre ({:.1} vertices); a rut applied in {:.3} ms",
            rut_m / 1000.0,
            layer_per_m,
            patch_per_m,
            patch_vertices as f64 / rut_m,
            median(&apply_ms),
        ),
    })
}

/// A part's result: its figures and its lines of the summary.
struct PartReport {
    json: serde_json::Value,
    summary: String,
}

/// Craters a second during the pass under fire.
const CRATERS_PER_S: f64 = 100.0;

/// Part 3: `cig bench render`'s streaming pass drawn plain and under 100 craters a second.
fn pass_under_fire(
    database: &Arc<cig_terrain::TerrainDatabase>,
    options: &DynTerrainOptions,
) -> Result<PartReport, BenchError> {
    crate::require((20..=100_000).contains(&options.frames), || {
        format!("--frames {} must be between 20 and 100000", options.frames)
    })?;
    let gpu = cig_render::Gpu::headless()?;
    let target = cig_render::OffscreenTarget::new(&gpu, options.size);
    let dt_s = 1.0 / 60.0;
    let leg = crate::render::pass_leg(database, 300.0, options.frames as f64 * dt_s);
    let time_s = cig_environment::UtcTime::parse_iso8601("2026-06-21T19:00:00Z")
        .map_err(|e| step_error("the pass's time", e))?
        .unix_seconds();
    let pass = |craters: bool| -> Result<Vec<f64>, BenchError> {
        let cache = Arc::new(TileCache::new(
            Arc::clone(database),
            options.paging.clone(),
        )?);
        let mut query = QuerySession::new(Arc::clone(&cache));
        let views = crate::flight::views_along(&mut query, &leg, dt_s, 60.0, options.size)?;
        let mut renderer =
            cig_render::Renderer::new(Arc::clone(&gpu), &cache, cig_render::FRAME_FORMAT);
        let mut places = Places(2200);
        let author = EditAuthor {
            site: 9,
            application: 10,
        };
        let mut made = 0u32;
        let mut frame_ms = Vec::with_capacity(views.len());
        for (k, view) in views.iter().enumerate() {
            let started = Instant::now();
            if craters {
                let due = ((k + 1) as f64 * dt_s * CRATERS_PER_S) as u32;
                let frame = cig_geo::EnuFrame::new(view.eye);
                let (sh, ch) = leg.heading_deg.to_radians().sin_cos();
                let mut new = Vec::new();
                while made < due {
                    made += 1;
                    let ahead_m = 200.0 + 1300.0 * places.next();
                    let side_m = (places.next() * 2.0 - 1.0) * 300.0;
                    let east = ahead_m * sh + side_m * ch;
                    let north = ahead_m * ch - side_m * sh;
                    let at = frame.enu_to_geodetic(glam::DVec3::new(east, north, 0.0));
                    let Ok(ground) = query.hot(at.lat_deg, at.lon_deg) else {
                        continue;
                    };
                    let Ok(Some(dims)) = cig_dynterrain::crater::dimensions(
                        ground.material,
                        cig_dynterrain::soil::SoilMoisture::Dry,
                        7.0,
                    ) else {
                        continue;
                    };
                    new.push(TerrainEdit {
                        author,
                        sequence: made,
                        time_utc_s: time_s,
                        shape: EditShape::Crater {
                            centre: GeoPoint {
                                lat_deg: at.lat_deg,
                                lon_deg: at.lon_deg,
                            },
                            radius_m: dims.radius_m,
                            depth_m: dims.depth_m,
                            lip_radius_m: dims.lip_radius_m,
                            lip_height_m: dims.lip_height_m,
                        },
                    });
                }
                if !new.is_empty() {
                    cache.update_edits(|layer| {
                        for edit in new {
                            // An edit the layer refuses (outside, too many) is left out.
                            let _refused = layer.apply(edit);
                        }
                    });
                }
            }
            let mut snapshot = cig_scene::FrameSnapshot::new(time_s, vec![*view]);
            snapshot.max_pixel_error = 1.0;
            cache.update(&[view.eye]);
            renderer.render(
                &cache,
                &snapshot,
                0,
                target.view(),
                cig_render::FrameOptions::default(),
            )?;
            frame_ms.push(started.elapsed().as_secs_f64() * 1e3);
        }
        Ok(frame_ms)
    };
    let plain = pass(false)?;
    let fired = pass(true)?;
    let stall = |times: &[f64]| {
        let settled = &times[10.min(times.len() / 2)..];
        let max = settled.iter().copied().fold(0.0, f64::max);
        (max / median(settled), median(settled))
    };
    let (stall_plain, median_plain) = stall(&plain);
    let (stall_fired, median_fired) = stall(&fired);
    let craters = (options.frames as f64 * dt_s * CRATERS_PER_S) as u32;
    Ok(PartReport {
        json: serde_json::json!({
            "adapter": gpu.describe(),
            "frames": options.frames,
            "size": [options.size.0, options.size.1],
            "craters": craters,
            "frame_ms_median_plain": median_plain,
            "frame_ms_median_with_craters": median_fired,
            "median_ratio": median_fired / median_plain,
            "stall_plain": stall_plain,
            "stall_with_craters": stall_fired,
        }),
        summary: format!(
            "\nthe pass under {craters} craters ({CRATERS_PER_S} a second): median frame {median_fired:.1} ms \
             against {median_plain:.1} ms plain (ratio {:.3}); stall {stall_fired:.2} against {stall_plain:.2} plain (target <= 2)",
            median_fired / median_plain
        ),
    })
}
