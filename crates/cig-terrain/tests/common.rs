//! Shared helpers: analytic terrains built into in-memory databases.
#![allow(dead_code, reason = "each test file uses a different subset")]

use cig_terrain::build::build_pyramid;
use cig_terrain::database::{GeoidGrid, Manifest, MemoryTileStore, TerrainDatabase};
use cig_terrain::material::Material;
use cig_terrain::raster::{GeoGrid, Raster};
use cig_terrain::{PagingConfig, TileCache};
use std::sync::Arc;

/// A grid of `rows x cols` posts at about `spacing_m` near 36 N 121 W.
pub fn grid(rows: usize, cols: usize, spacing_m: f64) -> GeoGrid {
    let (n, e) = cig_geo::metres_per_degree(36.0);
    GeoGrid {
        south_lat_deg: 36.0,
        west_lon_deg: -121.0,
        dlat_deg: spacing_m / n,
        dlon_deg: spacing_m / e,
        rows,
        cols,
    }
}

/// A raster whose post (row, col) has height `f(row, col)`; materials cycle by column.
pub fn raster(grid: GeoGrid, f: impl Fn(usize, usize) -> f32) -> Raster {
    let elevation_m = (0..grid.len())
        .map(|k| f(k / grid.cols, k % grid.cols))
        .collect();
    let material = (0..grid.len())
        .map(|k| Material::ALL[(k % grid.cols) % 9])
        .collect();
    Raster {
        grid,
        elevation_m,
        material: Some(material),
    }
}

/// Builds `raster` into a memory store; `geoid_m` is a constant undulation.
pub fn database(
    raster: &Raster,
    tile_cells: u32,
    geoid_m: f32,
) -> (Arc<TerrainDatabase>, Arc<MemoryTileStore>) {
    let store = Arc::new(MemoryTileStore::new());
    let summary = build_pyramid::<cig_terrain::build::BuildError>(raster, tile_cells, &mut |t| {
        store.insert(t.key, t.encode());
        Ok(())
    })
    .expect("build");
    let mut geoid = GeoidGrid::zero();
    geoid.undulation_m.iter_mut().for_each(|v| *v = geoid_m);
    let manifest = Manifest::from_build(&summary, geoid, 0, vec!["test".into()]);
    let db = TerrainDatabase::new(manifest, store.clone() as Arc<dyn cig_terrain::TileStore>)
        .expect("db");
    (Arc::new(db), store)
}

pub fn cache(db: &Arc<TerrainDatabase>, config: PagingConfig) -> Arc<TileCache> {
    Arc::new(TileCache::new(Arc::clone(db), config).expect("cache"))
}
