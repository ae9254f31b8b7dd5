//! The terrain queries and the culture: bases on HOT, line of sight stopped by buildings and
//! crowns but not fences, collision segments meeting fences, the highest surface with culture,
//! and culture paged with its tiles inside the memory budget.
mod common;

use cig_geo::Geodetic;
use cig_terrain::build::build_pyramid;
use cig_terrain::culture::bin_placements;
use cig_terrain::culture_hit::{contains, ItemFrame};
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::raster::Raster;
use cig_terrain::tile::tile_memory_bytes;
use cig_terrain::{
    CultureKind, CultureManifest, CulturePlacement, CultureTest, PagingConfig, QuerySession,
    TileKey,
};
use common::*;
use std::collections::HashMap;
use std::sync::Arc;

const GEOID_M: f32 = 12.0;

/// Builds `raster` with `placements` into a memory database (geoid [`GEOID_M`]); also returns
/// the number of objects stored for each finest tile.
fn culture_database(
    raster: &Raster,
    tile_cells: u32,
    placements: &[CulturePlacement],
) -> (Arc<TerrainDatabase>, HashMap<TileKey, usize>) {
    culture_database_with(raster, tile_cells, placements, |_| {})
}

/// [`culture_database`] with the culture manifest changed by `edit` before the database opens.
fn culture_database_with(
    raster: &Raster,
    tile_cells: u32,
    placements: &[CulturePlacement],
    edit: impl FnOnce(&mut CultureManifest),
) -> (Arc<TerrainDatabase>, HashMap<TileKey, usize>) {
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(raster, tile_cells, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = GEOID_M);
    let mut manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    let (tiles, mut culture) = bin_placements(&manifest.layout, placements).expect("placements");
    edit(&mut culture);
    let mut counts = HashMap::new();
    for tile in &tiles {
        store.insert_culture(tile.key, tile.encode());
        counts.insert(tile.key, tile.items.len());
    }
    manifest.culture = Some(culture);
    let db = TerrainDatabase::new(manifest, store as Arc<dyn cig_terrain::TileStore>).expect("db");
    (Arc::new(db), counts)
}

fn place(kind: CultureKind, (lat_deg, lon_deg): (f64, f64), size_m: [f32; 3]) -> CulturePlacement {
    CulturePlacement {
        kind,
        lat_deg,
        lon_deg,
        height_m: size_m[0],
        width_m: size_m[1],
        length_m: size_m[2],
        heading_deg: 0.0,
        variant: 0,
    }
}

/// The point `east_m`, `north_m` from `(lat, lon)`.
fn offset((lat, lon): (f64, f64), east_m: f64, north_m: f64) -> (f64, f64) {
    let (n, e) = cig_geo::metres_per_degree(lat);
    (lat + north_m / n, lon + east_m / e)
}

/// A geodetic point `above_m` over the terrain at `(lat, lon)`.
fn above(q: &mut QuerySession, (lat, lon): (f64, f64), above_m: f64) -> Geodetic {
    let ground = q.hot(lat, lon).expect("inside").height_ellipsoid_m();
    Geodetic::new(lat, lon, ground + above_m)
}

/// The ends of a line from `a` to `b`, `above_m` over the terrain at each end.
fn line(q: &mut QuerySession, a: (f64, f64), b: (f64, f64), above_m: f64) -> (Geodetic, Geodetic) {
    (above(q, a, above_m), above(q, b, above_m))
}

/// A sloping, rolling terrain: about 10 % north, 5 % east, with 8 m bumps.
fn slope(r: usize, c: usize) -> f32 {
    let (r, c) = (r as f32, c as f32);
    150.0 + 3.0 * r + 1.5 * c + 8.0 * (r * 0.37).sin() * (c * 0.29).cos()
}

#[test]
fn a_trees_base_is_hot_at_its_trunk_on_a_slope() {
    let g = grid(129, 129, 30.0);
    // Trees on a lattice that crosses tile edges (32-cell tiles) and cell diagonals.
    let placements: Vec<_> = (0..400)
        .map(|k| {
            let (fr, fc) = (
                2.0 + (k % 20) as f64 * 6.23 + 0.011 * k as f64,
                1.0 + (k / 20) as f64 * 6.31,
            );
            let mut p = place(
                if k % 2 == 0 {
                    CultureKind::ConiferTree
                } else {
                    CultureKind::BroadleafTree
                },
                (
                    g.south_lat_deg + fr * g.dlat_deg,
                    g.west_lon_deg + fc * g.dlon_deg,
                ),
                [18.0, 6.0, 6.0],
            );
            p.heading_deg = k as f32 * 17.0;
            p
        })
        .collect();
    let (db, counts) = culture_database(&raster(g, slope), 32, &placements);
    let cache = cache(&db, PagingConfig::default());
    let mut q = QuerySession::new(Arc::clone(&cache));
    let layout = *db.layout();
    let mut checked = 0;
    let mut worst_m: f64 = 0.0;
    for (&key, &count) in &counts {
        let tile = cache.load_now(key).expect("tile");
        let culture = tile
            .culture
            .as_ref()
            .expect("the tile's culture is loaded with it");
        assert_eq!(culture.items.len(), count);
        for item in &culture.items {
            let row = f64::from(key.row) * f64::from(layout.tile_cells) + f64::from(item.fi);
            let col = f64::from(key.col) * f64::from(layout.tile_cells) + f64::from(item.fj);
            let (lat, lon) = (
                g.south_lat_deg + row * g.dlat_deg,
                g.west_lon_deg + col * g.dlon_deg,
            );
            let hot = q.height_msl_m(lat, lon).expect("inside");
            let error_m = (f64::from(item.base_m) - hot).abs();
            worst_m = worst_m.max(error_m);
            assert!(
                error_m < 0.01,
                "{} at {key} ({}, {}): base {} m, HOT {hot} m",
                item.kind,
                item.fi,
                item.fj,
                item.base_m
            );
            // HOT answers the bare terrain, also with culture about.
            assert_eq!(q.hot(lat, lon).expect("inside").height_msl_m, hot);
            checked += 1;
        }
    }
    assert_eq!(checked, placements.len());
    // On this slope the base differs from a post's height: the check is not trivially met.
    assert!(worst_m < 0.01);
}

/// A flat plain at 100 m (with a 0.2 m ripple) and the placements around [`centre`].
fn plain_with(placements: impl Fn((f64, f64)) -> Vec<CulturePlacement>) -> QuerySession {
    let g = grid(129, 129, 30.0);
    let centre = centre();
    let r = raster(g, |r, c| 100.0 + 0.2 * ((r + c) % 2) as f32);
    let (db, _) = culture_database(&r, 32, &placements(centre));
    QuerySession::new(cache(&db, PagingConfig::default()))
}

/// The middle of finest tile (1, 1) of 32-cell tiles, 480 m from its edges.
fn centre() -> (f64, f64) {
    grid(129, 129, 30.0).post_lat_lon_deg(48, 48)
}

#[test]
fn a_building_blocks_a_line_of_sight_and_open_ground_beside_it_does_not() {
    // A house 20 m long, 10 m wide, 8 m to its ridge, its length 70 degrees east of north.
    let house = |c| {
        vec![CulturePlacement {
            heading_deg: 70.0,
            ..place(CultureKind::House, c, [8.0, 10.0, 20.0])
        }]
    };
    let mut q = plain_with(house);
    let c = centre();
    // West to east through the centre, 2 m above the ground.
    let from = above(&mut q, offset(c, -60.0, 0.0), 2.0);
    let to = above(&mut q, offset(c, 60.0, 0.0), 2.0);
    let r = q.los(from, to).expect("los");
    assert!(!r.visible, "{r:?}");
    let hit = r.hit.expect("hit");
    let culture = hit.culture.expect("the house stops it, not the terrain");
    assert_eq!(culture.kind, CultureKind::House);
    // Along the east-west line the box's half-extent is min(10 / sin 70, 5 / cos 70) m: its
    // west end wall.
    let half = (10.0 / 70f64.to_radians().sin()).min(5.0 / 70f64.to_radians().cos());
    assert!(
        (hit.range_m - (60.0 - half)).abs() < 0.05,
        "range {} m, expected {} m",
        hit.range_m,
        60.0 - half
    );
    // The wall it met faces west-south-west: the box's -x face turned by the heading.
    let [e, n, u] = culture.normal_enu;
    let (sin_h, cos_h) = 70f64.to_radians().sin_cos();
    assert!(
        (e + sin_h).abs() < 1e-4 && (n + cos_h).abs() < 1e-4 && u.abs() < 1e-9,
        "{:?}",
        culture.normal_enu
    );
    // The bare terrain does not stop it.
    let bare = q.los_with(from, to, CultureTest::Ignore).expect("los");
    assert!(bare.visible, "{bare:?}");
    // The same line shifted past the footprint (radius 11.2 m) by 3 m: open ground.
    for north_m in [-14.2, 14.2] {
        let from = above(&mut q, offset(c, -60.0, north_m), 2.0);
        let to = above(&mut q, offset(c, 60.0, north_m), 2.0);
        let r = q.los(from, to).expect("los");
        assert!(r.visible, "{north_m} m: {r:?}");
    }
    // Over the roof: clear; through the ridge height less 0.3 m: stopped.
    let (a, b) = line(&mut q, offset(c, -60.0, 0.0), offset(c, 60.0, 0.0), 8.3);
    let over = q.los(a, b).expect("los");
    assert!(over.visible, "{over:?}");
    let (a, b) = line(&mut q, offset(c, -60.0, 0.0), offset(c, 60.0, 0.0), 7.7);
    let under = q.los(a, b).expect("los");
    assert!(!under.visible, "{under:?}");
}

#[test]
fn a_conifers_crown_blocks_a_line_of_sight() {
    // 20 m tall, 6 m wide: the crown is an ellipsoid 2.52 m across its middle at 11.6 m.
    let mut q = plain_with(|c| vec![place(CultureKind::ConiferTree, c, [20.0, 6.0, 6.0])]);
    let c = centre();
    let from = above(&mut q, offset(c, 0.0, -80.0), 11.6);
    let to = above(&mut q, offset(c, 0.0, 80.0), 11.6);
    let r = q.los(from, to).expect("los");
    let hit = r.hit.expect("the crown stops it");
    assert_eq!(hit.culture.map(|h| h.kind), Some(CultureKind::ConiferTree));
    assert!((hit.range_m - (80.0 - 2.52)).abs() < 0.05, "{hit:?}");
    // Beside the crown (2.52 m) and above the tree: clear.
    for (east_m, up_m) in [(2.8, 11.6), (-2.8, 11.6), (0.0, 20.3)] {
        let (a, b) = line(
            &mut q,
            offset(c, east_m, -80.0),
            offset(c, east_m, 80.0),
            up_m,
        );
        let r = q.los(a, b).expect("los");
        assert!(r.visible, "{east_m} m east, {up_m} m up: {r:?}");
    }
    // The highest surface over the trunk is the crown's top; HOT stays the ground.
    let top = q.hot_with_culture(c.0, c.1).expect("inside");
    assert_eq!(top.culture.map(|h| h.kind), Some(CultureKind::ConiferTree));
    assert!(
        (top.height_msl_m - (top.terrain.height_msl_m + 20.0)).abs() < 0.01,
        "{top:?}"
    );
    assert!(
        (q.hot(c.0, c.1).expect("inside").height_msl_m - top.terrain.height_msl_m).abs() < 1e-9
    );
}

#[test]
fn a_fence_does_not_block_a_line_of_sight_but_a_collision_segment_meets_it() {
    // 30 m of fence running north-south, 1.4 m high.
    let mut q = plain_with(|c| vec![place(CultureKind::Fence, c, [1.4, 0.1, 30.0])]);
    let c = centre();
    let from = above(&mut q, offset(c, -40.0, 3.0), 1.0);
    let to = above(&mut q, offset(c, 40.0, 3.0), 1.0);
    let r = q.los(from, to).expect("los");
    assert!(r.visible, "{r:?}");
    let hit = q
        .collision(from, to)
        .expect("collision")
        .hit
        .expect("the segment meets the fence");
    assert_eq!(hit.culture.map(|h| h.kind), Some(CultureKind::Fence));
    assert!((hit.range_m - 39.95).abs() < 0.05, "{hit:?}");
    // Past its end (15 m north of the centre) it meets nothing.
    let (a, b) = line(&mut q, offset(c, -40.0, 16.0), offset(c, 40.0, 16.0), 1.0);
    let past = q.collision(a, b).expect("collision");
    assert!(past.visible, "{past:?}");
}

#[test]
fn the_highest_surface_is_the_roof_on_a_building_and_the_ground_beside_it() {
    let mut q = plain_with(|c| {
        vec![CulturePlacement {
            heading_deg: 90.0,
            ..place(CultureKind::LargeBuilding, c, [14.0, 16.0, 30.0])
        }]
    });
    let c = centre();
    // 14 m east of the centre is on the roof (30 m long east-west), 9 m north is off it.
    let on = offset(c, 14.0, 0.0);
    let roof = q.hot_with_culture(on.0, on.1).expect("inside");
    assert_eq!(
        roof.culture.map(|h| h.kind),
        Some(CultureKind::LargeBuilding)
    );
    let base = f64::from(roof.culture.expect("culture").item.base_m);
    assert!((roof.height_msl_m - (base + 14.0)).abs() < 1e-3, "{roof:?}");
    assert_eq!(roof.normal_enu, [0.0, 0.0, 1.0]);
    let (hat, _) = q
        .hat_with_culture(Geodetic::new(on.0, on.1, base + 20.0 + f64::from(GEOID_M)))
        .expect("inside");
    assert!((hat - 6.0).abs() < 1e-3, "{hat}");
    let off = offset(c, 0.0, 9.0);
    let ground = q.hot_with_culture(off.0, off.1).expect("inside");
    assert!(ground.culture.is_none(), "{ground:?}");
    assert_eq!(ground.height_msl_m, ground.terrain.height_msl_m);
}

#[test]
fn a_sightline_meets_the_volumes_as_a_sampled_march_does() {
    // Houses, trees, bushes, a wall and a pole around the centre; segments at random.
    let mut q = plain_with(|c| {
        let kinds = [
            (CultureKind::House, [8.0, 9.0, 14.0], 25.0),
            (CultureKind::BroadleafTree, [15.0, 9.0, 9.0], 0.0),
            (CultureKind::Bush, [2.5, 3.0, 3.0], 0.0),
            (CultureKind::Wall, [2.0, 0.5, 25.0], 70.0),
            (CultureKind::PowerPole, [10.0, 0.4, 0.4], 0.0),
            (CultureKind::ConiferTree, [18.0, 5.0, 5.0], 0.0),
        ];
        kinds
            .iter()
            .enumerate()
            .map(|(k, &(kind, size, heading_deg))| CulturePlacement {
                heading_deg,
                ..place(
                    kind,
                    offset(c, -40.0 + 17.0 * k as f64, 5.0 * (k % 2) as f64),
                    size,
                )
            })
            .collect()
    });
    let c = centre();
    let cache = Arc::clone(q.cache());
    let layout = *cache.database().layout();
    let g = layout.grid;
    // Every object, from the loaded tiles, with its frame.
    let mut objects = Vec::new();
    for row in 0..4 {
        for col in 0..4 {
            let key = TileKey { level: 0, row, col };
            let tile = cache.load_now(key).expect("tile");
            for item in tile.culture.iter().flat_map(|c| c.items.iter()) {
                objects.push((*item, ItemFrame::new(&layout, key, item)));
            }
        }
    }
    assert_eq!(objects.len(), 6);
    let mut rng = 0x5eed_u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut hits, mut agreed, mut grazes) = (0, 0, 0);
    for _ in 0..300 {
        let a = offset(c, -70.0 + 140.0 * next(), -30.0 + 60.0 * next());
        let b = offset(c, -70.0 + 140.0 * next(), -30.0 + 60.0 * next());
        let from = above(&mut q, a, 0.5 + 20.0 * next());
        let to = above(&mut q, b, 0.5 + 20.0 * next());
        let r = q.los(from, to).expect("los");
        // March 4000 samples along the chord (linear in lat, lon, height over 150 m: well
        // under a millimetre from it), each tested against every volume.
        let samples = 4000;
        let first_inside = (0..=samples).find(|&n| {
            let t = n as f64 / samples as f64;
            let lat = from.lat_deg + t * (to.lat_deg - from.lat_deg);
            let lon = from.lon_deg + t * (to.lon_deg - from.lon_deg);
            let msl = from.alt_m + t * (to.alt_m - from.alt_m) - f64::from(GEOID_M);
            let (row, col) = g.fractional_index(lat, lon);
            objects.iter().any(|(item, frame)| {
                let p = frame.local(col, row, msl);
                item.volume().into_iter().flatten().any(|v| contains(&v, p))
            })
        });
        let length_m = (to.to_ecef() - from.to_ecef()).length();
        let step_m = length_m / samples as f64;
        let culture_hit = r.hit.filter(|h| h.culture.is_some());
        match (culture_hit, first_inside) {
            (Some(h), Some(n)) => {
                hits += 1;
                let sampled_m = n as f64 * length_m / samples as f64;
                assert!(
                    h.range_m <= sampled_m + 0.01 && h.range_m >= sampled_m - step_m - 0.01,
                    "hit at {} m, march at {sampled_m} m",
                    h.range_m
                );
                agreed += 1;
            }
            (None, None) => agreed += 1,
            (Some(h), None) => {
                // Only a graze thinner than the march's step may slip between samples.
                grazes += 1;
                assert!(grazes <= 3, "query hits the march misses: {h:?}");
            }
            (None, Some(n)) => {
                // The terrain may come first; otherwise the query missed an object.
                let terrain = r.hit.map(|h| h.range_m);
                let sampled_m = n as f64 * length_m / samples as f64;
                assert!(
                    terrain.is_some_and(|t| t <= sampled_m + 0.01),
                    "the march meets an object at {sampled_m} m, the query: {r:?}"
                );
                agreed += 1;
            }
        }
    }
    assert!(hits > 30, "too few segments met an object ({hits})");
    assert!(agreed > 290, "{agreed}");
}

#[test]
fn an_object_over_a_tile_edge_is_seen_alike_by_a_cold_and_a_warm_cache() {
    // 32-cell tiles: column 64 is the edge between tile columns 1 and 2. A house 20 m long
    // east-west centred 4 m west of the edge overhangs 6 m into tile column 2.
    let g = grid(129, 129, 30.0);
    let edge = g.post_lat_lon_deg(48, 64);
    let r = raster(g, |_, _| 100.0);
    let house = CulturePlacement {
        heading_deg: 90.0,
        ..place(
            CultureKind::House,
            offset(edge, -4.0, 0.0),
            [8.0, 10.0, 20.0],
        )
    };
    let home = TileKey {
        level: 0,
        row: 1,
        col: 1,
    };
    // The manifest as written today (the house's half diagonal recorded) and as an older
    // build wrote it (no bounds: the largest a valid placement allows are used).
    let recorded = culture_database(&r, 32, &[house]).0;
    let (old, _) = culture_database_with(&r, 32, &[house], |c| {
        c.max_footprint_radius_m = 0.0;
        c.max_height_m = 0.0;
    });
    let bound_m = recorded
        .manifest()
        .culture
        .as_ref()
        .map(|c| c.footprint_bound_m());
    assert!(
        bound_m.is_some_and(|b| (b - 11.18).abs() < 0.01),
        "{bound_m:?}"
    );
    let mut answers = Vec::new();
    for db in [recorded, old] {
        // A north-south line 3 m east of the edge: over tile column 2 only.
        let line = |q: &mut QuerySession| {
            let from = above(q, offset(edge, 3.0, -60.0), 2.0);
            let to = above(q, offset(edge, 3.0, 60.0), 2.0);
            (from, to)
        };
        // Cold: nothing resident, a fresh session.
        let cold_cache = cache(&db, PagingConfig::default());
        let mut cold = QuerySession::new(Arc::clone(&cold_cache));
        let (from, to) = line(&mut cold);
        assert!(cold_cache.resident(home).is_none());
        let cold_hit = cold
            .los(from, to)
            .expect("los")
            .hit
            .expect("the overhang stops it");
        // The house's tile was loaded for its culture, like the tiles under the line.
        assert!(cold_cache.resident(home).is_some());
        let cold_collision = cold_cache_collision(&db, from, to);
        // Warm: the house's tile resident before the session's first query, and the same
        // session again.
        let warm_cache = cache(&db, PagingConfig::default());
        warm_cache.load_now(home).expect("tile");
        let mut warm = QuerySession::new(Arc::clone(&warm_cache));
        let warm_hit = warm
            .los(from, to)
            .expect("los")
            .hit
            .expect("the overhang stops it");
        let again = warm
            .los(from, to)
            .expect("los")
            .hit
            .expect("the overhang stops it");
        for (name, hit) in [
            ("cold", cold_hit),
            ("warm", warm_hit),
            ("again", again),
            ("collision", cold_collision),
        ] {
            assert_eq!(
                hit.culture.map(|h| h.kind),
                Some(CultureKind::House),
                "{name}"
            );
            assert!((hit.range_m - 55.0).abs() < 0.05, "{name}: {hit:?}");
            let apart_m = (hit.point.to_ecef() - cold_hit.point.to_ecef()).length();
            assert!(apart_m < 1e-3, "{name}: {apart_m} m from the cold answer");
        }
        // The highest surface over the overhang is its roof, cold or warm.
        let over = offset(edge, 3.0, 0.0);
        let cold_cache = cache(&db, PagingConfig::default());
        let roof = QuerySession::new(cold_cache)
            .hot_with_culture(over.0, over.1)
            .expect("inside");
        assert_eq!(roof.culture.map(|h| h.kind), Some(CultureKind::House));
        let warm_roof = warm.hot_with_culture(over.0, over.1).expect("inside");
        assert_eq!(roof.height_msl_m, warm_roof.height_msl_m);
        answers.push(cold_hit);
    }
    // The old manifest's wider bound finds the same house at the same point.
    let apart_m = (answers[0].point.to_ecef() - answers[1].point.to_ecef()).length();
    assert!(apart_m < 1e-3, "{apart_m} m");
}

/// A collision segment from a cold cache and session.
fn cold_cache_collision(
    db: &Arc<TerrainDatabase>,
    from: Geodetic,
    to: Geodetic,
) -> cig_terrain::LosHit {
    QuerySession::new(cache(db, PagingConfig::default()))
        .collision(from, to)
        .expect("collision")
        .hit
        .expect("the overhang stops it")
}

#[test]
fn culture_pages_with_its_tiles_inside_the_budget() {
    // 15 km square at 30 m posts, 32-cell tiles (256 finest tiles), a tree every 30-odd
    // metres on most tiles.
    let g = grid(513, 513, 30.0);
    let mut placements = Vec::new();
    let mut rng = 99u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..60_000 {
        let (fr, fc) = (next() * 512.0, next() * 512.0);
        // A clearing of a few tiles keeps some finest tiles without culture.
        if fr < 64.0 && fc > 448.0 {
            continue;
        }
        placements.push(place(
            CultureKind::BroadleafTree,
            (
                g.south_lat_deg + fr * g.dlat_deg,
                g.west_lon_deg + fc * g.dlon_deg,
            ),
            [12.0, 7.0, 7.0],
        ));
    }
    let (db, counts) = culture_database(
        &raster(g, |r, c| 50.0 + (r + c) as f32 * 0.1),
        32,
        &placements,
    );
    let probe = cache(&db, PagingConfig::default());
    let finest = TileKey {
        level: 0,
        row: 0,
        col: 0,
    };
    let finest_bytes = probe.bytes_of(finest);
    let coarse_bytes = probe.tile_bytes();
    assert!(
        finest_bytes > coarse_bytes,
        "a finest tile counts its culture"
    );
    drop(probe);
    let budget = finest_bytes * 40;
    let c = cache(
        &db,
        PagingConfig {
            budget_bytes: budget,
            active_area_m: 3_000.0,
            hysteresis_box_m: 600.0,
            recenter_step_m: 500.0,
            ..PagingConfig::default()
        },
    );
    let mut q = QuerySession::new(Arc::clone(&c));
    let layout = *db.layout();
    let posts = layout.posts_per_side();
    let depth = cig_terrain::tile::quadtree_depth_for(layout.tile_cells as usize);
    let (rows, cols) = layout.tiles_at(0);
    let (n_per_deg, e_per_deg) = cig_geo::metres_per_degree(g.south_lat_deg);
    let mut seen_with_culture = 0;
    let mut culture_hits = 0;
    for frame in 0..300 {
        // Diagonally across the database and back, 100 m a frame, with a line of sight
        // ahead along the ground each frame.
        let d_m = 1_000.0 + 100.0 * f64::from(frame % 150);
        let d_m = if frame < 150 { d_m } else { 16_000.0 - d_m };
        let (lat, lon) = (
            g.south_lat_deg + d_m * 0.7 / n_per_deg,
            g.west_lon_deg + d_m * 0.7 / e_per_deg,
        );
        let stats = c.update(&[Geodetic::new(lat, lon, 300.0)]);
        // Loads in flight hold their bytes too (at least a coarser tile's each).
        assert!(
            stats.resident_bytes + stats.in_flight as u64 * coarse_bytes <= budget,
            "frame {frame}: {stats:?}"
        );
        let eye = above(&mut q, (lat, lon), 5.0);
        let ahead = above(&mut q, offset((lat, lon), 400.0, 300.0), 5.0);
        if q.los(eye, ahead)
            .expect("los")
            .hit
            .is_some_and(|h| h.culture.is_some())
        {
            culture_hits += 1;
        }
        if frame % 10 == 9 {
            c.wait_idle();
            let stats = c.stats();
            assert!(stats.resident_bytes <= budget, "frame {frame}: {stats:?}");
            // Every resident finest tile holds its culture; what they take is in the budget.
            let mut bytes = 0u64;
            for row in 0..rows {
                for col in 0..cols {
                    let key = TileKey { level: 0, row, col };
                    let Some(tile) = c.resident(key) else {
                        continue;
                    };
                    let expected = counts.get(&key).copied().unwrap_or(0);
                    let held = tile.culture.as_ref().map_or(0, |c| c.items.len());
                    assert_eq!(held, expected, "{key}: culture resident with its tile");
                    seen_with_culture += usize::from(held > 0);
                    bytes += tile_memory_bytes(posts, depth) as u64
                        + tile.culture.as_ref().map_or(0, |c| c.memory_bytes());
                }
            }
            assert!(bytes <= stats.resident_bytes, "{bytes} > {stats:?}");
        }
    }
    let stats = c.stats();
    assert!(stats.evictions > 0, "the flight must page: {stats:?}");
    assert!(seen_with_culture > 20, "{seen_with_culture}");
    assert!(
        culture_hits > 10,
        "lines of sight through the wood: {culture_hits}"
    );
}

#[test]
fn a_damaged_culture_file_costs_its_culture_and_not_the_terrain() {
    let g = grid(129, 129, 30.0);
    let centre = centre();
    let r = raster(g, |r, c| 100.0 + 0.2 * ((r + c) % 2) as f32);
    let tree = place(CultureKind::ConiferTree, centre, [20.0, 6.0, 6.0]);
    let (db, counts) = culture_database(&r, 32, &[tree]);
    let (&key, _) = counts.iter().next().expect("the tree's tile");
    assert!(db.load_tile(key).expect("tile").culture.is_some());
    // The same database with that tile's culture file flipped in one byte.
    let store = Arc::new(MemoryTileStore::new());
    for level in 0..db.layout().levels {
        for k in db.layout().keys_at(level) {
            let tile = db.load_tile(k).expect("tile");
            store.insert(k, tile.encode());
        }
    }
    let (tiles, _) = bin_placements(db.layout(), &[tree]).expect("placements");
    let mut bytes = tiles[0].encode();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x10;
    store.insert_culture(key, bytes);
    let damaged = TerrainDatabase::new(
        db.manifest().clone(),
        store as Arc<dyn cig_terrain::TileStore>,
    )
    .expect("db");
    let tile = damaged
        .load_tile(key)
        .expect("the terrain tile still loads");
    assert!(tile.culture.is_none());
    assert_eq!(
        tile.elevation_m,
        db.load_tile(key).expect("tile").elevation_m
    );
}
