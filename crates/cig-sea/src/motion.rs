//! Ships riding the sea in the time domain: a hull's particulars ([`HullParameters`]: its
//! natural periods), and heave, pitch and roll integrated in time from the wave surface,
//! deterministic in (sea, track, time).
//!
//! The IG's ships use the same oscillators in closed form ([`crate::response`]: no history,
//! microseconds a frame); this integration checks it, and follows a recorded track whose
//! course and speed change (the transients the closed form leaves out), at the cost of the
//! sea sampled over minutes of the past.
//!
//! Algorithm:
//!
//! 1. Wave-following attitude ([`ShipMotionModel::equilibrium`]). The sea height is sampled
//!    over the waterplane at 5 rows across (±0.4 B, ±0.2 B, 0) of one point per 2.5 m along
//!    the hull (16..=64 points a row, so 80..=320 points), and a plane `h = a + b ξ + c η`
//!    (ξ forward, η to starboard) is fitted by least squares, each point weighted by the
//!    local breadth of a waterplane `B (1 − (2ξ / L)⁴)` (area coefficient 0.8). The plane's
//!    height `a` is the equilibrium heave, `atan b` the pitch, `−atan c` the roll. Averaging
//!    over the waterplane filters out waves much shorter than the hull, as the real hull's
//!    buoyancy does (the Froude–Krylov force is the pressure integrated over the hull); the
//!    tapered ends keep the cut-off smooth. The rows are staggered along the hull by ½ and
//!    ½ ± acos(−¼)/2π of a cell so that a wave exactly one cell long, which would alias
//!    through each row, cancels over the five.
//! 2. Dynamics. Heave, pitch and roll are each a linear second-order oscillator driven
//!    towards that attitude, `ẍ + 2ζω ẋ + ω² x = ω² x_eq(t)`: following long waves
//!    quasi-statically, amplifying near resonance by up to `1 / 2ζ`, and filtering waves
//!    whose encounter period is much shorter than the natural period. No coupling between
//!    modes; no surge, sway or yaw.
//!    - Roll natural period: `T_φ = 2 C B / √GM`, with
//!      `C = 0.373 + 0.023 (B / d) − 0.043 (L / 100)` (IMO Intact Stability Code 2008, part A
//!      2.3.4, weather criterion; `C` ≈ 0.37–0.44 for ordinary hulls; `L` is taken as the
//!      waterline length and `d` as the mean draft).
//!    - Heave and pitch natural periods: `T_z = T_θ = 2.5 √d` s (d in m). From the heave
//!      natural frequency `ω² = ρ g A_wp / (m + a₃₃)` (SNAME *Principles of Naval
//!      Architecture* vol. III, Motions in Waves) with the added mass `a₃₃` ≈ the displaced
//!      mass and `C_B / C_WP` ≈ 0.78: `T_z = 2π √(2 C_B d / (g C_WP))` ≈ 2.5 √d. Pitch is
//!      given the same period (in conventional hulls the two are close; a simplification).
//!    - Damping ratios: roll 0.07 (lightly damped; bilge keels give about 0.05–0.1), heave
//!      and pitch 0.3 (strong wave-radiation damping, 0.2–0.5). All three can be set.
//! 3. Determinism. The oscillators are integrated by a classical Runge–Kutta step of
//!    [`MOTION_STEP_S`] (1/20 s) on the absolute time grid `k / 20` s, the attitude being
//!    linear between grid points, starting at rest on the attitude a fixed window before `t`
//!    (five e-folding times of the slowest mode, 60..=600 s, [`ShipMotionModel::window_s`])
//!    and ending with a partial step to `t` itself. **The motion at `t` is therefore a
//!    function of (sea, track, t) only** ([`ShipMotionModel::motion_at`]): two IGs with the
//!    same sea and track agree bit for bit whatever frame times they ran. Sea older than the
//!    window is forgotten; its influence would have decayed to e⁻⁵ < 1 %.
//!    [`ShipMotionTracker`] gives the same numbers bit for bit while computing each grid
//!    point's attitude once (cached): 80..=320 sea samples per grid step (20 a second) plus
//!    a re-run of the cheap oscillators over the window each call.
//!
//! The ship's past positions come from a track, `t ↦ ShipPose`; for a ship on a straight
//! course at constant speed, [`StraightCourse`] dead-reckons it backwards, so the sea is
//! sampled where the hull was (this gives the encounter frequency). A course or speed change
//! then rewrites the reconstructed past; pass a recorded track to avoid that.
//!
//! Limits: linear, uncoupled modes with constant coefficients (no parametric roll, no
//! nonlinear righting arm, no slamming or green water); one waterplane shape for all hulls
//! (the rows stay at ±0.4 B where the real waterplane narrows); the oscillators run on the
//! fitted plane's slopes, so angles are assumed small (below ~30°); the sea is only its height
//! (no orbital velocities, no wave drift); added mass and damping do not vary with frequency
//! or speed.

use std::collections::VecDeque;

use crate::{checked, SeaError};

/// The integration step and grid spacing, s (1/20 s).
pub const MOTION_STEP_S: f64 = 0.05;

/// The shortest window of sea history used, s.
pub const MIN_WINDOW_S: f64 = 60.0;

/// The longest window of sea history used, s.
pub const MAX_WINDOW_S: f64 = 600.0;

/// E-folding times of the slowest mode the window spans.
const WINDOW_E_FOLDS: f64 = 5.0;

/// Heave and pitch natural period per square root of draft, s/√m.
pub const HEAVE_PERIOD_PER_SQRT_DRAFT: f64 = 2.5;

/// Default roll damping ratio.
pub const DEFAULT_ROLL_DAMPING: f64 = 0.07;

/// Default heave damping ratio.
pub const DEFAULT_HEAVE_DAMPING: f64 = 0.3;

/// Default pitch damping ratio.
pub const DEFAULT_PITCH_DAMPING: f64 = 0.3;

/// Largest |time| accepted, s.
const MAX_TIME_S: f64 = 1.0e9;

/// Target length of a waterplane cell along the hull, m.
const ALONG_CELL_M: f64 = 2.5;

/// Rows across the waterplane.
const ACROSS_ROWS: usize = 5;

/// A hull's main particulars for seakeeping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullParameters {
    length_m: f64,
    beam_m: f64,
    draft_m: f64,
    gm_m: f64,
    roll_damping: f64,
    heave_damping: f64,
    pitch_damping: f64,
}

impl HullParameters {
    /// A destroyer-size warship: 150 m × 18 m, draft 5.5 m, GM 1.5 m (roll period 11.3 s,
    /// heave and pitch 5.9 s).
    pub const DESTROYER: HullParameters = HullParameters {
        length_m: 150.0,
        beam_m: 18.0,
        draft_m: 5.5,
        gm_m: 1.5,
        roll_damping: DEFAULT_ROLL_DAMPING,
        heave_damping: DEFAULT_HEAVE_DAMPING,
        pitch_damping: DEFAULT_PITCH_DAMPING,
    };

    /// A merchant ship: 180 m × 30 m, draft 10 m, GM 2 m (roll period 15.5 s, heave and
    /// pitch 7.9 s).
    pub const MERCHANT: HullParameters = HullParameters {
        length_m: 180.0,
        beam_m: 30.0,
        draft_m: 10.0,
        gm_m: 2.0,
        roll_damping: DEFAULT_ROLL_DAMPING,
        heave_damping: DEFAULT_HEAVE_DAMPING,
        pitch_damping: DEFAULT_PITCH_DAMPING,
    };

    /// A patrol craft: 30 m × 6 m, draft 1.8 m, GM 0.9 m (roll period 5.5 s, heave and
    /// pitch 3.4 s).
    pub const PATROL_CRAFT: HullParameters = HullParameters {
        length_m: 30.0,
        beam_m: 6.0,
        draft_m: 1.8,
        gm_m: 0.9,
        roll_damping: DEFAULT_ROLL_DAMPING,
        heave_damping: DEFAULT_HEAVE_DAMPING,
        pitch_damping: DEFAULT_PITCH_DAMPING,
    };

    /// A hull `length_m` (waterline, 5..=500 m) by `beam_m` (1..=100 m, at most the length),
    /// drawing `draft_m` (0.2..=30 m, at most the length) with metacentric height `gm_m`
    /// (0.05..=20 m), with the default damping ratios.
    pub fn new(
        length_m: f64,
        beam_m: f64,
        draft_m: f64,
        gm_m: f64,
    ) -> Result<HullParameters, SeaError> {
        let length_m = checked("length_m", length_m, 5.0, 500.0, "5..=500 m")?;
        let beam_m = checked("beam_m", beam_m, 1.0, 100.0, "1..=100 m")?;
        if beam_m > length_m {
            return Err(SeaError::OutOfRange {
                name: "beam_m",
                range: "at most length_m",
                value: beam_m,
            });
        }
        let draft_m = checked("draft_m", draft_m, 0.2, 30.0, "0.2..=30 m")?;
        if draft_m > length_m {
            return Err(SeaError::OutOfRange {
                name: "draft_m",
                range: "at most length_m",
                value: draft_m,
            });
        }
        let gm_m = checked("gm_m", gm_m, 0.05, 20.0, "0.05..=20 m")?;
        Ok(HullParameters {
            length_m,
            beam_m,
            draft_m,
            gm_m,
            roll_damping: DEFAULT_ROLL_DAMPING,
            heave_damping: DEFAULT_HEAVE_DAMPING,
            pitch_damping: DEFAULT_PITCH_DAMPING,
        })
    }

    /// The same hull with other damping ratios (each 0.01..=1, 1 being critical).
    pub fn with_damping(
        self,
        roll: f64,
        heave: f64,
        pitch: f64,
    ) -> Result<HullParameters, SeaError> {
        Ok(HullParameters {
            roll_damping: checked("roll damping ratio", roll, 0.01, 1.0, "0.01..=1")?,
            heave_damping: checked("heave damping ratio", heave, 0.01, 1.0, "0.01..=1")?,
            pitch_damping: checked("pitch damping ratio", pitch, 0.01, 1.0, "0.01..=1")?,
            ..self
        })
    }

    /// The parameters' bits, to key a cache by hull.
    pub fn bits(&self) -> [u64; 7] {
        [
            self.length_m,
            self.beam_m,
            self.draft_m,
            self.gm_m,
            self.roll_damping,
            self.heave_damping,
            self.pitch_damping,
        ]
        .map(f64::to_bits)
    }

    /// Waterline length, m.
    pub fn length_m(&self) -> f64 {
        self.length_m
    }

    /// Beam, m.
    pub fn beam_m(&self) -> f64 {
        self.beam_m
    }

    /// Mean draft, m.
    pub fn draft_m(&self) -> f64 {
        self.draft_m
    }

    /// Transverse metacentric height GM, m.
    pub fn gm_m(&self) -> f64 {
        self.gm_m
    }

    /// Roll damping ratio ζ (fraction of critical).
    pub fn roll_damping(&self) -> f64 {
        self.roll_damping
    }

    /// Heave damping ratio ζ.
    pub fn heave_damping(&self) -> f64 {
        self.heave_damping
    }

    /// Pitch damping ratio ζ.
    pub fn pitch_damping(&self) -> f64 {
        self.pitch_damping
    }

    /// The IMO roll coefficient `C = 0.373 + 0.023 (B / d) − 0.043 (L / 100)`, s/√m.
    pub fn roll_coefficient(&self) -> f64 {
        0.373 + 0.023 * (self.beam_m / self.draft_m) - 0.043 * (self.length_m / 100.0)
    }

    /// Natural roll period `2 C B / √GM`, s.
    pub fn roll_period_s(&self) -> f64 {
        2.0 * self.roll_coefficient() * self.beam_m / self.gm_m.sqrt()
    }

    /// Natural heave period `2.5 √d`, s.
    pub fn heave_period_s(&self) -> f64 {
        HEAVE_PERIOD_PER_SQRT_DRAFT * self.draft_m.sqrt()
    }

    /// Natural pitch period, s: taken equal to the heave period.
    pub fn pitch_period_s(&self) -> f64 {
        self.heave_period_s()
    }
}

/// A ship's motion about its calm-water floating position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShipMotion {
    /// Heave, m, up positive.
    pub heave_m: f64,
    /// Pitch, degrees, bow up positive.
    pub pitch_deg: f64,
    /// Roll, degrees, starboard down positive.
    pub roll_deg: f64,
}

/// Where a ship is at one moment, in the sea's local frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShipPose {
    /// Position east of the frame's origin, m (centre of the waterplane).
    pub x_east_m: f64,
    /// Position north of the frame's origin, m.
    pub y_north_m: f64,
    /// Heading, degrees true (clockwise from north).
    pub heading_deg: f64,
}

/// A straight course at constant speed through a known position at a known time: the track
/// dead-reckoned forwards and backwards from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StraightCourse {
    pose: ShipPose,
    speed_mps: f64,
    t_s: f64,
}

impl StraightCourse {
    /// The ship at (`x_east_m`, `y_north_m`) (|x|, |y| <= 10 000 km) at `t_s` (|t| <= 10⁹ s),
    /// heading `heading_deg` true (finite) at `speed_mps` (0..=40 m/s) through the water.
    pub fn new(
        x_east_m: f64,
        y_north_m: f64,
        heading_deg: f64,
        speed_mps: f64,
        t_s: f64,
    ) -> Result<StraightCourse, SeaError> {
        let pose = ShipPose {
            x_east_m: checked("x_east_m", x_east_m, -1.0e7, 1.0e7, "-1e7..=1e7 m")?,
            y_north_m: checked("y_north_m", y_north_m, -1.0e7, 1.0e7, "-1e7..=1e7 m")?,
            heading_deg: checked("heading_deg", heading_deg, -1.0e6, 1.0e6, "-1e6..=1e6 deg")?,
        };
        Ok(StraightCourse {
            pose,
            speed_mps: checked("speed_mps", speed_mps, 0.0, 40.0, "0..=40 m/s")?,
            t_s: checked("t_s", t_s, -MAX_TIME_S, MAX_TIME_S, "-1e9..=1e9 s")?,
        })
    }

    /// The velocity (east, north), m/s.
    pub fn velocity_enu_mps(&self) -> [f64; 2] {
        let heading = self.pose.heading_deg.to_radians();
        [
            self.speed_mps * heading.sin(),
            self.speed_mps * heading.cos(),
        ]
    }

    /// Where the ship is at `t_s` on this course.
    pub fn pose_at(&self, t_s: f64) -> ShipPose {
        let run = self.speed_mps * (t_s - self.t_s);
        let heading = self.pose.heading_deg.to_radians();
        ShipPose {
            x_east_m: self.pose.x_east_m + run * heading.sin(),
            y_north_m: self.pose.y_north_m + run * heading.cos(),
            heading_deg: self.pose.heading_deg,
        }
    }
}

/// One second-order mode: natural angular frequency and damping ratio.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Mode {
    omega: f64,
    zeta: f64,
}

impl Mode {
    fn new(period_s: f64, zeta: f64) -> Mode {
        Mode {
            omega: std::f64::consts::TAU / period_s,
            zeta,
        }
    }

    fn acceleration(&self, x: f64, v: f64, u: f64) -> f64 {
        self.omega * self.omega * (u - x) - 2.0 * self.zeta * self.omega * v
    }

    /// One classical Runge–Kutta step of length `h` with the input linear from `u0` to `u1`.
    fn step(&self, x: f64, v: f64, u0: f64, u1: f64, h: f64) -> (f64, f64) {
        let um = 0.5 * (u0 + u1);
        let k1x = v;
        let k1v = self.acceleration(x, v, u0);
        let k2x = v + 0.5 * h * k1v;
        let k2v = self.acceleration(x + 0.5 * h * k1x, v + 0.5 * h * k1v, um);
        let k3x = v + 0.5 * h * k2v;
        let k3v = self.acceleration(x + 0.5 * h * k2x, v + 0.5 * h * k2v, um);
        let k4x = v + h * k3v;
        let k4v = self.acceleration(x + h * k3x, v + h * k3v, u1);
        (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }
}

/// The motion model of one hull: waterplane sample points with their plane-fit weights, the
/// three modes and the history window.
#[derive(Clone, Debug, PartialEq)]
pub struct ShipMotionModel {
    hull: HullParameters,
    /// (forward, starboard) offsets of the waterplane sample points, m.
    points: Vec<[f64; 2]>,
    /// Least-squares weights of each point for (height, slope forward, slope to starboard).
    weights: Vec<[f64; 3]>,
    /// Heave, pitch, roll.
    modes: [Mode; 3],
    window_steps: i64,
}

impl ShipMotionModel {
    /// The model of a hull.
    pub fn new(hull: HullParameters) -> ShipMotionModel {
        let (points, weights) = waterplane(hull.length_m, hull.beam_m);
        let modes = [
            Mode::new(hull.heave_period_s(), hull.heave_damping),
            Mode::new(hull.pitch_period_s(), hull.pitch_damping),
            Mode::new(hull.roll_period_s(), hull.roll_damping),
        ];
        let slowest = modes
            .iter()
            .map(|m| 1.0 / (m.zeta * m.omega))
            .fold(0.0, f64::max);
        let window_s = (WINDOW_E_FOLDS * slowest).clamp(MIN_WINDOW_S, MAX_WINDOW_S);
        // Between 1200 and 12 000 steps.
        let window_steps = (window_s / MOTION_STEP_S).ceil() as i64;
        ShipMotionModel {
            hull,
            points,
            weights,
            modes,
            window_steps,
        }
    }

    /// The hull.
    pub fn hull(&self) -> &HullParameters {
        &self.hull
    }

    /// How much sea history one motion uses, s.
    pub fn window_s(&self) -> f64 {
        self.window_steps as f64 * MOTION_STEP_S
    }

    /// The wave-following attitude of the ship at `pose` at `t_s`: the plane fitted to the sea
    /// over the waterplane (no dynamics). `sea_height(x_east_m, y_north_m, t_s)` gives the sea
    /// surface height in metres; a non-finite height or pose is refused.
    pub fn equilibrium(
        &self,
        sea_height: impl Fn(f64, f64, f64) -> f64,
        pose: ShipPose,
        t_s: f64,
    ) -> Result<ShipMotion, SeaError> {
        let [a, b, c] = self.fit(&sea_height, pose, t_s)?;
        Ok(attitude([a, b, c]))
    }

    /// The motion at `t_s` (|t| <= 10⁹ s) of a ship following `track` (its pose at any past
    /// time) on the sea `sea_height(x_east_m, y_north_m, t_s)`: a pure function of the sea,
    /// the track over the last [`ShipMotionModel::window_s`] seconds and `t_s`.
    pub fn motion_at(
        &self,
        sea_height: impl Fn(f64, f64, f64) -> f64,
        track: impl Fn(f64) -> ShipPose,
        t_s: f64,
    ) -> Result<ShipMotion, SeaError> {
        let t = checked("t_s", t_s, -MAX_TIME_S, MAX_TIME_S, "-1e9..=1e9 s")?;
        let (k0, k1) = self.grid(t);
        let mut samples = Vec::with_capacity((k1 - k0 + 1) as usize);
        for k in k0..=k1 {
            let tau = grid_time(k);
            samples.push(self.fit(&sea_height, track(tau), tau)?);
        }
        let now = self.fit(&sea_height, track(t), t)?;
        Ok(self.integrate(&samples, k1, t, now))
    }

    /// [`ShipMotionModel::motion_at`] for a ship on a straight course.
    pub fn motion_on_course(
        &self,
        sea_height: impl Fn(f64, f64, f64) -> f64,
        course: &StraightCourse,
        t_s: f64,
    ) -> Result<ShipMotion, SeaError> {
        self.motion_at(sea_height, |tau| course.pose_at(tau), t_s)
    }

    /// First and last grid indices of the window ending at `t`.
    fn grid(&self, t: f64) -> (i64, i64) {
        let k1 = (t / MOTION_STEP_S).floor() as i64;
        (k1 - self.window_steps, k1)
    }

    /// The plane fitted to the sea over the waterplane: (height, slope forward, slope to
    /// starboard).
    fn fit(
        &self,
        sea_height: &impl Fn(f64, f64, f64) -> f64,
        pose: ShipPose,
        t: f64,
    ) -> Result<[f64; 3], SeaError> {
        for (name, value) in [
            ("pose x_east_m", pose.x_east_m),
            ("pose y_north_m", pose.y_north_m),
            ("pose heading_deg", pose.heading_deg),
        ] {
            checked(name, value, -1.0e7, 1.0e7, "-1e7..=1e7")?;
        }
        let heading = pose.heading_deg.to_radians();
        let (s, c) = heading.sin_cos();
        // Forward (sin ψ, cos ψ) and starboard (cos ψ, −sin ψ) in (east, north).
        let mut fit = [0.0; 3];
        for (p, w) in self.points.iter().zip(&self.weights) {
            let x = pose.x_east_m + p[0] * s + p[1] * c;
            let y = pose.y_north_m + p[0] * c - p[1] * s;
            let h = sea_height(x, y, t);
            if !h.is_finite() {
                return Err(SeaError::OutOfRange {
                    name: "sea height",
                    range: "finite",
                    value: h,
                });
            }
            for (f, wi) in fit.iter_mut().zip(w) {
                *f += wi * h;
            }
        }
        Ok(fit)
    }

    /// Runs the three oscillators over the grid samples (`samples[i]` at index
    /// `k1 − len + 1 + i`), from rest on the first, then a partial step to `t` with the fit
    /// `now` there.
    fn integrate(&self, samples: &[[f64; 3]], k1: i64, t: f64, now: [f64; 3]) -> ShipMotion {
        let mut out = [0.0; 3];
        let Some(first) = samples.first() else {
            return attitude(now);
        };
        let last = samples[samples.len() - 1];
        let tail = t - grid_time(k1);
        for (m, mode) in self.modes.iter().enumerate() {
            let (mut x, mut v) = (first[m], 0.0);
            for pair in samples.windows(2) {
                (x, v) = mode.step(x, v, pair[0][m], pair[1][m], MOTION_STEP_S);
            }
            (x, _) = mode.step(x, v, last[m], now[m], tail);
            out[m] = x;
        }
        attitude(out)
    }
}

/// The time of grid index `k`, s.
fn grid_time(k: i64) -> f64 {
    k as f64 * MOTION_STEP_S
}

/// Heave, pitch and roll from the fitted plane (or oscillator states in the same units).
fn attitude([a, b, c]: [f64; 3]) -> ShipMotion {
    ShipMotion {
        heave_m: a,
        pitch_deg: b.atan().to_degrees(),
        roll_deg: -c.atan().to_degrees(),
    }
}

/// The waterplane's sample points (forward, starboard), m, and their least-squares weights
/// for the plane `a + b ξ + c η`, each point weighted by the local breadth of the waterplane.
fn waterplane(length_m: f64, beam_m: f64) -> (Vec<[f64; 2]>, Vec<[f64; 3]>) {
    let cells = along_cells(length_m);
    // Row offsets along a cell: the centre row at ½, the next rows at ½ + φ/2π and the outer
    // ones at ½ − φ/2π with cos φ = −¼, so that 2 e^{iφ} + 2 e^{−iφ} + 1 = 0.
    let shift = (-0.25f64).acos() / std::f64::consts::TAU;
    let offsets = [0.5 - shift, 0.5 + shift, 0.5, 0.5 + shift, 0.5 - shift];
    let cell = length_m / cells as f64;
    let mut points = Vec::with_capacity(cells * ACROSS_ROWS);
    let mut breadths = Vec::with_capacity(cells * ACROSS_ROWS);
    for (row, offset) in offsets.iter().enumerate() {
        let eta = beam_m * (row as f64 - 2.0) / ACROSS_ROWS as f64;
        for i in 0..cells {
            let xi = -0.5 * length_m + cell * (i as f64 + offset);
            let u = 2.0 * xi / length_m;
            points.push([xi, eta]);
            breadths.push(1.0 - u * u * u * u);
        }
    }
    // Weighted normal equations M = Σ b v vᵀ with v = (1, ξ, η); weights b M⁻¹ v.
    let mut m = [[0.0; 3]; 3];
    for (p, b) in points.iter().zip(&breadths) {
        let v = [1.0, p[0], p[1]];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, e) in row.iter_mut().enumerate() {
                *e += b * v[r] * v[c];
            }
        }
    }
    let inv = inverse3(m);
    let weights = points
        .iter()
        .zip(&breadths)
        .map(|(p, b)| {
            let v = [1.0, p[0], p[1]];
            let mut w = [0.0; 3];
            for (r, wr) in w.iter_mut().enumerate() {
                *wr = b * (inv[r][0] * v[0] + inv[r][1] * v[1] + inv[r][2] * v[2]);
            }
            w
        })
        .collect();
    (points, weights)
}

/// Cells along each waterplane row for a hull `length_m` long: one per 2.5 m, 16..=64.
fn along_cells(length_m: f64) -> usize {
    // In 16..=64 after the clamp, so the cast is exact.
    (length_m / ALONG_CELL_M).round().clamp(16.0, 64.0) as usize
}

/// The inverse of a 3×3 matrix by cofactors (the waterplane's normal matrix, never
/// singular: its points span a plane).
fn inverse3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cof =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let c = [
        [cof(1, 2, 1, 2), -cof(1, 2, 0, 2), cof(1, 2, 0, 1)],
        [-cof(0, 2, 1, 2), cof(0, 2, 0, 2), -cof(0, 2, 0, 1)],
        [cof(0, 1, 1, 2), -cof(0, 1, 0, 2), cof(0, 1, 0, 1)],
    ];
    let det = m[0][0] * c[0][0] + m[0][1] * c[0][1] + m[0][2] * c[0][2];
    // Transposed cofactors over the determinant.
    let mut inv = [[0.0; 3]; 3];
    for (r, row) in inv.iter_mut().enumerate() {
        for (col, e) in row.iter_mut().enumerate() {
            *e = c[col][r] / det;
        }
    }
    inv
}

/// [`ShipMotionModel::motion_at`] with the waterplane fits of the grid points cached between
/// calls: the same numbers bit for bit, at the cost of a few sea samples per frame.
///
/// The cache assumes the sea and the track at past times do not change between calls (the
/// same sea closure, and a recorded track or the same [`StraightCourse`]); call
/// [`ShipMotionTracker::clear`] when they do, e.g. after a course change given as a new
/// `StraightCourse`. Going back in time before the cached window recomputes it.
#[derive(Clone, Debug)]
pub struct ShipMotionTracker {
    model: ShipMotionModel,
    first: i64,
    fits: VecDeque<[f64; 3]>,
}

impl ShipMotionTracker {
    /// A tracker with an empty cache.
    pub fn new(model: ShipMotionModel) -> ShipMotionTracker {
        ShipMotionTracker {
            model,
            first: 0,
            fits: VecDeque::new(),
        }
    }

    /// The motion model.
    pub fn model(&self) -> &ShipMotionModel {
        &self.model
    }

    /// Forgets the cached sea.
    pub fn clear(&mut self) {
        self.fits.clear();
    }

    /// The motion at `t_s`, equal to [`ShipMotionModel::motion_at`] with the same sea and
    /// track.
    pub fn motion_at(
        &mut self,
        sea_height: impl Fn(f64, f64, f64) -> f64,
        track: impl Fn(f64) -> ShipPose,
        t_s: f64,
    ) -> Result<ShipMotion, SeaError> {
        let t = checked("t_s", t_s, -MAX_TIME_S, MAX_TIME_S, "-1e9..=1e9 s")?;
        let (k0, k1) = self.model.grid(t);
        let end = self.first + self.fits.len() as i64;
        if self.fits.is_empty() || k0 < self.first || k0 > end {
            self.fits.clear();
            self.first = k0;
        }
        while self.first < k0 {
            self.fits.pop_front();
            self.first += 1;
        }
        self.fits.truncate((k1 - k0 + 1) as usize);
        let mut k = self.first + self.fits.len() as i64;
        while k <= k1 {
            let tau = grid_time(k);
            let fit = self.model.fit(&sea_height, track(tau), tau)?;
            self.fits.push_back(fit);
            k += 1;
        }
        let now = self.model.fit(&sea_height, track(t), t)?;
        Ok(self
            .model
            .integrate(self.fits.make_contiguous(), k1, t, now))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::G_MPS2;

    /// Long-crested waves (amplitude m, wavelength m, direction of travel deg true, phase).
    fn sea(waves: Vec<(f64, f64, f64, f64)>) -> impl Fn(f64, f64, f64) -> f64 {
        move |x, y, t| {
            waves
                .iter()
                .map(|&(a, lambda, dir, phase)| {
                    let k = std::f64::consts::TAU / lambda;
                    let w = (G_MPS2 * k).sqrt();
                    let d = dir.to_radians();
                    a * (k * (x * d.sin() + y * d.cos()) - w * t + phase).cos()
                })
                .sum()
        }
    }

    fn rms(values: &[f64]) -> f64 {
        (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
    }

    /// Heave, pitch and roll series at `n` times from `t0` every `dt`.
    pub(crate) fn series(
        hull: HullParameters,
        sea: &impl Fn(f64, f64, f64) -> f64,
        course: StraightCourse,
        t0: f64,
        dt: f64,
        n: usize,
    ) -> [Vec<f64>; 3] {
        let mut tracker = ShipMotionTracker::new(ShipMotionModel::new(hull));
        let mut out = [Vec::new(), Vec::new(), Vec::new()];
        for i in 0..n {
            let t = t0 + dt * i as f64;
            let m = tracker
                .motion_at(sea, |tau| course.pose_at(tau), t)
                .unwrap();
            out[0].push(m.heave_m);
            out[1].push(m.pitch_deg);
            out[2].push(m.roll_deg);
        }
        out
    }

    fn mixed(scale: f64) -> Vec<(f64, f64, f64, f64)> {
        vec![
            (0.5 * scale, 80.0, 200.0, 0.0),
            (0.3 * scale, 120.0, 170.0, 1.0),
            (0.2 * scale, 60.0, 250.0, 2.0),
        ]
    }

    #[test]
    fn periods_of_the_three_classes() {
        let d = HullParameters::DESTROYER;
        assert!(
            (d.roll_period_s() - 11.28).abs() < 0.01,
            "{}",
            d.roll_period_s()
        );
        assert!((d.heave_period_s() - 5.86).abs() < 0.01);
        assert_eq!(d.pitch_period_s(), d.heave_period_s());
        let m = HullParameters::MERCHANT;
        assert!(
            (m.roll_period_s() - 15.47).abs() < 0.01,
            "{}",
            m.roll_period_s()
        );
        let p = HullParameters::PATROL_CRAFT;
        assert!(
            (p.roll_period_s() - 5.52).abs() < 0.01,
            "{}",
            p.roll_period_s()
        );
        for hull in [d, m, p] {
            let again =
                HullParameters::new(hull.length_m(), hull.beam_m(), hull.draft_m(), hull.gm_m())
                    .unwrap();
            assert_eq!(again, hull);
            let w = ShipMotionModel::new(hull).window_s();
            assert!(
                (MIN_WINDOW_S..=MAX_WINDOW_S + MOTION_STEP_S).contains(&w),
                "{w}"
            );
        }
    }

    #[test]
    fn a_level_sea_gives_no_motion_and_a_slope_gives_the_attitude() {
        let model = ShipMotionModel::new(HullParameters::DESTROYER);
        let course = StraightCourse::new(0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        let calm = model
            .motion_on_course(|_, _, _| 0.0, &course, 100.0)
            .unwrap();
        assert_eq!(calm, ShipMotion::default());
        // Heading north: the sea rising 1 % to the north raises the bow; rising to the east
        // (starboard) lifts the starboard side, a roll to port (negative).
        let ahead = model
            .equilibrium(|_, y, _| 0.3 + 0.01 * y, course.pose_at(0.0), 0.0)
            .unwrap();
        assert!((ahead.heave_m - 0.3).abs() < 1e-12, "{ahead:?}");
        assert!((ahead.pitch_deg - 0.01f64.atan().to_degrees()).abs() < 1e-9);
        assert!(ahead.roll_deg.abs() < 1e-9);
        let abeam = model
            .equilibrium(|x, _, _| 0.01 * x, course.pose_at(0.0), 0.0)
            .unwrap();
        assert!(
            (abeam.roll_deg + 0.01f64.atan().to_degrees()).abs() < 1e-9,
            "{abeam:?}"
        );
        assert!(abeam.pitch_deg.abs() < 1e-9);
        // A steady slope, the motion settles on it.
        let settled = model
            .motion_on_course(|x, y, _| 0.01 * (y - x), &course, 500.0)
            .unwrap();
        assert!(
            (settled.pitch_deg - ahead.pitch_deg).abs() < 1e-6,
            "{settled:?}"
        );
        assert!(
            (settled.roll_deg - abeam.roll_deg.abs()).abs() < 1e-6,
            "{settled:?}"
        );
        // Sampled where the ship is: heading 090 at 10 m/s on a sea rising to the east.
        let moving = StraightCourse::new(100.0, 0.0, 90.0, 10.0, 0.0).unwrap();
        let eq = model
            .equilibrium(|x, _, _| 0.001 * x, moving.pose_at(20.0), 20.0)
            .unwrap();
        assert!((eq.heave_m - 0.3).abs() < 1e-9, "{eq:?}");
    }

    #[test]
    fn a_rougher_sea_moves_the_ship_more() {
        let course = StraightCourse::new(0.0, 0.0, 10.0, 5.0, 0.0).unwrap();
        let calm = series(
            HullParameters::DESTROYER,
            &sea(mixed(0.5)),
            course,
            200.0,
            0.25,
            240,
        );
        let rough = series(
            HullParameters::DESTROYER,
            &sea(mixed(2.0)),
            course,
            200.0,
            0.25,
            240,
        );
        for mode in 0..3 {
            let (c, r) = (rms(&calm[mode]), rms(&rough[mode]));
            assert!(c > 0.0 && r > 2.0 * c, "mode {mode}: calm {c}, rough {r}");
        }
    }

    #[test]
    fn waves_shorter_than_the_hull_are_filtered() {
        let hull = HullParameters::DESTROYER;
        let model = ShipMotionModel::new(hull);
        // Head seas: waves travelling south onto a ship heading north, 1 m amplitude.
        let course = StraightCourse::new(0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        let short = sea(vec![(1.0, 5.0, 180.0, 0.3)]);
        let long = sea(vec![(1.0, 300.0, 180.0, 0.3)]);
        // The waterplane alone.
        let eq = |s: &dyn Fn(f64, f64, f64) -> f64| {
            let (mut h, mut p) = (Vec::new(), Vec::new());
            for i in 0..200 {
                let t = 0.1 * i as f64;
                let m = model.equilibrium(s, course.pose_at(t), t).unwrap();
                h.push(m.heave_m);
                p.push(m.pitch_deg);
            }
            (rms(&h), rms(&p))
        };
        let (hs, ps) = eq(&short);
        let (hl, pl) = eq(&long);
        assert!(
            hs < 0.01 * hl && ps < 0.01 * pl,
            "heave {hs} vs {hl}, pitch {ps} vs {pl}"
        );
        // With the dynamics.
        let s = series(hull, &short, course, 300.0, 0.2, 150);
        let l = series(hull, &long, course, 300.0, 0.2, 150);
        for mode in 0..2 {
            let (rs, rl) = (rms(&s[mode]), rms(&l[mode]));
            assert!(rs < 0.01 * rl, "mode {mode}: short {rs}, long {rl}");
        }
    }

    #[test]
    fn the_motion_is_a_function_of_sea_track_and_time() {
        let model = ShipMotionModel::new(HullParameters::PATROL_CRAFT);
        let waves = sea(mixed(1.0));
        let course = StraightCourse::new(50.0, -20.0, 135.0, 8.0, 10.0).unwrap();
        let track = |tau| course.pose_at(tau);
        let t = 123.456;
        let a = model.motion_at(&waves, track, t).unwrap();
        let b = model.motion_at(&waves, track, t).unwrap();
        let bits = |m: ShipMotion| {
            [
                m.heave_m.to_bits(),
                m.pitch_deg.to_bits(),
                m.roll_deg.to_bits(),
            ]
        };
        assert_eq!(bits(a), bits(b));
        assert!(a.heave_m != 0.0 && a.pitch_deg != 0.0 && a.roll_deg != 0.0);
        // Two IGs at different frame rates agree with each other and with the pure function
        // at the times they share.
        let mut fast = ShipMotionTracker::new(model.clone());
        let mut slow = ShipMotionTracker::new(model.clone());
        for i in 0..600 {
            let t = 100.0 + f64::from(i) / 60.0;
            let f = fast.motion_at(&waves, track, t).unwrap();
            if i % 4 == 0 {
                let s = slow.motion_at(&waves, track, t).unwrap();
                assert_eq!(bits(f), bits(s), "t {t}");
            }
            if i % 97 == 0 {
                let pure = model.motion_at(&waves, track, t).unwrap();
                assert_eq!(bits(f), bits(pure), "t {t}");
            }
        }
        // Jumping ahead and going back in time are fine too.
        let ahead = fast.motion_at(&waves, track, t).unwrap();
        assert_eq!(bits(ahead), bits(a));
        let back = fast.motion_at(&waves, track, 100.5).unwrap();
        let pure = model.motion_at(&waves, track, 100.5).unwrap();
        assert_eq!(bits(back), bits(pure));
    }

    #[test]
    fn free_roll_has_the_imo_period() {
        let hull = HullParameters::DESTROYER;
        let c = 0.373 + 0.023 * (18.0 / 5.5) - 0.043 * (150.0 / 100.0);
        let want = 2.0 * c * 18.0 / 1.5f64.sqrt();
        // The sea slopes across the ship until t = 100 s, then falls flat: the ship rolls
        // freely from the heel it had.
        let step = |x: f64, _y: f64, t: f64| if t < 100.0 { 0.05 * x } else { 0.0 };
        let course = StraightCourse::new(0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        let dt = 0.05;
        let [_, _, roll] = series(hull, &step, course, 100.0, dt, 1200);
        assert!(roll[0] < -2.5, "{}", roll[0]);
        let mut ups = Vec::new();
        for i in 1..roll.len() {
            if roll[i - 1] < 0.0 && roll[i] >= 0.0 {
                let u = -roll[i - 1] / (roll[i] - roll[i - 1]);
                ups.push(100.0 + dt * (i as f64 - 1.0 + u));
            }
        }
        assert!(ups.len() >= 4, "{ups:?}");
        let period = (ups[3] - ups[0]) / 3.0;
        assert!(
            (period - want).abs() < 0.05 * want,
            "period {period}, want {want}"
        );
        // And it decays: lightly damped.
        let peak = |from: usize| roll[from..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak(600) < peak(0) && peak(600) > 0.2 * peak(0));
    }

    #[test]
    fn bad_input_is_refused() {
        assert!(HullParameters::new(f64::NAN, 18.0, 5.0, 1.0).is_err());
        assert!(HullParameters::new(150.0, -1.0, 5.0, 1.0).is_err());
        assert!(HullParameters::new(150.0, 18.0, 0.0, 1.0).is_err());
        assert!(HullParameters::new(150.0, 18.0, 5.0, 0.0).is_err());
        assert!(HullParameters::new(150.0, 18.0, 5.0, f64::INFINITY).is_err());
        assert!(HullParameters::new(10.0, 12.0, 2.0, 1.0).is_err());
        assert!(HullParameters::new(600.0, 18.0, 5.0, 1.0).is_err());
        assert!(HullParameters::DESTROYER
            .with_damping(0.0, 0.3, 0.3)
            .is_err());
        assert!(HullParameters::DESTROYER
            .with_damping(0.1, 1.5, 0.3)
            .is_err());
        assert!(HullParameters::DESTROYER
            .with_damping(0.1, 0.3, f64::NAN)
            .is_err());
        assert!(StraightCourse::new(0.0, 0.0, 0.0, -1.0, 0.0).is_err());
        assert!(StraightCourse::new(0.0, f64::NAN, 0.0, 1.0, 0.0).is_err());
        let model = ShipMotionModel::new(HullParameters::PATROL_CRAFT);
        let course = StraightCourse::new(0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        assert!(model
            .motion_on_course(|_, _, _| 0.0, &course, f64::NAN)
            .is_err());
        assert!(model
            .motion_on_course(|_, _, _| f64::NAN, &course, 1.0)
            .is_err());
        let bad_track = |_| ShipPose {
            x_east_m: f64::INFINITY,
            ..ShipPose::default()
        };
        assert!(model.motion_at(|_, _, _| 0.0, bad_track, 1.0).is_err());
        let mut tracker = ShipMotionTracker::new(model);
        assert!(tracker
            .motion_at(|_, _, _| f64::NAN, |tau| course.pose_at(tau), 1.0)
            .is_err());
        assert!(tracker
            .motion_at(|_, _, _| 0.0, |tau| course.pose_at(tau), 1.0)
            .is_ok());
    }
}
