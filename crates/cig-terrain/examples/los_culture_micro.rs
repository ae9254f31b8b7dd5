//! Micro-benchmark of line of sight through dense culture on an in-memory database: 30 m posts,
//! 128-cell tiles, a wood of about 40 000 trees a tile (one every 19 m) over four tiles with
//! houses among them. Sightlines at random through the wood at eye height (most stop at a tree
//! within a few tens of metres), over the canopy, grazing the crowns, and along a tile edge.
//! `cargo run --release -p cig-terrain --example los_culture_micro`
use cig_geo::Geodetic;
use cig_terrain::build::build_pyramid;
use cig_terrain::culture::bin_placements;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{
    CultureKind, CulturePlacement, Material, PagingConfig, QuerySession, TileCache, TileStore,
};
use std::sync::Arc;
use std::time::Instant;

const TILE: usize = 128;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n = 6 * TILE + 1;
    let (m_north, m_east) = cig_geo::metres_per_degree(36.0);
    let grid = GeoGrid {
        south_lat_deg: 36.0,
        west_lon_deg: -121.0,
        dlat_deg: 30.0 / m_north,
        dlon_deg: 30.0 / m_east,
        rows: n,
        cols: n,
    };
    let height = |r: f64, c: f64| 300.0 + 20.0 * (r * 0.021).sin() * (c * 0.017).cos() + 0.05 * r;
    let raster = Raster {
        grid,
        elevation_m: (0..n * n)
            .map(|k| height((k / n) as f64, (k % n) as f64) as f32)
            .collect(),
        material: Some(vec![Material::Grass; n * n]),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary =
        build_pyramid::<cig_terrain::build::BuildError>(&raster, TILE as u32, &mut |t| {
            store.insert(t.key, t.encode());
            Ok(())
        })?;
    let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]);
    // The wood: finest tiles 2..4 in both directions (grid posts 256..512).
    let mut x = 7u64;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let (lo, span) = (2.0 * TILE as f64, 2.0 * TILE as f64);
    let mut placements = Vec::new();
    for k in 0..160_000 {
        let (r, c) = (lo + span * next(), lo + span * next());
        let kind = match k % 50 {
            0 => CultureKind::House,
            1..=20 => CultureKind::BroadleafTree,
            _ => CultureKind::ConiferTree,
        };
        let [h, w, l] = kind.typical_size_m();
        let s = 0.8 + 0.4 * next() as f32;
        placements.push(CulturePlacement {
            kind,
            lat_deg: grid.south_lat_deg + r * grid.dlat_deg,
            lon_deg: grid.west_lon_deg + c * grid.dlon_deg,
            height_m: h * s,
            width_m: w * s,
            length_m: l * s,
            heading_deg: 360.0 * next() as f32,
            variant: k as u8,
        });
    }
    let (tiles, culture) = bin_placements(&manifest.layout, &placements)?;
    for tile in &tiles {
        store.insert_culture(tile.key, tile.encode());
    }
    println!(
        "{} objects on {} tiles, at most {} a tile",
        culture.total(),
        culture.tiles,
        culture.max_items_per_tile
    );
    for (label, recorded) in [
        ("bounds recorded", true),
        ("old manifest (no bounds)", false),
    ] {
        let mut manifest = manifest.clone();
        let mut culture = culture.clone();
        if !recorded {
            culture.max_footprint_radius_m = 0.0;
            culture.max_height_m = 0.0;
        }
        println!(
            "{label}: footprint bound {:.1} m, height bound {:.1} m",
            culture.footprint_bound_m(),
            culture.height_bound_m()
        );
        manifest.culture = Some(culture);
        let db = Arc::new(TerrainDatabase::new(
            manifest,
            Arc::clone(&store) as Arc<dyn TileStore>,
        )?);
        run(&db, grid, &mut next)?;
    }
    Ok(())
}

fn run(
    db: &Arc<TerrainDatabase>,
    grid: GeoGrid,
    next: &mut impl FnMut() -> f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let lo = 2.0 * TILE as f64;
    let cache = Arc::new(TileCache::new(Arc::clone(db), PagingConfig::default())?);
    let mut q = QuerySession::new(Arc::clone(&cache));
    let geodetic = |q: &mut QuerySession, r: f64, c: f64, up: f64| {
        let (lat, lon) = (
            grid.south_lat_deg + r * grid.dlat_deg,
            grid.west_lon_deg + c * grid.dlon_deg,
        );
        let ground = q.height_msl_m(lat, lon).expect("inside");
        Geodetic::new(lat, lon, ground + up)
    };
    let count = 20_000;
    // (name, from (row, col, up), to (row, col, up)) generators.
    type Line = ((f64, f64, f64), (f64, f64, f64));
    let cases: Vec<(&str, Vec<Line>)> = vec![
        (
            "eye height in the wood, 300 m",
            (0..count)
                .map(|_| {
                    let (r, c) = (lo + 20.0 + 200.0 * next(), lo + 20.0 + 200.0 * next());
                    let a = std::f64::consts::TAU * next();
                    ((r, c, 1.8), (r + 10.0 * a.sin(), c + 10.0 * a.cos(), 1.8))
                })
                .collect(),
        ),
        (
            "over the canopy (40 m), 2 km",
            (0..count)
                .map(|_| {
                    let (r, c) = (lo + 20.0 + 150.0 * next(), lo + 20.0 + 150.0 * next());
                    let a = std::f64::consts::TAU * next();
                    ((r, c, 40.0), (r + 66.0 * a.sin(), c + 66.0 * a.cos(), 40.0))
                })
                .collect(),
        ),
        (
            "air to ground (1000 m down to 2 m), 3 km",
            (0..count)
                .map(|_| {
                    let (r, c) = (lo + 20.0 + 200.0 * next(), lo + 20.0 + 200.0 * next());
                    let a = std::f64::consts::TAU * next();
                    (
                        (r, c, 2.0),
                        (r + 100.0 * a.sin(), c + 100.0 * a.cos(), 1000.0),
                    )
                })
                .collect(),
        ),
        (
            "along a tile edge (3 m east of it, 40 m up), 2 km",
            (0..count)
                .map(|_| {
                    let r = lo + 20.0 + 150.0 * next();
                    let c = 3.0 * TILE as f64 + 0.1;
                    ((r, c, 40.0), (r + 66.0, c, 40.0))
                })
                .collect(),
        ),
    ];
    for (name, lines) in cases {
        let lines: Vec<(Geodetic, Geodetic)> = lines
            .iter()
            .map(|&((r0, c0, u0), (r1, c1, u1))| {
                (geodetic(&mut q, r0, c0, u0), geodetic(&mut q, r1, c1, u1))
            })
            .collect();
        // Warm: every tile and culture index the lines use is at hand.
        for &(a, b) in &lines {
            std::hint::black_box(q.los(a, b)?);
        }
        let t = Instant::now();
        let mut blocked = 0;
        let mut by_culture = 0;
        for _ in 0..3 {
            for &(a, b) in &lines {
                let r = q.los(a, b)?;
                blocked += usize::from(!r.visible);
                by_culture += usize::from(r.hit.is_some_and(|h| h.culture.is_some()));
            }
        }
        let per = t.elapsed().as_secs_f64() / (3.0 * lines.len() as f64);
        println!(
            "{name}: {:.2} us per LOS ({:.0} % blocked, {:.0} % by culture)",
            per * 1e6,
            100.0 * blocked as f64 / (3.0 * lines.len() as f64),
            100.0 * by_culture as f64 / (3.0 * lines.len() as f64),
        );
    }
    // Cold: a fresh cache and session for each of a few lines.
    let t = Instant::now();
    let cold = 20;
    for k in 0..cold {
        let cache = Arc::new(TileCache::new(Arc::clone(db), PagingConfig::default())?);
        let mut q = QuerySession::new(cache);
        let r = lo + 20.0 + 10.0 * k as f64;
        let (a, b) = (
            geodetic(&mut q, r, lo + 20.0, 40.0),
            geodetic(&mut q, r, lo + 100.0, 40.0),
        );
        std::hint::black_box(q.los(a, b)?);
    }
    println!(
        "cold (fresh cache, 2.4 km over the canopy): {:.0} us per LOS, tile loads included",
        t.elapsed().as_secs_f64() * 1e6 / f64::from(cold)
    );
    Ok(())
}
