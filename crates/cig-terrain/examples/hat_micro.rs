//! Micro-benchmark of the HAT path on an in-memory database: a small window (cache-resident)
//! against the whole area (memory-bound). `cargo run --release -p cig-terrain --example hat_micro`
use cig_geo::Geodetic;
use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{Material, PagingConfig, QuerySession, TileCache};
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n = 1668;
    let grid = GeoGrid {
        south_lat_deg: 36.0,
        west_lon_deg: -121.0,
        dlat_deg: 0.00027,
        dlon_deg: 0.00033,
        rows: n,
        cols: n,
    };
    let raster = Raster {
        grid,
        elevation_m: (0..n * n).map(|k| ((k * 7919) % 1000) as f32).collect(),
        material: Some(vec![Material::Grass; n * n]),
    };
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(&raster, 128, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })?;
    let manifest = Manifest::from_build(&summary, GeoidGrid::zero(), 0, vec![]);
    let db = Arc::new(TerrainDatabase::new(manifest, store)?);
    let cache = Arc::new(TileCache::new(db, PagingConfig::default())?);
    let mut q = QuerySession::new(cache);
    for (name, span) in [("one tile", 0.03), ("whole area", 0.44)] {
        let mut x = 1u64;
        let pts: Vec<Geodetic> = (0..1 << 20)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                let a = (x >> 11) as f64 / (1u64 << 53) as f64;
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                let b = (x >> 11) as f64 / (1u64 << 53) as f64;
                Geodetic::new(36.001 + a * span, -120.999 + b * span, 500.0)
            })
            .collect();
        for p in &pts {
            std::hint::black_box(q.hat_m(*p)?);
            std::hint::black_box(q.height_msl_m(p.lat_deg, p.lon_deg)?);
        }
        let t = Instant::now();
        let mut sum = 0.0;
        for _ in 0..5 {
            for p in &pts {
                sum += q.hat_m(*p)?;
            }
        }
        let per = t.elapsed().as_secs_f64() / (5.0 * pts.len() as f64);
        println!(
            "{name}: {:.1} ns per HAT ({:.2} M/s) {sum:.0}",
            per * 1e9,
            1e-6 / per
        );
        let t = Instant::now();
        for _ in 0..5 {
            for p in &pts {
                sum += q.height_msl_m(p.lat_deg, p.lon_deg)?;
            }
        }
        let per = t.elapsed().as_secs_f64() / (5.0 * pts.len() as f64);
        println!(
            "{name}: {:.1} ns per height only ({:.2} M/s) {sum:.0}",
            per * 1e9,
            1e-6 / per
        );
        let mut out = Vec::new();
        let t = Instant::now();
        for _ in 0..5 {
            for frame in pts.chunks(256) {
                q.hat_batch_m(frame, &mut out);
                sum += out.iter().flatten().sum::<f64>();
            }
        }
        let per = t.elapsed().as_secs_f64() / (5.0 * pts.len() as f64);
        println!(
            "{name}: {:.1} ns per batched HAT ({:.2} M/s) {sum:.0}",
            per * 1e9,
            1e-6 / per
        );
    }
    Ok(())
}
