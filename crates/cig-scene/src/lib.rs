//! The renderer's plain data, computed on the CPU without touching the GPU: views and camera
//! maths ([`view`]), the terrain quadtree's nodes ([`node`]), level-of-detail selection
//! ([`lod`]) and node meshes ([`terrain_mesh`]), light, sky and fog ([`lighting`]), entity
//! models ([`models`]) and the choice of their levels by the detail control parameter
//! ([`detail`]), the per-frame snapshot ([`snapshot`]), lightning bolts ready to draw
//! and their flash ([`bolt`]), and what a thermal sensor view needs ([`thermal`]).
//!
//! This crate is pure: it never opens files, sockets, the GPU or the terminal; `cig-render`
//! turns what it computes into frames.

pub mod bolt;
pub mod culture;
pub mod detail;
pub mod display;
pub mod edit_patch;
pub mod horizon;
pub mod lighting;
pub mod lights;
pub mod lod;
pub mod models;
pub mod node;
pub mod nvg;
pub mod overload;
pub mod reticle;
pub mod sea;
pub mod snapshot;
pub mod terrain_mesh;
pub mod thermal;
pub mod view;

pub use lighting::{Fog, FogMode, Lighting};
pub use lod::{LodSettings, Selection, TerrainLod};
pub use node::{NodeKey, NodeLayout};
pub use snapshot::{
    lift_eyes_above_terrain, BoltDraw, BoltLine, EntityInstance, EntitySpec, EyeBelowTerrain,
    FogLayer, FrameSnapshot, PrecipitationDraw,
};
pub use view::{Camera, FovDeg, Hpr, View, ViewError};
