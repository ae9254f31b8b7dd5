//! cig's benchmarks, and the fixtures and scenes they share with the demo and the commands.
//!
//! Each benchmark takes a plain option struct and returns its report as JSON (and, where the
//! command prints a summary instead, that summary as text); the `cig bench` commands map their
//! arguments onto the options and print what comes back. Every rate or time is measured
//! against a baseline taken in the same run on the same data (copying the bytes, a flat array
//! step, the memory reads alone, the same frames with the feature off), so the ratios survive a
//! noisy machine; the figures themselves are medians of rounds. Reports carry the machine, the
//! date and the commit (given by the caller).
//!
//! - [`db`]: HAT, batched HAT and LOS rates on one core, cold tile loads, build and import times.
//! - [`imagery`]: importing a synthetic 20,000 x 20,000 RGB orthoimage: time, peak memory.
//! - [`particles`]: one fixed step of the obscurant engine with about 22,000 puffs.
//! - [`render`]: a 300 m/s low pass streamed, level of detail against full detail, the ground's
//!   detail against plain colour texels, plumes in view.
//! - [`net`]: DIS decoding, 10,000 dead-reckoned remote entities, HAT/HOT requests, CIGI
//!   decoding and applying, and a flood of a loopback endpoint.
//! - [`channels`]: three display channels (`cig serve` processes) frame-locked to a host: the
//!   spread of their frames, a slave's cost against a master's, a restarted slave's rejoining.
//! - [`soak`]: a long run of `cig serve` under load, its memory, frame time, descriptors and
//!   threads watched for drift.
//! - [`env`]: the ephemeris and light per update, and the physical sky, fog and clouds' share
//!   of the frame.
//!
//! Shared with `cig demo`, `cig db` and `cig render`: [`database`] (the demo database's
//! parameters, building a database with a progress callback), [`flight`] (views along a leg
//! that follows the terrain), [`demo`] (the demo's hilltop, flight, environment shots and
//! contact sheet).
//!
//! Limits: benchmarks are commands, never timed tests; figures depend on the machine (see
//! each module). The GPU benchmarks need a device (lavapipe does). Nothing here prints: the
//! caller prints the reports, and draws the progress the callbacks report.

pub mod channels;
pub mod culture;
pub mod database;
pub mod db;
pub mod demo;
pub mod dynterrain;
pub mod env;
pub mod flight;
pub mod imagery;
pub mod net;
pub mod particles;
pub mod render;
mod report;
pub mod sea;
pub mod sensor;
pub mod soak;

/// A report with a human summary: `cig bench` prints the JSON with `--json`, else the summary.
#[derive(Clone, Debug)]
pub struct Report {
    /// Every figure, with the machine, date and commit.
    pub json: serde_json::Value,
    /// The figures that matter, in a few lines.
    pub summary: String,
}

/// Why a benchmark could not run. One line each.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// An option out of its range; the message names it.
    #[error("{0}")]
    Option(String),
    /// The benchmark cannot measure this input (database too small, nothing in view …).
    #[error("{0}")]
    Scene(String),
    /// A step that failed: what was being done, then why.
    #[error("{what}: {reason}")]
    Step { what: String, reason: String },
    #[error(transparent)]
    Database(#[from] cig_terrain_io::store::DbError),
    #[error(transparent)]
    Import(#[from] cig_terrain_io::import::ImportError),
    #[error(transparent)]
    Imagery(#[from] cig_terrain_io::imagery::ImageryError),
    #[error(transparent)]
    Synth(#[from] cig_synth::SynthError),
    #[error(transparent)]
    Paging(#[from] cig_terrain::cache::PagingConfigError),
    #[error(transparent)]
    Load(#[from] cig_terrain::database::LoadError),
    #[error(transparent)]
    Query(#[from] cig_terrain::QueryError),
    #[error(transparent)]
    Render(#[from] cig_render::RenderError),
    #[error(transparent)]
    Effects(#[from] cig_effects::EffectsError),
    #[error(transparent)]
    Environment(#[from] cig_environment::EnvironmentError),
    #[error(transparent)]
    Cigi(#[from] cig_cigi::CigiError),
    #[error(transparent)]
    DisEncode(#[from] cig_dis::EncodeError),
    #[error(transparent)]
    World(#[from] cig_ig::WorldError),
    #[error(transparent)]
    Scenario(#[from] cig_ig::ScenarioError),
    #[error(transparent)]
    Net(#[from] cig_net::NetError),
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Integer(#[from] std::num::TryFromIntError),
}

/// The terrain's height above the ellipsoid at a point, for placing a benchmark's eye and
/// objects.
pub(crate) fn ground_m(
    session: &mut cig_terrain::QuerySession,
    lat_deg: f64,
    lon_deg: f64,
) -> Result<f64, BenchError> {
    session
        .hot(lat_deg, lon_deg)
        .map(|h| h.height_ellipsoid_m())
        .step("the terrain under the benchmark's scene")
}

/// Adds what was being done to an error, as `anyhow`'s context would: "what: reason: cause".
pub(crate) trait Step<T> {
    /// The error, if any, as a [`BenchError::Step`] saying `what` failed.
    fn step(self, what: &str) -> Result<T, BenchError>;
    /// The same, with `what` made only on failure.
    fn step_with(self, what: impl FnOnce() -> String) -> Result<T, BenchError>;
}

impl<T, E: std::error::Error> Step<T> for Result<T, E> {
    fn step(self, what: &str) -> Result<T, BenchError> {
        self.step_with(|| what.to_string())
    }

    fn step_with(self, what: impl FnOnce() -> String) -> Result<T, BenchError> {
        self.map_err(|e| {
            let mut reason = e.to_string();
            let mut cause = e.source();
            while let Some(c) = cause {
                reason.push_str(": ");
                reason.push_str(&c.to_string());
                cause = c.source();
            }
            BenchError::Step {
                what: what(),
                reason,
            }
        })
    }
}

/// Refuses an option unless `ok`.
pub(crate) fn require(ok: bool, message: impl FnOnce() -> String) -> Result<(), BenchError> {
    if ok {
        Ok(())
    } else {
        Err(BenchError::Option(message()))
    }
}
