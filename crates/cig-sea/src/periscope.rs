//! The periscope's optics: magnification and field of view, the stadimeter, the reticle, the
//! head's height over the sea and the water washing over its window.
//!
//! Algorithms and sources:
//!
//! - Field of view: the true field is the unity-power field over the magnification,
//!   `FOV = 48° / M` (document 001, the periscope trainer: 1× shows 48°, 6× shows 8°). The
//!   standard powers are those of the tri-power periscope of US patent 4,017,148: 1.5× (32°),
//!   6× (8°) and 12× (4°).
//! - Stadimeter: the range of a target of known masthead height `H` whose waterline-to-masthead
//!   angle is `α` is `H / tan α`. The real instrument doubles the image and the officer brings
//!   the masthead of one image to the waterline of the other after setting `H`; the sum is the
//!   same. Measured on a rendered channel the angle comes in whole pixels: with a span of `n`
//!   pixels the range is off by at most `0.5 / n` of itself
//!   ([`Stadimeter::quantisation_error_fraction`]): 1.1 % for a 30 m masthead at 5 km on a
//!   1024-pixel 8° channel (44 px).
//! - Pixels: a size `s` at range `r`, centred on the axis of a rectilinear (pinhole) channel
//!   `W` pixels and `FOV` degrees wide, spans `W (s / r) / (2 tan(FOV / 2))` pixels: a 100 m
//!   ship at 20 km covers 5.8 px at 48°, 8.9 px at 32° and 36.6 px at 8° on 1024 pixels.
//! - Reticle: graduations across the horizontal line at a 1-2-5 step of degrees chosen so
//!   that at most 40 intervals cross the field (2° at 48°, 1° at 32°, 0.2° at 8°, 0.1° at 4°),
//!   every fifth one major. This is a rendering choice, not a copy of a given instrument.
//! - Wash-over: the window (default 0.15 m tall, centred at the head height) is wet over the
//!   fraction of its height below the sea. When the sea falls away the film drains from the
//!   top down with the front accelerating as under gravity, so the fraction still wet `x`
//!   seconds after the water stood at a level falls as `1 − (x / T)²`, gone after the drain
//!   time `T` (default 0.8 s, a choice inside the 0.5–1 s that the trainer's reviewers asked
//!   for). The coverage at `t` is the largest wetness left by any moment of the last `T`
//!   seconds, a pure function of the sea-height history and `t`.
//!
//! Limits: the field of view is taken as exact (real eyepieces differ by a degree or two); no
//! distortion, vignetting or optical quality is modelled; the stadimeter assumes the waterline
//! is visible (see [`crate::horizon`] for hull-down targets) and a flat sea; the wash-over
//! ignores spray, droplets and a wiper.

use crate::{checked, SeaError};

/// The field of view at unity power, degrees (document 001).
pub const UNITY_FIELD_OF_VIEW_DEG: f64 = 48.0;

/// Highest magnification accepted.
pub const MAX_MAGNIFICATION: f64 = 40.0;

/// `value` when finite and inside `0 < value <= hi`.
fn positive(name: &'static str, value: f64, hi: f64, range: &'static str) -> Result<f64, SeaError> {
    if value.is_finite() && value > 0.0 && value <= hi {
        Ok(value)
    } else {
        Err(SeaError::OutOfRange { name, range, value })
    }
}

/// `value` when finite and inside `0 < value < hi`.
fn open(name: &'static str, value: f64, hi: f64, range: &'static str) -> Result<f64, SeaError> {
    if value.is_finite() && value > 0.0 && value < hi {
        Ok(value)
    } else {
        Err(SeaError::OutOfRange { name, range, value })
    }
}

fn field(fov_deg: f64) -> Result<f64, SeaError> {
    open("fov_deg", fov_deg, 180.0, "0 < fov_deg < 180")
}

fn width(width_px: u32) -> Result<f64, SeaError> {
    if width_px == 0 {
        Err(SeaError::OutOfRange {
            name: "width_px",
            range: "at least 1",
            value: 0.0,
        })
    } else {
        Ok(f64::from(width_px))
    }
}

/// A periscope magnification (power), greater than 0 and at most 40.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Magnification(f64);

impl Magnification {
    /// Unity power: 48°.
    pub const X1: Magnification = Magnification(1.0);
    /// Low power of the tri-power periscope: 1.5×, 32°.
    pub const X1_5: Magnification = Magnification(1.5);
    /// High power: 6×, 8°.
    pub const X6: Magnification = Magnification(6.0);
    /// Highest power of the tri-power periscope: 12×, 4°.
    pub const X12: Magnification = Magnification(12.0);
    /// The standard powers of the tri-power periscope (US patent 4,017,148), low to high.
    pub const TRI_POWER: [Magnification; 3] =
        [Magnification::X1_5, Magnification::X6, Magnification::X12];

    /// A magnification `0 < power <= 40`.
    pub fn new(power: f64) -> Result<Magnification, SeaError> {
        positive("magnification", power, MAX_MAGNIFICATION, "0 < power <= 40").map(Magnification)
    }

    /// The power.
    pub fn power(&self) -> f64 {
        self.0
    }

    /// The true field of view, degrees: 48° / power.
    pub fn field_of_view_deg(&self) -> f64 {
        UNITY_FIELD_OF_VIEW_DEG / self.0
    }
}

/// The true field of view at a magnification, degrees: 48° / power (1.5× 32°, 6× 8°, 12× 4°).
pub fn field_of_view_deg(magnification: Magnification) -> f64 {
    magnification.field_of_view_deg()
}

/// How many pixels an object `size_m` across (0..=10 km) spans at `range_m` (0 < r <= 1000 km),
/// centred on the axis of a rectilinear channel `width_px` wide showing `fov_deg` across
/// (0 < fov < 180): `W (s / r) / (2 tan(FOV / 2))`, fractional.
pub fn pixels_subtended(
    size_m: f64,
    range_m: f64,
    fov_deg: f64,
    width_px: u32,
) -> Result<f64, SeaError> {
    let s = checked("size_m", size_m, 0.0, 10_000.0, "0..=10000 m")?;
    let r = positive("range_m", range_m, 1.0e6, "0 < range_m <= 1000000 m")?;
    let fov = field(fov_deg)?;
    let w = width(width_px)?;
    Ok(w * (s / r) / (2.0 * (0.5 * fov.to_radians()).tan()))
}

/// The angle, degrees, whose tangent spans `pixels` (0..=width) at the centre of a rectilinear
/// channel `width_px` wide showing `fov_deg` across: the inverse of [`pixels_subtended`]
/// (`atan(n 2 tan(FOV / 2) / W)`).
pub fn angle_of_pixels_deg(pixels: f64, fov_deg: f64, width_px: u32) -> Result<f64, SeaError> {
    let fov = field(fov_deg)?;
    let w = width(width_px)?;
    let n = checked("pixels", pixels, 0.0, w, "0..=width_px")?;
    Ok((n * 2.0 * (0.5 * fov.to_radians()).tan() / w)
        .atan()
        .to_degrees())
}

/// The stadimeter: range from a known masthead height and the angle it subtends.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stadimeter;

impl Stadimeter {
    /// Range, m, of a target whose masthead stands `masthead_height_m` (0 < H <= 1000 m) above
    /// its waterline and subtends `subtended_deg` (0 < α < 90) from waterline to masthead:
    /// `H / tan α`.
    pub fn range_m(masthead_height_m: f64, subtended_deg: f64) -> Result<f64, SeaError> {
        let h = positive(
            "masthead_height_m",
            masthead_height_m,
            1000.0,
            "0 < masthead_height_m <= 1000 m",
        )?;
        let a = open(
            "subtended_deg",
            subtended_deg,
            90.0,
            "0 < subtended_deg < 90",
        )?;
        Ok(h / a.to_radians().tan())
    }

    /// The angle, degrees, that a masthead `masthead_height_m` (0 < H <= 1000 m) above the
    /// waterline subtends at `range_m` (0 < r <= 1000 km): `atan(H / r)`.
    pub fn subtended_deg(masthead_height_m: f64, range_m: f64) -> Result<f64, SeaError> {
        let h = positive(
            "masthead_height_m",
            masthead_height_m,
            1000.0,
            "0 < masthead_height_m <= 1000 m",
        )?;
        let r = positive("range_m", range_m, 1.0e6, "0 < range_m <= 1000000 m")?;
        Ok((h / r).atan().to_degrees())
    }

    /// Range, m, from a waterline-to-masthead span of `pixels` measured on a rectilinear
    /// channel `width_px` wide showing `fov_deg` across.
    pub fn range_from_pixels_m(
        masthead_height_m: f64,
        pixels: f64,
        fov_deg: f64,
        width_px: u32,
    ) -> Result<f64, SeaError> {
        let angle = angle_of_pixels_deg(pixels, fov_deg, width_px)?;
        Stadimeter::range_m(masthead_height_m, angle)
    }

    /// The largest error of a range read from a span measured in whole pixels, as a fraction of
    /// the true range: `0.5 / n` for a span of `n` pixels (n >= 1), since the true span lies
    /// within half a pixel of `n` and the range goes as its inverse.
    pub fn quantisation_error_fraction(measured_pixels: f64) -> Result<f64, SeaError> {
        let n = checked(
            "measured_pixels",
            measured_pixels,
            1.0,
            1.0e6,
            "1..=1000000",
        )?;
        Ok(0.5 / n)
    }
}

/// Where the periscope head stands: its height above the mean sea surface, m, from the sea
/// floor (`-water_depth_m`, the head under water) up to 30 m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriscopeMount {
    height_above_sea_m: f64,
    water_depth_m: f64,
}

impl PeriscopeMount {
    /// Highest head accepted above the sea, m.
    pub const MAX_HEIGHT_ABOVE_SEA_M: f64 = 30.0;

    /// A head `height_above_sea_m` above the mean sea surface (negative: under water) in water
    /// `water_depth_m` deep (0..=11 000 m). The head may not be below the sea floor nor more
    /// than 30 m up.
    pub fn new(height_above_sea_m: f64, water_depth_m: f64) -> Result<PeriscopeMount, SeaError> {
        let depth = checked("water_depth_m", water_depth_m, 0.0, 11_000.0, "0..=11000 m")?;
        let height = checked(
            "height_above_sea_m",
            height_above_sea_m,
            -depth,
            PeriscopeMount::MAX_HEIGHT_ABOVE_SEA_M,
            "-water_depth_m..=30 m",
        )?;
        Ok(PeriscopeMount {
            height_above_sea_m: height,
            water_depth_m: depth,
        })
    }

    /// The head's height above the mean sea surface, m (negative: under water).
    pub fn height_above_sea_m(&self) -> f64 {
        self.height_above_sea_m
    }

    /// The water depth, m.
    pub fn water_depth_m(&self) -> f64 {
        self.water_depth_m
    }

    /// Whether the sea at `sea_height_m` (above mean sea level) stands over the head.
    pub fn is_submerged(&self, sea_height_m: f64) -> bool {
        sea_height_m >= self.height_above_sea_m
    }
}

/// Water washing over the periscope window and draining off it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WashOver {
    window_height_m: f64,
    drain_time_s: f64,
}

impl Default for WashOver {
    /// [`WashOver::DEFAULT`].
    fn default() -> WashOver {
        WashOver::DEFAULT
    }
}

/// Steps over the drain time at which the history is looked at (besides its samples and
/// the moments the window goes fully under).
const WASH_STEPS: usize = 64;

impl WashOver {
    /// A window 0.15 m tall draining in 0.8 s.
    pub const DEFAULT: WashOver = WashOver {
        window_height_m: 0.15,
        drain_time_s: 0.8,
    };

    /// A window `window_height_m` tall (0 < h <= 2 m) whose water drains in `drain_time_s`
    /// (0 < T <= 10 s).
    pub fn new(window_height_m: f64, drain_time_s: f64) -> Result<WashOver, SeaError> {
        Ok(WashOver {
            window_height_m: positive(
                "window_height_m",
                window_height_m,
                2.0,
                "0 < window_height_m <= 2 m",
            )?,
            drain_time_s: positive(
                "drain_time_s",
                drain_time_s,
                10.0,
                "0 < drain_time_s <= 10 s",
            )?,
        })
    }

    /// The window's height, m.
    pub fn window_height_m(&self) -> f64 {
        self.window_height_m
    }

    /// The drain time, s.
    pub fn drain_time_s(&self) -> f64 {
        self.drain_time_s
    }

    /// The fraction of the window (0..=1) covered by water at `t_s`, for a window centred
    /// `head_height_m` above the mean sea surface (-11 000..=30 m) and the sea height at the
    /// head `sea_height_history` as `(t_s, height_m)` samples in increasing time.
    ///
    /// The sea is linearly interpolated between samples, held at the last sample after the
    /// history ends, and unknown (no water) before it begins; an empty history gives 0.
    /// 1 while the sea stands over the whole window, 0 once it has been below the window for
    /// the drain time, between while draining or half under.
    pub fn coverage(
        &self,
        head_height_m: f64,
        sea_height_history: &[(f64, f64)],
        t_s: f64,
    ) -> Result<f64, SeaError> {
        let head = checked(
            "head_height_m",
            head_height_m,
            -11_000.0,
            30.0,
            "-11000..=30 m",
        )?;
        let t = checked("t_s", t_s, -1.0e12, 1.0e12, "finite, |t| <= 1e12 s")?;
        let mut previous = f64::NEG_INFINITY;
        for &(ts, h) in sea_height_history {
            if !ts.is_finite() || ts <= previous {
                return Err(SeaError::OutOfRange {
                    name: "sea_height_history time",
                    range: "finite and increasing",
                    value: ts,
                });
            }
            checked(
                "sea_height_history height",
                h,
                -1.0e4,
                1.0e4,
                "-10000..=10000 m",
            )?;
            previous = ts;
        }
        let Some(&(t_first, _)) = sea_height_history.first() else {
            return Ok(0.0);
        };
        let bottom = head - 0.5 * self.window_height_m;
        let top = head + 0.5 * self.window_height_m;
        let wet = |sea: f64| ((sea - bottom) / self.window_height_m).clamp(0.0, 1.0);
        let drain = self.drain_time_s;
        let left = |tau: f64| -> f64 {
            let x = (t - tau) / drain;
            if (0.0..1.0).contains(&x) {
                1.0 - x * x
            } else {
                0.0
            }
        };
        let from = t - drain;
        let mut best: f64 = 0.0;
        let mut consider = |tau: f64, sea: f64| {
            if tau >= t_first && tau >= from && tau <= t {
                best = best.max(wet(sea) * left(tau));
            }
        };
        // Moments on a grid over the drain time, at the samples and at the crossings of the
        // window's top (where the window leaves full cover).
        for j in 0..=WASH_STEPS {
            let tau = t - drain * (j as f64) / (WASH_STEPS as f64);
            if let Some(sea) = sea_at(sea_height_history, tau) {
                consider(tau, sea);
            }
        }
        for pair in sea_height_history.windows(2) {
            let ((t0, h0), (t1, h1)) = (pair[0], pair[1]);
            if t1 < from || t0 > t {
                continue;
            }
            consider(t0, h0);
            consider(t1, h1);
            if (h0 - top) * (h1 - top) < 0.0 {
                let u = (top - h0) / (h1 - h0);
                consider(t0 + u * (t1 - t0), top);
            }
        }
        if let Some(&(tl, hl)) = sea_height_history.last() {
            consider(tl, hl);
        }
        Ok(best.clamp(0.0, 1.0))
    }
}

/// The sea height at `tau` from increasing samples: interpolated inside, held after the end,
/// `None` before the beginning.
fn sea_at(history: &[(f64, f64)], tau: f64) -> Option<f64> {
    let first = history.first()?;
    if tau < first.0 {
        return None;
    }
    let after = history.partition_point(|&(ts, _)| ts <= tau);
    if after >= history.len() {
        return history.last().map(|&(_, h)| h);
    }
    let (t0, h0) = history[after - 1];
    let (t1, h1) = history[after];
    let u = (tau - t0) / (t1 - t0);
    Some(h0 + u * (h1 - h0))
}

/// A bearing in degrees normalised to `[0, 360)`.
fn normalised_deg(value: f64) -> f64 {
    let r = value.rem_euclid(360.0);
    if r >= 360.0 {
        0.0
    } else {
        r
    }
}

/// The true bearing readout for a view heading in degrees true (finite), normalised to
/// `[0, 360)`.
pub fn true_bearing_deg(view_heading_deg: f64) -> Result<f64, SeaError> {
    let h = checked(
        "view_heading_deg",
        view_heading_deg,
        -1.0e9,
        1.0e9,
        "finite, |heading| <= 1e9 deg",
    )?;
    Ok(normalised_deg(h))
}

/// The relative bearing (from the ship's head, clockwise) of a view heading, both in degrees
/// true, normalised to `[0, 360)`.
pub fn relative_bearing_deg(view_heading_deg: f64, ship_heading_deg: f64) -> Result<f64, SeaError> {
    let v = true_bearing_deg(view_heading_deg)?;
    let s = checked(
        "ship_heading_deg",
        ship_heading_deg,
        -1.0e9,
        1.0e9,
        "finite, |heading| <= 1e9 deg",
    )?;
    Ok(normalised_deg(v - normalised_deg(s)))
}

/// One graduation of the reticle's horizontal line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReticleTick {
    /// Angle from the centre of the field, degrees (positive right).
    pub angle_deg: f64,
    /// Whether it is a major (long, every fifth) graduation; the centre is major.
    pub major: bool,
}

/// The steps between reticle graduations that [`reticle_ticks`] chooses from, degrees.
const RETICLE_STEPS_DEG: [f64; 9] = [0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0];

/// Intervals of the reticle across the field, at most.
const RETICLE_MAX_INTERVALS: f64 = 40.0;

/// The step between reticle graduations for a field of view, degrees: the smallest of
/// 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10 and 20 that puts at most 40 intervals across the field.
pub fn reticle_step_deg(fov_deg: f64) -> Result<f64, SeaError> {
    let fov = field(fov_deg)?;
    let wanted = fov / RETICLE_MAX_INTERVALS;
    Ok(RETICLE_STEPS_DEG
        .iter()
        .copied()
        .find(|&s| s >= wanted)
        .unwrap_or(RETICLE_STEPS_DEG[RETICLE_STEPS_DEG.len() - 1]))
}

/// The graduations of the reticle's horizontal line for a field of view (0 < fov < 180),
/// left to right and symmetric about the centre, at [`reticle_step_deg`], every fifth major.
pub fn reticle_ticks(fov_deg: f64) -> Result<Vec<ReticleTick>, SeaError> {
    let step = reticle_step_deg(fov_deg)?;
    // At most 20 steps either side (40 intervals); the epsilon keeps a tick on the edge.
    let n = ((0.5 * fov_deg / step) + 1e-9).floor().clamp(0.0, 20.0) as i32;
    Ok((-n..=n)
        .map(|j| ReticleTick {
            angle_deg: f64::from(j) * step,
            major: j % 5 == 0,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_of_view_of_the_standard_powers() {
        assert_eq!(field_of_view_deg(Magnification::X1), 48.0);
        assert_eq!(field_of_view_deg(Magnification::X1_5), 32.0);
        assert_eq!(field_of_view_deg(Magnification::X6), 8.0);
        assert_eq!(field_of_view_deg(Magnification::X12), 4.0);
        let tri: Vec<f64> = Magnification::TRI_POWER
            .iter()
            .map(|m| m.field_of_view_deg())
            .collect();
        assert_eq!(tri, vec![32.0, 8.0, 4.0]);
        assert_eq!(Magnification::new(3.0).unwrap().field_of_view_deg(), 16.0);
        assert_eq!(Magnification::new(40.0).unwrap().power(), 40.0);
    }

    #[test]
    fn a_100_m_ship_at_20_km_on_1024_pixels() {
        for (fov, want) in [(48.0, 6.0), (32.0, 9.0), (8.0, 37.0)] {
            let px = pixels_subtended(100.0, 20_000.0, fov, 1024).unwrap();
            assert_eq!(px.round(), want, "{fov}°: {px}");
        }
    }

    #[test]
    fn stadimeter_round_trip() {
        let angle = Stadimeter::subtended_deg(30.0, 5000.0).unwrap();
        let range = Stadimeter::range_m(30.0, angle).unwrap();
        assert!((range - 5000.0).abs() < 1e-6, "{range}");
        // 30 m at 5 km subtends 0.344°, 20.6 minutes of arc.
        assert!((angle * 60.0 - 20.63).abs() < 0.01, "{angle}");
    }

    #[test]
    fn stadimeter_in_whole_pixels_is_within_5_percent_at_5_km() {
        let (fov, w) = (8.0, 1024);
        let true_px = pixels_subtended(30.0, 5000.0, fov, w).unwrap();
        let measured = true_px.round();
        assert_eq!(measured, 44.0, "{true_px}");
        let range = Stadimeter::range_from_pixels_m(30.0, measured, fov, w).unwrap();
        let error = (range - 5000.0).abs() / 5000.0;
        let bound = Stadimeter::quantisation_error_fraction(measured).unwrap();
        assert!(bound < 0.05, "bound {bound}");
        assert!(error <= bound + 1e-12, "error {error} over bound {bound}");
        // The bound holds for any true span within half a pixel of the measured one.
        for k in 0..=20 {
            let p = measured - 0.5 + f64::from(k) / 20.0;
            let truth = Stadimeter::range_from_pixels_m(30.0, p, fov, w).unwrap();
            let err = (range - truth).abs() / truth;
            assert!(err <= bound + 1e-12, "{p}: {err} > {bound}");
        }
    }

    #[test]
    fn wash_over_covers_then_drains() {
        let wash = WashOver::DEFAULT;
        let head = 0.0;
        // The sea stands 0.5 m over the head until t = 10 s, then falls to 0.5 m below it
        // by 10.1 s and stays there.
        let history: Vec<(f64, f64)> = (0..=200)
            .map(|i| {
                let t = f64::from(i) * 0.1;
                let h = if t <= 10.0 { 0.5 } else { -0.5 };
                (t, h)
            })
            .collect();
        let cov = |t: f64| wash.coverage(head, &history, t).unwrap();
        assert_eq!(cov(5.0), 1.0);
        assert_eq!(cov(10.0), 1.0);
        // Draining: strictly between 0 and 1, falling.
        let a = cov(10.3);
        let b = cov(10.6);
        assert!(0.0 < b && b < a && a < 1.0, "{a} {b}");
        // Long after clearing, dry.
        assert_eq!(cov(12.0), 0.0);
        assert_eq!(cov(20.0), 0.0);
        // Before the history begins, and with no history, dry.
        assert_eq!(cov(-1.0), 0.0);
        assert_eq!(wash.coverage(head, &[], 3.0).unwrap(), 0.0);
        // Half the window under water with a steady sea: half covered.
        let steady = [(0.0, 0.0), (10.0, 0.0)];
        let half = wash.coverage(0.0, &steady, 5.0).unwrap();
        assert!((half - 0.5).abs() < 1e-12, "{half}");
        // Submerged head (held after the last sample).
        assert_eq!(wash.coverage(-2.0, &steady, 50.0).unwrap(), 1.0);
    }

    #[test]
    fn mount_and_bearings() {
        let m = PeriscopeMount::new(1.5, 200.0).unwrap();
        assert_eq!(m.height_above_sea_m(), 1.5);
        assert!(!m.is_submerged(0.3));
        assert!(m.is_submerged(1.6));
        assert!(PeriscopeMount::new(-18.0, 200.0).is_ok());
        assert!(PeriscopeMount::new(30.0, 50.0).is_ok());
        assert_eq!(true_bearing_deg(370.0).unwrap(), 10.0);
        assert_eq!(true_bearing_deg(-90.0).unwrap(), 270.0);
        assert_eq!(true_bearing_deg(360.0).unwrap(), 0.0);
        assert_eq!(true_bearing_deg(-1e-15).unwrap(), 0.0);
        assert_eq!(relative_bearing_deg(10.0, 350.0).unwrap(), 20.0);
        assert_eq!(relative_bearing_deg(350.0, 10.0).unwrap(), 340.0);
    }

    #[test]
    fn reticle_graduations() {
        for (fov, step, count) in [
            (48.0, 2.0, 25),
            (32.0, 1.0, 33),
            (8.0, 0.2, 41),
            (4.0, 0.1, 41),
        ] {
            assert_eq!(reticle_step_deg(fov).unwrap(), step, "{fov}");
            let ticks = reticle_ticks(fov).unwrap();
            assert_eq!(ticks.len(), count, "{fov}");
            let first = ticks[0];
            let last = ticks[ticks.len() - 1];
            assert!(first.angle_deg >= -0.5 * fov - 1e-9 && last.angle_deg <= 0.5 * fov + 1e-9);
            assert_eq!(first.angle_deg, -last.angle_deg);
            let centre = ticks[ticks.len() / 2];
            assert_eq!(centre.angle_deg, 0.0);
            assert!(centre.major);
            let majors = ticks.iter().filter(|t| t.major).count();
            assert!(majors >= 3, "{fov}: {majors}");
        }
    }

    #[test]
    fn bad_input_is_refused() {
        for m in [0.0, -1.0, 40.5, f64::NAN, f64::INFINITY] {
            assert!(Magnification::new(m).is_err(), "{m}");
        }
        assert!(Stadimeter::range_m(0.0, 1.0).is_err());
        assert!(Stadimeter::range_m(30.0, 0.0).is_err());
        assert!(Stadimeter::range_m(30.0, 90.0).is_err());
        assert!(Stadimeter::range_m(f64::NAN, 1.0).is_err());
        assert!(Stadimeter::subtended_deg(30.0, 0.0).is_err());
        assert!(Stadimeter::quantisation_error_fraction(0.0).is_err());
        assert!(pixels_subtended(100.0, 0.0, 8.0, 1024).is_err());
        assert!(pixels_subtended(100.0, 1000.0, 0.0, 1024).is_err());
        assert!(pixels_subtended(100.0, 1000.0, 180.0, 1024).is_err());
        assert!(pixels_subtended(100.0, 1000.0, 8.0, 0).is_err());
        assert!(pixels_subtended(-1.0, 1000.0, 8.0, 1024).is_err());
        assert!(angle_of_pixels_deg(2000.0, 8.0, 1024).is_err());
        assert!(PeriscopeMount::new(31.0, 100.0).is_err());
        assert!(PeriscopeMount::new(-101.0, 100.0).is_err());
        assert!(PeriscopeMount::new(1.0, -5.0).is_err());
        assert!(PeriscopeMount::new(f64::NAN, 100.0).is_err());
        assert!(WashOver::new(0.0, 1.0).is_err());
        assert!(WashOver::new(0.1, 0.0).is_err());
        let wash = WashOver::DEFAULT;
        assert!(wash.coverage(0.0, &[(1.0, 0.0), (1.0, 0.0)], 1.0).is_err());
        assert!(wash.coverage(0.0, &[(2.0, 0.0), (1.0, 0.0)], 1.0).is_err());
        assert!(wash.coverage(0.0, &[(f64::NAN, 0.0)], 1.0).is_err());
        assert!(wash.coverage(0.0, &[(0.0, f64::NAN)], 1.0).is_err());
        assert!(wash.coverage(f64::NAN, &[], 1.0).is_err());
        assert!(wash.coverage(0.0, &[], f64::INFINITY).is_err());
        assert!(true_bearing_deg(f64::NAN).is_err());
        assert!(relative_bearing_deg(0.0, f64::INFINITY).is_err());
        assert!(reticle_ticks(0.0).is_err());
        assert!(reticle_ticks(f64::NAN).is_err());
    }
}
