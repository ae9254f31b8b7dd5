//! Ships' motions in a seaway in closed form: every wave's share through the hull's filter and
//! the ship's own natural periods (the frequency-domain method of seakeeping, response
//! amplitude operators: St Denis and Pierson 1953; SNAME *Principles of Naval Architecture*
//! vol. III, Motions in Waves).
//!
//! Algorithm. The sea is a sum of linear waves `Re(A e^(i (k·x − ω t)))`
//! ([`SeaSurface::linear_waves`]). For each wave, with the ship heading ψ (ξ forward, η to
//! starboard; `k_ξ`, `k_η` the wave vector's components) and making good the velocity `v`:
//!
//! 1. **The hull's filter**: the Froude–Krylov force and moments of a wall-sided hull on a
//!    rectangular waterplane `L × B` (`l = L / 2`, `w = B / 2`), normalised so a wave much
//!    longer than the hull passes whole:
//!    - heave (the waterplane's mean height) `F_z = sinc(k_ξ l) sinc(k_η w)`;
//!    - pitch (its slope along the hull, `∫ξh / ∫ξ²`) `F_θ = i k_ξ G(k_ξ l) sinc(k_η w)`;
//!    - roll (its slope across, `∫ηh / ∫η²`) `F_φ = i k_η G(k_η w) sinc(k_ξ l)`;
//!
//!    `sinc x = sin x / x`, `G(x) = 3 (sin x − x cos x) / x³`. Waves shorter than the hull
//!    along it, or than the beam across it, cancel over the waterplane.
//! 2. **Depth**: a wave's pressure decays as `e^(−k z)` below the surface; each share is
//!    multiplied by `e^(−k d / 2)`, the pressure at half the draft `d` (the Smith effect).
//! 3. **The ship's dynamics**: heave, pitch and roll are each a linear second-order oscillator
//!    driven by its share, `ẍ + 2ζω_n ẋ + ω_n² x = ω_n² x_wave`. Its steady response at the
//!    encounter frequency `ω_e = ω − k·v` is the share times
//!    `H(ω_e) = ω_n² / (ω_n² − ω_e² − 2iζ ω_n ω_e)`: quasi-static for long waves, amplified up to
//!    `1 / 2ζ` at the natural period, filtered when the waves meet the ship faster than it can
//!    follow. The periods and damping ratios are [`HullParameters`]': roll `2 C B / √GM` from
//!    the beam (the IMO weather criterion's formula), heave and pitch `2.5 √d`.
//! 4. **The motion** at time `t` of the ship at `x`: heave `Σ Re(C_z E)`, the slopes
//!    `b = Σ Re(C_θ E)` and `c = Σ Re(C_φ E)` with `E = e^(i (k·x − ω t))` and
//!    `C = A F e^(−k d / 2) H`; pitch `atan b` (bow up), roll `−atan c` (starboard down). With
//!    `x` the ship's present position the phase turns at the encounter frequency as it moves.
//!
//! The coefficients depend on the heading and the velocity, not on the position or the time:
//! they are made once per (sea, hull, heading, velocity) ([`SeawayResponse::new`]; the
//! [`ResponseCache`] quantises the heading to 1° and the velocity to 0.25 m/s), keeping only the
//! waves that matter (a wave whose share of each motion's variance is below 10⁻⁶ of the total is
//! left out: at most 1 % of the variance for 10 000 waves), and then evaluated for any position
//! and time in microseconds. The motion is a pure function of (sea, hull, heading, velocity,
//! position, time): every IG that shares them draws the same ship, from its first frame (the
//! steady state: no start-up transient; only a change, 5. below, leaves a transient to keep). [`crate::motion`] integrates
//! the same oscillators in time; the two agree (the tests).
//!
//! 5. **Changes** ([`ShipRide`]): when the ship turns, changes speed or the sea changes at
//!    `t₀`, the oscillators' states (heave, the two slopes, and their rates, [`ModeStates`])
//!    at `t₀` differ from the new steady state's. The difference rings down as each mode's free
//!    motion `e^(−ζω_n τ) (x₀ cos ω_d τ + (v₀ + ζω_n x₀)/ω_d · sin ω_d τ)` ([`MotionTransient`]),
//!    which with the new steady state is the exact solution of the oscillator whose forcing
//!    switched at `t₀`. A patrol craft rolling at resonance that turns into the sea: the ride
//!    follows the time-domain integration to 0.07° rms over the next three roll periods, where
//!    the new steady state alone is off by 7.7° (the tests).
//!
//! Limits: linear, uncoupled modes (no parametric roll, nonlinear righting arm, slamming or
//! green water); a change of course or speed is a step between two steady states (a turn is
//! taken as the sequence of headings the IG sees, each a step; the transient follows each);
//! a rectangular waterplane (real
//! ones taper, letting a little less through of the waves about the ship's length); one depth
//! factor for the three modes; the linear sea (the choppy crests' horizontal displacement is
//! not felt); added mass and damping constant with frequency; no current (the velocity is
//! through the water).

use std::collections::HashMap;
use std::sync::Arc;

use rustfft::num_complex::Complex64;

use crate::motion::{HullParameters, ShipMotion};
use crate::surface::{LinearWave, SeaSurface};

/// Waves whose share of each motion's variance is below this fraction of the total are left out.
const NEGLIGIBLE_SHARE: f64 = 1.0e-6;

/// Waves whose bound is above this fraction of the bounds' total are made first; their
/// variance decides which of the others can matter.
const LEADING_SHARE: f64 = 1.0e-4;

/// The cache's heading step, degrees.
pub const HEADING_STEP_DEG: f64 = 1.0;

/// The cache's velocity step (each of east and north), m/s.
pub const VELOCITY_STEP_MPS: f64 = 0.25;

/// Speeds above this are taken as this, m/s.
const MAX_SPEED_MPS: f64 = 40.0;

/// Responses kept before the cache starts afresh.
const MAX_CACHED: usize = 512;

/// One wave's share of the three motions.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Term {
    k_rad_m: [f64; 2],
    omega_rad_s: f64,
    /// Heave (m), the slope along the hull and the slope across it.
    heave: Complex64,
    pitch: Complex64,
    roll: Complex64,
}

/// A hull's response to a sea at one heading and velocity.
#[derive(Clone, Debug, PartialEq)]
pub struct SeawayResponse {
    terms: Vec<Term>,
}

/// `sin x / x`.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1.0e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// `3 (sin x − x cos x) / x³`: `∫ s e^(ixs) ds / (i x ∫ s² ds)` over `s` in `[-1, 1]`.
fn first_moment(x: f64) -> f64 {
    if x.abs() < 1.0e-2 {
        1.0 - x * x / 10.0
    } else {
        3.0 * (x.sin() - x * x.cos()) / (x * x * x)
    }
}

/// `∫₀¹ sⁿ cos(xs) ds` and `∫₀¹ sⁿ sin(xs) ds` for `n` in `0..=5`: by their Taylor series for
/// `|x| < 0.5` (eight terms: below 10⁻¹⁵), else by the recurrence
/// `Cₙ = sin x / x − n Sₙ₋₁ / x`, `Sₙ = −cos x / x + n Cₙ₋₁ / x` (its errors grow by `n / x` a
/// step: at most 120 / 0.5⁵ ≈ 4000 ulp, about 10⁻¹²).
fn moments(x: f64) -> ([f64; 6], [f64; 6]) {
    let (mut c, mut s) = ([0.0; 6], [0.0; 6]);
    if x.abs() < 0.5 {
        // term = (−1)ᵐ x²ᵐ / (2m)!, for C; times x / (2m + 1) for S.
        let mut term = 1.0;
        for m in 0..8_u32 {
            let (even, odd) = (f64::from(2 * m), f64::from(2 * m + 1));
            let odd_term = term * x / odd;
            for n in 0..6_u32 {
                let n_f = f64::from(n);
                c[n as usize] += term / (n_f + even + 1.0);
                s[n as usize] += odd_term / (n_f + odd + 1.0);
            }
            term = -odd_term * x / (odd + 1.0);
        }
    } else {
        let (sin, cos) = x.sin_cos();
        c[0] = sin / x;
        s[0] = (1.0 - cos) / x;
        for n in 1..6 {
            #[expect(clippy::cast_precision_loss, reason = "n is at most 5")]
            let n_f = n as f64;
            c[n] = sin / x - n_f * s[n - 1] / x;
            s[n] = -cos / x + n_f * c[n - 1] / x;
        }
    }
    (c, s)
}

/// The filter along the hull of a waterplane whose breadth tapers as `1 − s⁴` (`s = 2ξ / L`,
/// area coefficient 0.8), for a wave with `x = k_ξ L / 2`: its mean
/// `∫ w e^(ixs) ds / ∫ w ds` and its slope `∫ s w e^(ixs) ds / (i x ∫ s² w ds)`, both 1 for
/// a long wave.
fn tapered(x: f64) -> (f64, f64) {
    let (c, s) = moments(x.abs());
    let mean = (c[0] - c[4]) / 0.8;
    // ∫ s² (1 − s⁴) over [0, 1] = 4 / 21; the slope's sign follows x's.
    let slope = if x.abs() < 1.0e-6 {
        1.0
    } else {
        (s[1] - s[5]) / (x.abs() * 4.0 / 21.0)
    };
    (mean, slope)
}

/// The square of the largest gain of a second-order oscillator with damping ratio `zeta`.
fn peak_gain(zeta: f64) -> f64 {
    if zeta < std::f64::consts::FRAC_1_SQRT_2 {
        1.0 / (2.0 * zeta * (1.0 - zeta * zeta).sqrt())
    } else {
        1.0
    }
    .powi(2)
}

/// Twice each motion's variance over `terms`: `Σ |C|²` for heave, pitch and roll.
fn variances(terms: &[Term]) -> [f64; 3] {
    terms.iter().fold([0.0; 3], |sum, t| {
        [
            sum[0] + t.heave.norm_sqr(),
            sum[1] + t.pitch.norm_sqr(),
            sum[2] + t.roll.norm_sqr(),
        ]
    })
}

/// The steady response of `ẍ + 2ζω_n ẋ + ω_n² x = ω_n² f` to `f = Re(e^(−iωt))`.
fn oscillator(period_s: f64, zeta: f64, omega_rad_s: f64) -> Complex64 {
    let omega_n = std::f64::consts::TAU / period_s;
    let omega_n2 = omega_n * omega_n;
    omega_n2
        / Complex64::new(
            omega_n2 - omega_rad_s * omega_rad_s,
            -2.0 * zeta * omega_n * omega_rad_s,
        )
}

impl SeawayResponse {
    /// The response of `hull` heading `heading_deg` (true) and making good
    /// `velocity_enu_mps` (east, north; its speed taken as at most 40 m/s) to `waves`.
    /// Non-finite heading or velocity are taken as 0.
    pub fn new(
        hull: &HullParameters,
        waves: &[LinearWave],
        heading_deg: f64,
        velocity_enu_mps: [f64; 2],
    ) -> SeawayResponse {
        SeawayResponse::with_shares(
            hull,
            waves,
            heading_deg,
            velocity_enu_mps,
            [LEADING_SHARE, NEGLIGIBLE_SHARE],
        )
    }

    /// [`SeawayResponse::new`] with the shares of the variance above which a wave is made
    /// first and below which it is left out.
    fn with_shares(
        hull: &HullParameters,
        waves: &[LinearWave],
        heading_deg: f64,
        velocity_enu_mps: [f64; 2],
        [leading_share, negligible_share]: [f64; 2],
    ) -> SeawayResponse {
        let heading = if heading_deg.is_finite() {
            heading_deg.to_radians()
        } else {
            0.0
        };
        let (sin_h, cos_h) = heading.sin_cos();
        let mut velocity = velocity_enu_mps.map(|v| if v.is_finite() { v } else { 0.0 });
        let speed = velocity[0].hypot(velocity[1]);
        if speed > MAX_SPEED_MPS {
            velocity = velocity.map(|v| v * MAX_SPEED_MPS / speed);
        }
        let (half_length_m, half_beam_m) = (0.5 * hull.length_m(), 0.5 * hull.beam_m());
        let term = |wave: &LinearWave, depth: f64| {
            let [kx, ky] = wave.k_rad_m;
            // Forward (sin ψ, cos ψ) and starboard (cos ψ, −sin ψ), east and north.
            let k_along = kx * sin_h + ky * cos_h;
            let k_across = kx * cos_h - ky * sin_h;
            let (x_along, x_across) = (k_along * half_length_m, k_across * half_beam_m);
            let (along_mean, along_slope) = tapered(x_along);
            let amplitude = Complex64::new(wave.amplitude_m[0], wave.amplitude_m[1]) * depth;
            let encounter = wave.omega_rad_s - (kx * velocity[0] + ky * velocity[1]);
            let i = Complex64::i();
            Term {
                k_rad_m: wave.k_rad_m,
                omega_rad_s: wave.omega_rad_s,
                heave: amplitude
                    * (along_mean * sinc(x_across))
                    * oscillator(hull.heave_period_s(), hull.heave_damping(), encounter),
                pitch: amplitude
                    * i
                    * (k_along * along_slope * sinc(x_across))
                    * oscillator(hull.pitch_period_s(), hull.pitch_damping(), encounter),
                roll: amplitude
                    * i
                    * (k_across * first_moment(x_across) * along_mean)
                    * oscillator(hull.roll_period_s(), hull.roll_damping(), encounter),
            }
        };
        // A bound on each wave's share that does not depend on the heading (the filters are
        // at most 1, the slopes' at most k, the oscillators' gain at most their resonance's):
        // the waves far above the rest are made first, and the others only when their bound
        // is not negligible against those.
        let gain = [
            peak_gain(hull.heave_damping()),
            peak_gain(hull.pitch_damping()),
            peak_gain(hull.roll_damping()),
        ];
        let bounds: Vec<([f64; 3], f64)> = waves
            .iter()
            .map(|wave| {
                let k = wave.k_rad_m[0].hypot(wave.k_rad_m[1]);
                let depth = (-0.5 * k * hull.draft_m()).exp();
                let a2 =
                    (wave.amplitude_m[0].powi(2) + wave.amplitude_m[1].powi(2)) * depth * depth;
                (
                    [a2 * gain[0], a2 * k * k * gain[1], a2 * k * k * gain[2]],
                    depth,
                )
            })
            .collect();
        let bound_total = bounds.iter().fold([0.0; 3], |sum, (b, _)| {
            [sum[0] + b[0], sum[1] + b[1], sum[2] + b[2]]
        });
        let large = |b: &[f64; 3], total: &[f64; 3], share: f64| {
            b.iter().zip(total).any(|(b, total)| *b > share * total)
        };
        let mut terms: Vec<Term> = Vec::new();
        let mut made = vec![false; waves.len()];
        for ((wave, (bound, depth)), made) in waves.iter().zip(&bounds).zip(&mut made) {
            if large(bound, &bound_total, leading_share) {
                terms.push(term(wave, *depth));
                *made = true;
            }
        }
        let leading = variances(&terms).map(|v| v * negligible_share);
        for ((wave, (bound, depth)), made) in waves.iter().zip(&bounds).zip(&made) {
            if !made && large(bound, &leading, 1.0) {
                terms.push(term(wave, *depth));
            }
        }
        // Each motion's variance, Σ |C|² / 2; a wave negligible in all three is left out.
        let total = variances(&terms);
        terms.retain(|t| {
            [t.heave, t.pitch, t.roll]
                .iter()
                .zip(total)
                .any(|(c, total)| c.norm_sqr() > negligible_share * total)
        });
        SeawayResponse { terms }
    }

    /// The waves kept.
    pub fn wave_count(&self) -> usize {
        self.terms.len()
    }

    /// The motion of the ship at (`x_east_m`, `y_north_m`) of the sea's frame (its
    /// waterplane's centre) at the sea's time `t_s`.
    pub fn motion_at(&self, x_east_m: f64, y_north_m: f64, t_s: f64) -> ShipMotion {
        ModeStates::motion_of(self.sum::<false>(x_east_m, y_north_m, t_s, [0.0; 2]).value)
    }

    /// The three oscillators' states and their rates for the ship at (`x_east_m`,
    /// `y_north_m`) at `t_s` moving over the ground at `velocity_enu_mps`: the phase of each
    /// wave turns at its encounter frequency `ω − k·v`, so the rate of `Re(C e^(iφ))` is
    /// `Re(i (k·v − ω) C e^(iφ))`.
    pub fn states_at(
        &self,
        x_east_m: f64,
        y_north_m: f64,
        t_s: f64,
        velocity_enu_mps: [f64; 2],
    ) -> ModeStates {
        self.sum::<true>(x_east_m, y_north_m, t_s, velocity_enu_mps)
    }

    /// The terms summed at a place and time: the states, and their rates when `RATES` (the
    /// steady ride each frame needs only the states).
    fn sum<const RATES: bool>(
        &self,
        x_east_m: f64,
        y_north_m: f64,
        t_s: f64,
        velocity_enu_mps: [f64; 2],
    ) -> ModeStates {
        let mut states = ModeStates::default();
        for term in &self.terms {
            let phase =
                term.k_rad_m[0] * x_east_m + term.k_rad_m[1] * y_north_m - term.omega_rad_s * t_s;
            let (sin, cos) = phase.sin_cos();
            for (m, c) in [term.heave, term.pitch, term.roll].into_iter().enumerate() {
                // Re(C e^(iφ)) = C.re cos φ − C.im sin φ.
                states.value[m] += c.re * cos - c.im * sin;
                if RATES {
                    let turn = term.k_rad_m[0] * velocity_enu_mps[0]
                        + term.k_rad_m[1] * velocity_enu_mps[1]
                        - term.omega_rad_s;
                    // Re(i w C e^(iφ)) = −w (C.re sin φ + C.im cos φ).
                    states.rate[m] -= turn * (c.re * sin + c.im * cos);
                }
            }
        }
        states
    }
}

/// The three oscillators' states: heave (m, up), the waterplane's slope along the hull (bow
/// up) and across it (starboard up), with their rates (per second).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ModeStates {
    /// Heave (m), slope along, slope across.
    pub value: [f64; 3],
    /// Their rates: m/s and slope per second.
    pub rate: [f64; 3],
}

impl ModeStates {
    /// Heave, pitch `atan b` and roll `−atan c` from the states `[heave, b, c]`.
    pub fn motion_of([heave, along, across]: [f64; 3]) -> ShipMotion {
        ShipMotion {
            heave_m: heave,
            pitch_deg: along.atan().to_degrees(),
            roll_deg: -across.atan().to_degrees(),
        }
    }

    fn plus(self, other: ModeStates) -> ModeStates {
        ModeStates {
            value: [0, 1, 2].map(|m| self.value[m] + other.value[m]),
            rate: [0, 1, 2].map(|m| self.rate[m] + other.rate[m]),
        }
    }

    fn minus(self, other: ModeStates) -> ModeStates {
        ModeStates {
            value: [0, 1, 2].map(|m| self.value[m] - other.value[m]),
            rate: [0, 1, 2].map(|m| self.rate[m] - other.rate[m]),
        }
    }
}

/// A transient below this (metres of heave, or slope) is spent.
const SPENT_TRANSIENT: f64 = 1.0e-5;

/// The free motion the oscillators are left with when the forcing changes at `start_s` (the
/// ship turns, changes speed, or the sea changes): each mode
/// `x(τ) = e^(−ζω_n τ) (x₀ cos ω_d τ + (v₀ + ζω_n x₀) / ω_d · sin ω_d τ)`,
/// `ω_d = ω_n √(1 − ζ²)`, `τ = t − start`, from the mismatch `x₀`, `v₀` between the motion
/// before the change and the new steady state at that instant. The steady state plus this is
/// the exact solution of the linear oscillator whose forcing switched at `start_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionTransient {
    start_s: f64,
    /// Per mode: natural frequency (rad/s), damping ratio, `x₀`, `v₀`.
    modes: [[f64; 4]; 3],
}

impl MotionTransient {
    /// The free motion of `hull`'s heave, pitch and roll from the states' `mismatch` at
    /// `start_s` (a damping ratio above 0.99 is taken as 0.99; a non-finite mismatch as 0).
    pub fn new(hull: &HullParameters, start_s: f64, mismatch: ModeStates) -> MotionTransient {
        let natural = [
            (hull.heave_period_s(), hull.heave_damping()),
            (hull.pitch_period_s(), hull.pitch_damping()),
            (hull.roll_period_s(), hull.roll_damping()),
        ];
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        MotionTransient {
            start_s,
            modes: [0, 1, 2].map(|m| {
                let (period_s, zeta) = natural[m];
                [
                    std::f64::consts::TAU / period_s,
                    zeta.min(0.99),
                    finite(mismatch.value[m]),
                    finite(mismatch.rate[m]),
                ]
            }),
        }
    }

    /// The free motion's states at `t_s` (before its start: at its start).
    pub fn at(&self, t_s: f64) -> ModeStates {
        let tau = (t_s - self.start_s).max(0.0);
        let mut states = ModeStates::default();
        for (m, &[omega_n, zeta, x0, v0]) in self.modes.iter().enumerate() {
            let decay = zeta * omega_n;
            let omega_d = omega_n * (1.0 - zeta * zeta).sqrt();
            let envelope = (-decay * tau).exp();
            let (sin, cos) = (omega_d * tau).sin_cos();
            let b = (v0 + decay * x0) / omega_d;
            states.value[m] = envelope * (x0 * cos + b * sin);
            // d/dτ of e^(−aτ)(x₀ cos ω_dτ + b sin ω_dτ).
            states.rate[m] =
                envelope * ((b * omega_d - decay * x0) * cos - (x0 * omega_d + decay * b) * sin);
        }
        states
    }

    /// Whether the free motion has died away by `t_s` (its envelope below 10⁻⁵ m or slope in
    /// every mode), or `t_s` is before its start (the clock went back).
    pub fn is_spent(&self, t_s: f64) -> bool {
        let tau = t_s - self.start_s;
        tau < 0.0
            || self.modes.iter().all(|&[omega_n, zeta, x0, v0]| {
                let omega_d = omega_n * (1.0 - zeta * zeta).sqrt();
                let size = x0.abs() + (v0.abs() + zeta * omega_n * x0.abs()) / omega_d;
                size * (-zeta * omega_n * tau).exp() < SPENT_TRANSIENT
            })
    }
}

/// One ship's ride from frame to frame: the steady response to the sea at its present heading
/// and velocity, plus the free motion left over from its last change of course, speed or sea
/// ([`MotionTransient`]), so the ship's motion stays continuous through a turn and rings down
/// at its natural periods, as the time-domain oscillators of [`crate::motion`] do.
///
/// A pure function of the changes it was given and when: IGs that see the same ship change
/// at the same sea time draw the same motion; one that starts later takes the steady state
/// until the next change (the difference dies away with the transient).
#[derive(Clone, Debug)]
pub struct ShipRide {
    response: Arc<SeawayResponse>,
    /// The response to the host's explicit waves as they apply where the ship is.
    explicit: Option<SeawayResponse>,
    velocity_enu_mps: [f64; 2],
    transient: Option<MotionTransient>,
}

impl ShipRide {
    /// A ship in the steady state of `response` (and of `explicit`, its response to the host's
    /// explicit waves where it is), moving at `velocity_enu_mps` (east, north, m/s; taken as
    /// [`usable_velocity`]).
    pub fn steady(
        response: Arc<SeawayResponse>,
        explicit: Option<SeawayResponse>,
        velocity_enu_mps: [f64; 2],
    ) -> ShipRide {
        ShipRide {
            response,
            explicit,
            velocity_enu_mps: usable_velocity(velocity_enu_mps),
            transient: None,
        }
    }

    /// The response the ship is in now.
    pub fn response(&self) -> &Arc<SeawayResponse> {
        &self.response
    }

    /// The oscillators' states at (`x_east_m`, `y_north_m`) at `t_s`.
    pub fn states_at(&self, x_east_m: f64, y_north_m: f64, t_s: f64) -> ModeStates {
        let mut steady = self
            .response
            .states_at(x_east_m, y_north_m, t_s, self.velocity_enu_mps);
        if let Some(explicit) = &self.explicit {
            steady =
                steady.plus(explicit.states_at(x_east_m, y_north_m, t_s, self.velocity_enu_mps));
        }
        match self.transient {
            Some(transient) if t_s >= transient.start_s => steady.plus(transient.at(t_s)),
            _ => steady,
        }
    }

    /// The ship's heave, pitch and roll at (`x_east_m`, `y_north_m`) at `t_s`.
    pub fn motion_at(&self, x_east_m: f64, y_north_m: f64, t_s: f64) -> ShipMotion {
        let live = self.transient.is_some_and(|t| !t.is_spent(t_s));
        if self.explicit.is_none() && !live {
            return self.response.motion_at(x_east_m, y_north_m, t_s);
        }
        ModeStates::motion_of(self.states_at(x_east_m, y_north_m, t_s).value)
    }

    /// The ship now in `response` (and `explicit`) at `velocity_enu_mps` from `t_s`, where it
    /// is at (`x_east_m`, `y_north_m`): the motion it had goes on into the new steady state
    /// through a transient. The same response (the same `Arc`), explicit response and
    /// velocity change nothing.
    pub fn change(
        &mut self,
        hull: &HullParameters,
        (response, explicit): (Arc<SeawayResponse>, Option<SeawayResponse>),
        velocity_enu_mps: [f64; 2],
        [x_east_m, y_north_m]: [f64; 2],
        t_s: f64,
    ) {
        let velocity_enu_mps = usable_velocity(velocity_enu_mps);
        if Arc::ptr_eq(&response, &self.response)
            && explicit == self.explicit
            && velocity_enu_mps == self.velocity_enu_mps
        {
            if self.transient.is_some_and(|t| t.is_spent(t_s)) {
                self.transient = None;
            }
            return;
        }
        let before = self.states_at(x_east_m, y_north_m, t_s);
        let next = ShipRide::steady(response, explicit, velocity_enu_mps);
        let after = next.states_at(x_east_m, y_north_m, t_s);
        let transient = MotionTransient::new(hull, t_s, before.minus(after));
        *self = ShipRide {
            transient: (!transient.is_spent(t_s)).then_some(transient),
            ..next
        };
    }
}

/// Which response a ship needs: the hull, its heading and velocity in the cache's steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct ResponseKey {
    hull: [u64; 7],
    heading_step: i64,
    velocity_steps: [i64; 2],
}

/// The responses of the ships on one sea (its waves as of [`ResponseCache::of`]), made once
/// per hull, heading (in steps of [`HEADING_STEP_DEG`]) and velocity (in steps of
/// [`VELOCITY_STEP_MPS`]) and kept. Each response is made at its step's value, so the motion
/// depends on the quantised heading and velocity alone, never on what was asked before.
#[derive(Clone, Debug, Default)]
pub struct ResponseCache {
    waves: Vec<LinearWave>,
    made: HashMap<ResponseKey, Arc<SeawayResponse>>,
}

/// A velocity (east, north, m/s) as the responses take it: non-finite parts 0, its speed at
/// most 40 m/s.
pub fn usable_velocity(velocity_enu_mps: [f64; 2]) -> [f64; 2] {
    let velocity = velocity_enu_mps.map(|v| if v.is_finite() { v } else { 0.0 });
    let speed = velocity[0].hypot(velocity[1]);
    if speed > MAX_SPEED_MPS {
        velocity.map(|v| v * MAX_SPEED_MPS / speed)
    } else {
        velocity
    }
}

/// The heading and velocity of the steps a response is made at (what [`ResponseCache`]
/// keys by): the heading in [`HEADING_STEP_DEG`] steps in `[0, 360)`, each of the velocity's
/// parts in [`VELOCITY_STEP_MPS`] steps (non-finite values 0, the speed at most 40 m/s).
pub fn quantised(heading_deg: f64, velocity_enu_mps: [f64; 2]) -> (f64, [f64; 2]) {
    let (heading_step, velocity_steps) = steps_of(heading_deg, velocity_enu_mps);
    #[expect(clippy::cast_precision_loss, reason = "the steps are small integers")]
    (
        heading_step as f64 * HEADING_STEP_DEG,
        velocity_steps.map(|n| n as f64 * VELOCITY_STEP_MPS),
    )
}

/// The heading's and velocity's steps (see [`quantised`]).
fn steps_of(heading_deg: f64, velocity_enu_mps: [f64; 2]) -> (i64, [i64; 2]) {
    let heading_deg = if heading_deg.is_finite() {
        heading_deg.rem_euclid(360.0)
    } else {
        0.0
    };
    let heading_step =
        steps(heading_deg, HEADING_STEP_DEG).rem_euclid(steps(360.0, HEADING_STEP_DEG));
    let velocity_steps = usable_velocity(velocity_enu_mps).map(|v| steps(v, VELOCITY_STEP_MPS));
    (heading_step, velocity_steps)
}

/// `value / step` rounded, saturating (non-finite values give 0).
fn steps(value: f64, step: f64) -> i64 {
    #[expect(
        clippy::cast_possible_truncation,
        reason = "rounded, and saturating is what is wanted for absurd values"
    )]
    let n = (value / step).round() as i64;
    n
}

impl ResponseCache {
    /// The cache for `surface`'s wind sea and swell (make a new one when they change); the
    /// host's explicit waves, which apply by place, are each ship's own
    /// ([`SeaSurface::explicit_linear_waves`], [`ShipRide`]).
    pub fn of(surface: &SeaSurface) -> ResponseCache {
        ResponseCache {
            waves: surface.spectral_linear_waves(),
            made: HashMap::new(),
        }
    }

    /// The response of `hull` heading `heading_deg` making good `velocity_enu_mps`.
    pub fn response(
        &mut self,
        hull: &HullParameters,
        heading_deg: f64,
        velocity_enu_mps: [f64; 2],
    ) -> Arc<SeawayResponse> {
        let (heading_step, velocity_steps) = steps_of(heading_deg, velocity_enu_mps);
        let key = ResponseKey {
            hull: hull.bits(),
            heading_step,
            velocity_steps,
        };
        if let Some(made) = self.made.get(&key) {
            return Arc::clone(made);
        }
        if self.made.len() >= MAX_CACHED {
            self.made.clear();
        }
        #[expect(clippy::cast_precision_loss, reason = "the steps are small integers")]
        let response = Arc::new(SeawayResponse::new(
            hull,
            &self.waves,
            heading_step as f64 * HEADING_STEP_DEG,
            velocity_steps.map(|n| n as f64 * VELOCITY_STEP_MPS),
        ));
        self.made.insert(key, Arc::clone(&response));
        response
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::StraightCourse;
    use crate::spectrum::SeaConditions;
    use crate::surface::{Cascade, SurfaceConfig, WaveComponent};
    use crate::G_MPS2;
    use std::f64::consts::TAU;

    /// A long-crested deep-water wave of amplitude `a` (m) and length `lambda` (m) travelling
    /// toward `toward_deg`, with phase `phase` (rad) at the origin at time 0.
    fn wave(a: f64, lambda: f64, toward_deg: f64, phase: f64) -> LinearWave {
        let k = TAU / lambda;
        let d = toward_deg.to_radians();
        LinearWave {
            k_rad_m: [k * d.sin(), k * d.cos()],
            omega_rad_s: (G_MPS2 * k).sqrt(),
            amplitude_m: [a * phase.cos(), a * phase.sin()],
        }
    }

    fn rms(values: &[f64]) -> f64 {
        (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
    }

    /// Heave, pitch and roll at `n` times from `t0` every `dt` on `course`.
    fn closed_form(
        response: &SeawayResponse,
        course: &StraightCourse,
        t0: f64,
        dt: f64,
        n: usize,
    ) -> [Vec<f64>; 3] {
        let mut out = [Vec::new(), Vec::new(), Vec::new()];
        for i in 0..n {
            let t = t0 + dt * i as f64;
            let pose = course.pose_at(t);
            let m = response.motion_at(pose.x_east_m, pose.y_north_m, t);
            out[0].push(m.heave_m);
            out[1].push(m.pitch_deg);
            out[2].push(m.roll_deg);
        }
        out
    }

    #[test]
    fn the_linear_waves_are_the_surface() {
        let conditions = SeaConditions::for_sea_state(5, 250.0).unwrap();
        let config = SurfaceConfig {
            cascades: vec![Cascade {
                tile_m: 400.0,
                size: 64,
            }],
            choppiness: 1.0,
        };
        let mut surface = SeaSurface::new(&conditions, 3, config).unwrap();
        surface
            .set_explicit_waves(vec![
                WaveComponent::new(1.2, 90.0, 7.6, 30.0, 40.0, 0.5).unwrap()
            ])
            .unwrap();
        let t = 1234.5;
        surface.update(t).unwrap();
        let waves = surface.linear_waves();
        assert!(waves.len() > 500, "{}", waves.len());
        let mut worst: f64 = 0.0;
        let mut spread = Vec::new();
        for (i, j) in [(0, 0), (3, 7), (17, 40), (63, 63), (32, 5), (50, 21)] {
            let (x, y) = (f64::from(i) * 400.0 / 64.0, f64::from(j) * 400.0 / 64.0);
            let sum: f64 = waves.iter().map(|w| w.height_m(x, y, t)).sum();
            let grid = surface.height_at_undisplaced(x, y);
            worst = worst.max((sum - grid).abs());
            spread.push(grid);
        }
        // The FFT runs in f32: agreement to about a millimetre on metres of sea.
        assert!(worst < 2e-3, "worst {worst} over heights {spread:?}");
        assert!(rms(&spread) > 0.3, "{spread:?}");
    }

    /// `waves` each scaled by the depth factor the closed form applies for `hull`.
    fn depth_scaled(hull: &HullParameters, waves: &[LinearWave]) -> Vec<LinearWave> {
        waves
            .iter()
            .map(|w| {
                let k = w.k_rad_m[0].hypot(w.k_rad_m[1]);
                let depth = (-0.5 * k * hull.draft_m()).exp();
                LinearWave {
                    amplitude_m: w.amplitude_m.map(|a| a * depth),
                    ..*w
                }
            })
            .collect()
    }

    /// The closed form against integrating the oscillators in time (crate::motion) on the
    /// same waves, each scaled by the depth factor the closed form applies.
    fn against_time_domain(hull: HullParameters, waves: &[LinearWave], course: StraightCourse) {
        let response = SeawayResponse::new(
            &hull,
            waves,
            course.pose_at(0.0).heading_deg,
            course.velocity_enu_mps(),
        );
        let scaled = depth_scaled(&hull, waves);
        let sea = |x: f64, y: f64, t: f64| scaled.iter().map(|w| w.height_m(x, y, t)).sum::<f64>();
        let (t0, dt, n) = (500.0, 0.25, 160);
        let closed = closed_form(&response, &course, t0, dt, n);
        let stepped = crate::motion::tests::series(hull, &sea, course, t0, dt, n);
        for (mode, (a, b)) in ["heave", "pitch", "roll"]
            .iter()
            .zip(closed.iter().zip(&stepped))
        {
            let difference: Vec<f64> = a.iter().zip(b).map(|(a, b)| a - b).collect();
            let scale = rms(b);
            assert!(
                rms(&difference) < 0.08 * scale + 1e-3,
                "{mode}: closed form {} vs integrated {scale}, difference {}",
                rms(a),
                rms(&difference)
            );
        }
    }

    #[test]
    fn a_turn_rings_down_as_the_oscillators_integrated_in_time_do() {
        // A patrol craft rolling at resonance in a beam sea (heading north, the waves
        // travelling east) turns at t = 600 s to head into them (heading west).
        let patrol = HullParameters::PATROL_CRAFT;
        let resonant = G_MPS2 * patrol.roll_period_s().powi(2) / TAU;
        let waves = [wave(0.3, resonant, 90.0, 0.4), wave(0.2, 60.0, 120.0, 1.0)];
        let turn_s = 600.0;
        let before = StraightCourse::new(0.0, 0.0, 0.0, 4.0, turn_s).unwrap();
        let after = StraightCourse::new(0.0, 0.0, 270.0, 4.0, turn_s).unwrap();
        let track = |t: f64| {
            if t < turn_s {
                before.pose_at(t)
            } else {
                after.pose_at(t)
            }
        };
        let scaled = depth_scaled(&patrol, &waves);
        let sea = |x: f64, y: f64, t: f64| scaled.iter().map(|w| w.height_m(x, y, t)).sum::<f64>();
        let mut tracker =
            crate::motion::ShipMotionTracker::new(crate::motion::ShipMotionModel::new(patrol));
        let response = |c: &StraightCourse| {
            Arc::new(SeawayResponse::new(
                &patrol,
                &waves,
                c.pose_at(0.0).heading_deg,
                c.velocity_enu_mps(),
            ))
        };
        let mut ride = ShipRide::steady(response(&before), None, before.velocity_enu_mps());
        let steady_after = response(&after);
        // Over the first three roll periods after the turn.
        let (mut with, mut without, mut integrated) = (Vec::new(), Vec::new(), Vec::new());
        let mut t = turn_s - 20.0;
        while t < turn_s + 3.0 * patrol.roll_period_s() {
            if t >= turn_s && !Arc::ptr_eq(ride.response(), &steady_after) {
                let p = after.pose_at(turn_s);
                ride.change(
                    &patrol,
                    (Arc::clone(&steady_after), None),
                    after.velocity_enu_mps(),
                    [p.x_east_m, p.y_north_m],
                    turn_s,
                );
            }
            if t >= turn_s {
                let p = track(t);
                let stepped = tracker.motion_at(sea, track, t).unwrap();
                integrated.push(stepped.roll_deg);
                with.push(ride.motion_at(p.x_east_m, p.y_north_m, t).roll_deg);
                without.push(steady_after.motion_at(p.x_east_m, p.y_north_m, t).roll_deg);
            }
            t += 0.25;
        }
        let error = |a: &[f64]| {
            let d: Vec<f64> = a.iter().zip(&integrated).map(|(a, b)| a - b).collect();
            rms(&d)
        };
        let scale = rms(&integrated);
        assert!(scale > 1.0, "the ship still rolls after the turn: {scale}");
        let (e_with, e_without) = (error(&with), error(&without));
        assert!(
            e_with < 0.05 * scale && e_with < 0.05 * e_without,
            "roll after the turn: integrated rms {scale}, error with the transient {e_with}, \
             steady state alone {e_without}"
        );
        // The transient dies away: long after, the ride is the new steady state.
        let late = turn_s + 1000.0;
        let p = after.pose_at(late);
        assert_eq!(
            ride.motion_at(p.x_east_m, p.y_north_m, late),
            steady_after.motion_at(p.x_east_m, p.y_north_m, late)
        );
    }

    #[test]
    fn the_states_rates_are_the_motions_derivative() {
        let conditions = SeaConditions::for_sea_state(5, 250.0).unwrap();
        let surface = SeaSurface::new(&conditions, 3, SurfaceConfig::default()).unwrap();
        let v = [3.0, -4.0];
        let response = SeawayResponse::new(
            &HullParameters::DESTROYER,
            &surface.linear_waves(),
            143.0,
            v,
        );
        let transient = MotionTransient::new(
            &HullParameters::DESTROYER,
            100.0,
            ModeStates {
                value: [0.5, 0.01, -0.05],
                rate: [0.1, 0.0, 0.02],
            },
        );
        let h = 1e-4;
        for t in [100.5, 107.0, 131.0] {
            let at = |t: f64| {
                let s = response.states_at(v[0] * t, v[1] * t, t, v);
                (s, transient.at(t))
            };
            let ((s, tr), (s1, tr1), (s0, tr0)) = (at(t), at(t + h), at(t - h));
            for m in 0..3 {
                let numeric = (s1.value[m] - s0.value[m]) / (2.0 * h);
                assert!(
                    (numeric - s.rate[m]).abs() < 1e-5 * (1.0 + numeric.abs()),
                    "{m}"
                );
                let numeric = (tr1.value[m] - tr0.value[m]) / (2.0 * h);
                assert!(
                    (numeric - tr.rate[m]).abs() < 1e-5 * (1.0 + numeric.abs()),
                    "{m}"
                );
            }
        }
        // At its start the transient is its mismatch.
        let start = transient.at(100.0);
        assert!((start.value[0] - 0.5).abs() < 1e-12 && (start.rate[2] - 0.02).abs() < 1e-12);
        assert!(
            !transient.is_spent(101.0) && transient.is_spent(2000.0) && transient.is_spent(99.0)
        );
    }

    #[test]
    fn the_closed_form_agrees_with_the_oscillators_integrated_in_time() {
        let patrol = HullParameters::PATROL_CRAFT;
        // Beam sea at the roll's natural period, the ship under way across it.
        let resonant = G_MPS2 * patrol.roll_period_s().powi(2) / TAU;
        let course = StraightCourse::new(100.0, -50.0, 0.0, 5.0, 0.0).unwrap();
        against_time_domain(patrol, &[wave(0.3, resonant, 90.0, 0.4)], course);
        // Head seas met at the encounter frequency, with a quartering swell.
        let course = StraightCourse::new(0.0, 0.0, 0.0, 8.0, 0.0).unwrap();
        against_time_domain(
            patrol,
            &[wave(0.5, 100.0, 180.0, 0.0), wave(0.4, 300.0, 135.0, 2.0)],
            course,
        );
        // A destroyer in a mixed sea.
        let course = StraightCourse::new(0.0, 0.0, 60.0, 10.0, 0.0).unwrap();
        against_time_domain(
            HullParameters::DESTROYER,
            &[
                wave(0.8, 200.0, 200.0, 0.0),
                wave(0.6, 150.0, 150.0, 1.0),
                wave(0.5, 120.0, 250.0, 2.0),
            ],
            course,
        );
    }

    #[test]
    fn resonance_amplifies_roll_by_one_over_twice_the_damping() {
        let hull = HullParameters::DESTROYER;
        let roll_at = |period_s: f64| {
            let lambda = G_MPS2 * period_s * period_s / TAU;
            let waves = [wave(0.5, lambda, 90.0, 0.0)];
            let response = SeawayResponse::new(&hull, &waves, 0.0, [0.0, 0.0]);
            let slope_deg = (TAU / lambda * 0.5).atan().to_degrees();
            let peak = (0..400)
                .map(|i| {
                    response
                        .motion_at(0.0, 0.0, f64::from(i) * 0.1)
                        .roll_deg
                        .abs()
                })
                .fold(0.0, f64::max);
            peak / slope_deg
        };
        let at_resonance = roll_at(hull.roll_period_s());
        // 1/2ζ = 7.1, less the hull's filter and the depth factor on a 200 m wave.
        assert!((5.0..7.2).contains(&at_resonance), "{at_resonance}");
        // Waves much longer than the roll period: the ship lies on the slope.
        let long = roll_at(4.0 * hull.roll_period_s());
        assert!((0.95..1.15).contains(&long), "{long}");
        // Waves much shorter: barely felt.
        assert!(roll_at(0.4 * hull.roll_period_s()) < 0.25);
    }

    /// The period, s, at which `values` (sampled every `dt` s) has the most power (averaged
    /// over ±0.2 s of period), searched from 2 to 30 s in steps of 0.1 s.
    fn peak_period_s(values: &[f64], dt: f64) -> f64 {
        let power: Vec<f64> = (0..=280)
            .map(|j| {
                let w = TAU / (2.0 + f64::from(j) * 0.1);
                let (mut a, mut b) = (0.0, 0.0);
                for (i, v) in values.iter().enumerate() {
                    let (sin, cos) = (w * i as f64 * dt).sin_cos();
                    a += v * cos;
                    b += v * sin;
                }
                a * a + b * b
            })
            .collect();
        let smoothed = power.windows(5).map(|w| w.iter().sum::<f64>());
        let (best, _) = smoothed.enumerate().fold(
            (0, 0.0),
            |best, (j, p)| if p > best.1 { (j, p) } else { best },
        );
        // The window starting at j is centred on j + 2.
        2.0 + (best + 2) as f64 * 0.1
    }

    #[test]
    fn a_ship_rolls_at_the_period_its_beam_gives() {
        // A beam sea (the wind from the west, the ship heading north) whose spectrum covers
        // the ship's natural roll period (5.5, 11.3 and 15.5 s).
        let mut periods = Vec::new();
        for (hull, code) in [
            (HullParameters::PATROL_CRAFT, 5),
            (HullParameters::DESTROYER, 6),
            (HullParameters::MERCHANT, 7),
        ] {
            let conditions = SeaConditions::for_sea_state(code, 270.0).unwrap();
            let surface = SeaSurface::new(&conditions, 11, SurfaceConfig::default()).unwrap();
            let response = SeawayResponse::new(&hull, &surface.linear_waves(), 0.0, [0.0, 0.0]);
            let dt = 0.5;
            let roll: Vec<f64> = (0..4096)
                .map(|i| response.motion_at(30.0, 40.0, f64::from(i) * dt).roll_deg)
                .collect();
            let period = peak_period_s(&roll, dt);
            let natural = hull.roll_period_s();
            assert!(
                (period / natural - 1.0).abs() < 0.1,
                "beam {} m: rolls most at {period} s, natural period {natural} s",
                hull.beam_m()
            );
            periods.push(period);
            assert!(rms(&roll) > 1.0, "{}", rms(&roll));
        }
        assert!(
            periods[0] < periods[1] && periods[1] < periods[2],
            "{periods:?}"
        );
        // Head on to the sea (short-crested: its spreading still reaches the beam) the
        // destroyer rolls less.
        let conditions = SeaConditions::for_sea_state(6, 270.0).unwrap();
        let waves = SeaSurface::new(&conditions, 11, SurfaceConfig::default())
            .unwrap()
            .linear_waves();
        let response = SeawayResponse::new(&HullParameters::DESTROYER, &waves, 270.0, [0.0; 2]);
        let beam = SeawayResponse::new(&HullParameters::DESTROYER, &waves, 0.0, [0.0; 2]);
        let roll_rms = |r: &SeawayResponse| {
            let roll: Vec<f64> = (0..2400)
                .map(|i| r.motion_at(0.0, 0.0, f64::from(i) * 0.5).roll_deg)
                .collect();
            rms(&roll)
        };
        let (head, beam) = (roll_rms(&response), roll_rms(&beam));
        assert!(head < 0.6 * beam, "head {head} beam {beam}");
    }

    #[test]
    fn the_tapered_filter_matches_quadrature() {
        for x in [
            0.0, 1e-3, 0.3, 0.499, 0.501, 1.0, 2.0, 4.0, 7.0, 30.0, 400.0,
        ] {
            // Midpoint rule over [-1, 1] with the taper 1 − s⁴.
            let n = 200_000;
            let (mut mean, mut first, mut second, mut area) = (0.0, 0.0, 0.0, 0.0);
            for i in 0..n {
                let s = -1.0 + (f64::from(i) + 0.5) * 2.0 / f64::from(n);
                let w = 1.0 - s.powi(4);
                mean += w * (x * s).cos();
                first += w * s * (x * s).sin();
                second += w * s * s;
                area += w;
            }
            let (m, slope) = tapered(x);
            assert!(
                (m - mean / area).abs() < 1e-6,
                "{x}: {m} vs {}",
                mean / area
            );
            if x > 0.0 {
                let expected = first / (x * second);
                assert!(
                    (slope - expected).abs() < 1e-6,
                    "{x}: {slope} vs {expected}"
                );
            }
        }
        assert_eq!(tapered(-2.0), tapered(2.0));
    }

    #[test]
    fn a_rougher_sea_moves_the_ship_more_and_the_cache_is_deterministic() {
        let motion = |code: u8| {
            let conditions = SeaConditions::for_sea_state(code, 200.0).unwrap();
            let surface = SeaSurface::new(&conditions, 4, SurfaceConfig::default()).unwrap();
            let mut cache = ResponseCache::of(&surface);
            let mut other = ResponseCache::of(&surface);
            let hull = HullParameters::DESTROYER;
            let response = cache.response(&hull, 45.2, [3.0, 3.1]);
            // The same steps give the same response, made at the steps' values.
            assert!(Arc::ptr_eq(
                &response,
                &cache.response(&hull, 44.9, [3.05, 3.0])
            ));
            assert_eq!(*response, *other.response(&hull, 45.0, [3.0, 3.0]));
            assert_eq!(
                *response,
                SeawayResponse::new(&hull, &surface.linear_waves(), 45.0, [3.0, 3.0])
            );
            let mut sums = [0.0; 3];
            for i in 0..200 {
                let m = response.motion_at(10.0, 20.0, 1.0e8 + f64::from(i) * 0.7);
                sums[0] += m.heave_m * m.heave_m;
                sums[1] += m.pitch_deg * m.pitch_deg;
                sums[2] += m.roll_deg * m.roll_deg;
            }
            sums
        };
        let calm = motion(2);
        let rough = motion(6);
        for (mode, (c, r)) in ["heave", "pitch", "roll"]
            .iter()
            .zip(calm.iter().zip(rough))
        {
            assert!(r > 10.0 * c, "{mode}: sea state 2 {c}, 6 {r}");
        }
    }

    #[test]
    fn the_waves_left_out_do_not_matter() {
        let hulls = [
            HullParameters::PATROL_CRAFT,
            HullParameters::DESTROYER,
            HullParameters::MERCHANT,
        ];
        for (code, hull) in [(3, hulls[0]), (5, hulls[1]), (7, hulls[2]), (5, hulls[0])] {
            let conditions = SeaConditions::for_sea_state(code, 300.0).unwrap();
            let surface = SeaSurface::new(&conditions, 9, SurfaceConfig::default()).unwrap();
            let waves = surface.linear_waves();
            let kept = SeawayResponse::new(&hull, &waves, 20.0, [2.0, 5.0]);
            let all = SeawayResponse::with_shares(&hull, &waves, 20.0, [2.0, 5.0], [0.0, 0.0]);
            assert_eq!(all.wave_count(), waves.len());
            assert!(kept.wave_count() < waves.len() / 5, "{}", kept.wave_count());
            let mut errors = [Vec::new(), Vec::new(), Vec::new()];
            let mut values = [Vec::new(), Vec::new(), Vec::new()];
            for i in 0..300 {
                let t = 7.0e7 + f64::from(i) * 0.9;
                let (a, b) = (
                    kept.motion_at(5.0, 2.0 * t, t),
                    all.motion_at(5.0, 2.0 * t, t),
                );
                for (m, (x, y)) in [
                    (a.heave_m, b.heave_m),
                    (a.pitch_deg, b.pitch_deg),
                    (a.roll_deg, b.roll_deg),
                ]
                .into_iter()
                .enumerate()
                {
                    errors[m].push(x - y);
                    values[m].push(y);
                }
            }
            for (e, v) in errors.iter().zip(&values) {
                assert!(rms(e) < 0.02 * rms(v), "{} vs {}", rms(e), rms(v));
            }
        }
    }

    #[test]
    fn few_waves_are_kept_and_odd_input_stays_finite() {
        let conditions = SeaConditions::for_sea_state(6, 0.0).unwrap();
        let surface = SeaSurface::new(&conditions, 1, SurfaceConfig::default()).unwrap();
        let waves = surface.linear_waves();
        let response = SeawayResponse::new(&HullParameters::DESTROYER, &waves, 0.0, [0.0, 5.0]);
        assert!(
            response.wave_count() < waves.len() / 2,
            "{} of {}",
            response.wave_count(),
            waves.len()
        );
        for (heading, velocity) in [
            (f64::NAN, [0.0, 0.0]),
            (1.0e300, [f64::INFINITY, f64::NAN]),
            (-720.0, [1.0e9, -1.0e9]),
        ] {
            let mut cache = ResponseCache::of(&surface);
            let response = cache.response(&HullParameters::PATROL_CRAFT, heading, velocity);
            let m = response.motion_at(0.0, 0.0, 10.0);
            assert!(m.heave_m.is_finite() && m.pitch_deg.is_finite() && m.roll_deg.is_finite());
        }
        // A calm sea: no waves, no motion.
        let calm = SeaSurface::new(
            &SeaConditions::for_sea_state(0, 0.0).unwrap(),
            1,
            SurfaceConfig::default(),
        )
        .unwrap();
        let response = ResponseCache::of(&calm).response(&HullParameters::DESTROYER, 0.0, [0.0; 2]);
        assert_eq!(response.motion_at(5.0, 5.0, 5.0), ShipMotion::default());
    }
}
