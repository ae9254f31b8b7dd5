//! Terrain database model and the IG's terrain queries.
//!
//! Data flows one way: a [`raster::Raster`] (from an importer or the synthetic generator) has
//! its voids filled ([`fill`]) and its materials derived when it has none ([`classify`]), then
//! [`build`] cuts it into the tiles of a quadtree pyramid ([`pyramid`], [`tile`]), with each
//! post's error for adaptive meshes ([`rtin`]). An open
//! [`database::TerrainDatabase`] hands tiles to the paging [`cache::TileCache`], and
//! [`query::QuerySession`] answers HOT, HAT and line of sight on the finest surface, line of
//! sight and collision also against the culture's simple volumes ([`culture_hit`]).
//!
//! This crate is pure: it never opens files, sockets, the GPU or the terminal. Tile bytes come
//! from a [`database::TileStore`] that an edge crate implements.

pub mod build;
pub mod cache;
pub mod classify;
pub mod culture;
pub mod culture_hit;
pub mod database;
pub mod edits;
pub mod features;
pub mod fill;
pub mod hint;
pub mod imagery;
pub mod material;
pub mod pyramid;
pub mod query;
pub mod raster;
pub mod rtin;
pub mod tile;

pub use cache::{PagingConfig, TileCache};
pub use culture::{CultureItem, CultureKind, CultureManifest, CulturePlacement, CultureTile};
pub use culture_hit::{CultureHit, CultureTest};
pub use database::{Manifest, TerrainDatabase, TileStore};
pub use edits::{EditAuthor, EditId, EditLayer, EditShape, GeoPoint, SpoilSide, TerrainEdit};
pub use imagery::{ImageryKey, ImageryLayout, ImageryManifest, ImageryTile};
pub use material::Material;
pub use pyramid::{PyramidLayout, TileKey};
pub use query::{
    CultureSurface, LosHit, LosResult, QueryError, QuerySession, Refraction, SurfacePoint,
};
pub use raster::{GeoGrid, Raster};
