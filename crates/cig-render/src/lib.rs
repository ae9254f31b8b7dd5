//! The wgpu renderer of cig: round-earth terrain with continuous level of detail, entity
//! models, a physically based sky (Bruneton/Hillaire atmosphere, sun disc, aerial perspective,
//! moon and stars) and fog, cloud layers, obscurant puffs (smoke, flame, dust), exposure from the
//! natural light and a tone map, for off-screen frames and windows alike.
//!
//! The renderer owns every GPU resource; the world reaches it as plain data (a
//! [`cig_scene::FrameSnapshot`] and the terrain [`cig_terrain::TileCache`]). Any wgpu backend
//! works (Vulkan, Metal, DX12, GL); with no GPU, Mesa's lavapipe renders the same frames.

pub mod ac_coupling;
pub mod adaptation;
pub mod atmosphere;
pub mod bolts;
pub mod celestial;
pub mod clouds;
pub mod display;
pub mod gltf_model;
pub mod gpu;
pub mod imagery;
pub mod lights;
pub mod offscreen;
pub mod pass;
pub mod precipitation;
pub mod puffs;
pub mod renderer;
pub mod sea;
pub mod sensor;
pub mod terrain;
pub mod viewer;

pub use adaptation::Adaptation;
pub use gltf_model::{load_gltf_model, ModelError};
pub use gpu::{Gpu, RenderError};
pub use offscreen::{load_for_view, render_image, render_image_with, Image, OffscreenTarget};
pub use pass::MSAA_SAMPLES;
pub use renderer::serde_like::FrameStats;
pub use renderer::{FrameOptions, Renderer, FRAME_FORMAT};
pub use viewer::{
    run_viewer, run_viewer_driven, FrameDriver, ObscurantOrder, ViewerError, ViewerOptions,
    ViewerReport, ViewerTick,
};
