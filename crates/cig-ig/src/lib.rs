//! cig's image-generator session, pure: the host's CIGI messages applied to the world and
//! answered, the DIS exercise joined, and the scenario file read — no sockets, GPU, files or
//! terminal (the `cig` binary owns those and hands bytes and text in).
//!
//! Modules, each opening with its algorithm and sources:
//! - [`scenario`]: the scenario file (TOML): entity-type table, owned entities, default view,
//!   DIS settings.
//! - [`model_table`]: entity types (CIGI and DIS) to models.
//! - [`pose`]: body-axis offsets, attachment and orientation composition, MSL altitudes.
//! - [`session`]: the IG side of CIGI 3.3/4.0 (ICD 3.3 §2.3, §4): packets applied, requests
//!   answered from the terrain query service, Start of Frame with the standard's counters.
//! - [`exercise`]: DIS 7/6 participation (thesis 000 §VI.E): remote entities, owned entities,
//!   detonation and appearance effects, shared world time.
//! - [`world`]: the per-frame step that ties them to the clock and the effects and produces
//!   the renderer's snapshot.
//! - [`frame_lock`]: the display channels' frame lock (a slave's "frame drawn" datagram, the
//!   master's wait for its slaves, with a timeout that drops a dead channel).
//! - [`weather`]: lightning storms (a Poisson strike schedule that is a function of seed and
//!   world time), the bolts lit now and their flash.
//! - [`lights`]: each drawn entity's lamps (light set from its model and domain, switches from
//!   its DIS appearance, the scenario or the host's Component Control) and burning entities'
//!   fires.
//! - [`scenes`]: the fires and the lightning bolt a single frame asks for (`cig render --smoke`,
//!   `--lightning`, the demo's storm).
//!
//! Limits: see each module.

pub mod exercise;
pub mod frame_lock;
pub mod lights;
pub mod model_table;
pub mod pose;
pub mod scenario;
pub mod scenes;
pub mod sea;
pub mod session;
pub mod terrain_edits;
pub mod thermal;
pub mod tracker;
pub mod weather;
pub mod world;

pub use cig_effects::EFFECT_EPOCH_UNIX_S;
pub use exercise::{Exercise, ExerciseCounters};
pub use model_table::{CigiEntityType, ModelTable};
pub use pose::{BodyOffset, Pose};
pub use scenario::{DisSettings, Scenario, ScenarioError, SmokeSource};
pub use session::{HostTimeSet, IgSession, SessionConfig, SessionCounters};
pub use world::{IgWorld, WorldConfig, WorldError};
