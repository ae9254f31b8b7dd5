//! Level-of-detail management of models by the detail control parameter of the GE study of
//! level of detail (source 004, §4.4-4.8 and the tentative specification of §6).
//!
//! # The algorithm
//!
//! For each model in each view a **detail control parameter** `N_e` is computed, the number of
//! display resolution elements its critical radius subtends:
//!
//! - 3-D models (Eq 16): `N_e = K_LOD · r_c / R_s · f(v)`, with `r_c` the critical radius,
//!   `R_s` the slant range and `K_LOD = 1 / tan(A_o)`, `A_o = FOV / width` the angle of one
//!   resolution element (degrees). A 40° channel of 1024 elements gives `K_LOD` = 1467 (§4.8.2).
//! - 2-D models and faces seen at low angles (Eq 17):
//!   `N_e = K_LOD · r_e H / (R_s² − r_e R_g) · f(v)` with `H` the eye's height above the face,
//!   `R_g` the ground range and `r_e` the effective radius of the ellipse of long radius `r_l`
//!   and short radius `r_s` at the angle `θ` from the long radius (Eq 15):
//!   `r_e² = r_l² r_s² / (r_s² cos²θ + r_l² sin²θ)`. Where the denominator is not positive
//!   the eye is over the face: full detail.
//! - `f(v)` removes a model when its fading in the fog reaches 98 % (§4.4): 1 below, 0 from
//!   there on ([`visibility_factor`]). The fade is `1 − t`, `t` the transmittance of the fog
//!   the renderer applies ([`crate::Fog::factor`], whichever of its modes); for the default
//!   exponential fog that is Koschmieder's `t = exp(−3.912 R / V)` ([`fog_fade`]), so a model
//!   goes at the meteorological visibility `V`, where it keeps 2 % of its contrast.
//! - **Area of interest** (§3.4, §6.1): `N_e` is multiplied by [`aoi_factor`] of the angle
//!   between the model and the view's point of interest (the view's centre by default): 1
//!   within `inner_deg`, falling along a smoothstep to `periphery_factor` at `outer_deg`, and
//!   that beyond. Smooth in the angle, so a turning view changes detail gradually.
//!
//! # Level selection
//!
//! The table of `N_e` per level-of-detail step follows the square law of Eq 18,
//! `T(s) = K s²` for `s = 1..=steps` (Table 3: `K` = 1.5, eight steps, 1.5 to 96). The step
//! of a value ([`DetailTable::step_of`]) is the largest whose table value it reaches; below
//! step 1 it is 0. Steps map onto a model's levels (finest first) by
//! `level(s) = ⌊(S − s) · n / S⌋` for `S` steps and `n` levels: with Table 3 and the three
//! levels of cig's models, steps 6-8 (`N_e` ≥ 54) draw the finest level, steps 3-5
//! (`N_e` ≥ 13.5) the middle one and steps 1-2 the coarsest, close to the fixed projected
//! diameters (120 and 24 px) this replaces.
//!
//! Each interval `[T(s), T(s+1))` is, as in §6.2, a pure zone followed by a combination zone:
//! the lower `1 − blend_fraction` of it draws step `s`'s level alone, the upper
//! `blend_fraction` blends in step `s + 1`'s level with a share rising linearly in `N_e`
//! from 0 to 1 at `T(s+1)` (§6.3: `N_e` = 6.75 on a 6-9 zone is .75 of one level and .25 of the
//! next). §6.2's own figures open each interval with its combination zone, a third to 0.4 of
//! it long; here it closes the interval, so the step a value reaches is drawn pure at its
//! table value. Default `blend_fraction` 0.5. The renderer draws the two levels on
//! complementary dithered shares of the model's pixels. Below step 1 the coarsest level fades
//! out: it covers a share `N_e / T(1)` of its pixels, so a model disappears gradually at its
//! farthest range instead of popping.
//!
//! # Limits
//!
//! `f(v)` is a step, as in the study: the model goes with 2 % of its contrast left. The fog
//! is the global one: a ground fog layer does not remove models. The area-of-interest curve
//! is a tunable choice (the study leaves it open, §5.2), and its point of interest is the
//! view's centre with no time lag (no eye tracker moves it yet). `K_LOD` is the view's, lowered
//! under load by [`crate::overload`] (Table 4) except for cue-important models (§4.6).

/// Table 3's square-law constant: `N_e = 1.5 step²`.
pub const TABLE3_K: f64 = 1.5;

/// Table 3's number of steps.
pub const TABLE3_STEPS: u32 = 8;

/// The fade in fog at which a model is removed (§4.4: "approximately 98%").
pub const REMOVAL_FADE: f64 = 0.98;

/// Koschmieder's constant `−ln 0.02` (as [`crate::lighting::KOSCHMIEDER`]).
const KOSCHMIEDER: f64 = crate::lighting::KOSCHMIEDER;

/// `K_LOD = 1 / tan(A_o)` with `A_o = fov_deg / width_px` degrees, the angle of one
/// resolution element (§4.8.2: 40°, 1024 px → 1467). Not finite or not positive when the
/// inputs are not (the callers validate).
pub fn klod(fov_deg: f64, width_px: f64) -> f64 {
    1.0 / (fov_deg / width_px).to_radians().tan()
}

/// Eq 16: `N_e = K_LOD r_c / R_s f(v)` for a 3-D model. A range of zero or less (the eye at
/// the model) is infinite detail while the model is visible; `f(v)` = 0 gives 0.
pub fn ne_3d(klod: f64, critical_radius_m: f64, slant_range_m: f64, visibility_factor: f64) -> f64 {
    if visibility_factor <= 0.0 || critical_radius_m <= 0.0 {
        return 0.0;
    }
    if slant_range_m <= 0.0 {
        return f64::INFINITY;
    }
    klod * critical_radius_m / slant_range_m * visibility_factor
}

/// Eq 15: the radius of the ellipse of radii `long_m` and `short_m` at `theta_deg` from the
/// long radius (the long radius at 0°, the short at 90°).
pub fn effective_radius_m(long_m: f64, short_m: f64, theta_deg: f64) -> f64 {
    let (s, c) = theta_deg.to_radians().sin_cos();
    let denominator = (short_m * c).powi(2) + (long_m * s).powi(2);
    if denominator <= 0.0 {
        return 0.0;
    }
    (long_m * short_m).abs() / denominator.sqrt()
}

/// Eq 17: `N_e = K_LOD r_e H / (R_s² − r_e R_g) f(v)` for a flat model or face of effective
/// radius `r_e` seen from `height_m` above its plane. An eye at or below the plane sees
/// nothing of it (0); where the denominator is not positive the eye is over the face (infinite
/// detail while visible).
pub fn ne_2d(
    klod: f64,
    effective_radius_m: f64,
    height_m: f64,
    slant_range_m: f64,
    ground_range_m: f64,
    visibility_factor: f64,
) -> f64 {
    if visibility_factor <= 0.0 || effective_radius_m <= 0.0 || height_m <= 0.0 {
        return 0.0;
    }
    let denominator = slant_range_m * slant_range_m - effective_radius_m * ground_range_m;
    if denominator <= 0.0 {
        return f64::INFINITY;
    }
    klod * effective_radius_m * height_m / denominator * visibility_factor
}

/// `f(v)`: 1 while the model's fade in the fog is below 98 %, 0 from there on.
pub fn visibility_factor(fade: f64) -> f64 {
    if fade >= REMOVAL_FADE {
        0.0
    } else {
        1.0
    }
}

/// The fade of a model at `range_m` in the exponential fog of meteorological visibility
/// `visibility_m` (Koschmieder): `1 − exp(−3.912 R / V)`, 0.98 at `R = V`. The renderer takes
/// `1 − Fog::factor` of the frame's fog instead, the same in this mode.
pub fn fog_fade(range_m: f64, visibility_m: f64) -> f64 {
    1.0 - (-KOSCHMIEDER * range_m.max(0.0) / visibility_m.max(1e-9)).exp()
}

/// Which levels of a model to draw and how they share its pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodBlend {
    /// The finer level drawn (the only one when `coarser` is `None`).
    pub finer: usize,
    /// The coarser level blended in, within a combination zone.
    pub coarser: Option<usize>,
    /// Share of the drawn pixels the finer level covers, 0..1 (1 without a blend).
    pub finer_share: f32,
    /// Share of the model's pixels drawn at all: 1, except while the model fades out below
    /// step 1 (0 where it is gone).
    pub coverage: f32,
}

impl LodBlend {
    /// One level drawn whole.
    pub fn single(level: usize) -> LodBlend {
        LodBlend {
            finer: level,
            coarser: None,
            finer_share: 1.0,
            coverage: 1.0,
        }
    }
}

/// Why a detail table or area of interest was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DetailError {
    #[error("the table's constant {0} must be positive and finite")]
    Constant(f64),
    #[error("the table's step count {0} must lie in 1..=64")]
    Steps(u32),
    #[error("the blend fraction {0} must lie in 0..=1")]
    BlendFraction(f64),
    #[error("K_LOD {0} must be positive and finite")]
    Klod(f64),
    #[error("the area of interest must have 0 <= inner <= outer degrees and a periphery factor in 0..=1 (inner {inner}, outer {outer}, factor {factor})")]
    AreaOfInterest { inner: f64, outer: f64, factor: f64 },
}

/// The table of `N_e` per level-of-detail step, `T(s) = k s²` (Eq 18, Table 3), and the
/// selection of a model's levels from it (§6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetailTable {
    k: f64,
    steps: u32,
    blend_fraction: f64,
}

impl Default for DetailTable {
    /// Table 3: 1.5 step², eight steps; half of each interval blended.
    fn default() -> Self {
        DetailTable {
            k: TABLE3_K,
            steps: TABLE3_STEPS,
            blend_fraction: 0.5,
        }
    }
}

impl DetailTable {
    /// A square-law table `k s²` of `steps` steps (1..=64), with the upper `blend_fraction`
    /// (0..=1) of each interval a combination zone.
    pub fn new(k: f64, steps: u32, blend_fraction: f64) -> Result<DetailTable, DetailError> {
        if !(k.is_finite() && k > 0.0) {
            return Err(DetailError::Constant(k));
        }
        if !(1..=64).contains(&steps) {
            return Err(DetailError::Steps(steps));
        }
        if !(0.0..=1.0).contains(&blend_fraction) {
            return Err(DetailError::BlendFraction(blend_fraction));
        }
        Ok(DetailTable {
            k,
            steps,
            blend_fraction,
        })
    }

    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// `T(step) = k step²`.
    pub fn value(&self, step: u32) -> f64 {
        self.k * f64::from(step) * f64::from(step)
    }

    /// The largest step whose table value `ne` reaches; 0 below step 1 (and for NaN).
    pub fn step_of(&self, ne: f64) -> u32 {
        (1..=self.steps)
            .rev()
            .find(|&s| ne >= self.value(s))
            .unwrap_or(0)
    }

    /// The model level (0 finest) of `step` (1..=steps) for a model of `levels` levels:
    /// `⌊(steps − step) · levels / steps⌋`.
    pub fn level_of_step(&self, step: u32, levels: usize) -> usize {
        let s = step.clamp(1, self.steps);
        let level = (self.steps - s) as usize * levels / self.steps as usize;
        level.min(levels.saturating_sub(1))
    }

    /// The combination zone below `T(step)`, where `step`'s level blends in over step
    /// `step − 1`'s (for `step` in 2..=steps): `(start, end)` in `N_e`.
    pub fn blend_zone(&self, step: u32) -> (f64, f64) {
        let high = self.value(step);
        let low = self.value(step.saturating_sub(1));
        (high - self.blend_fraction * (high - low), high)
    }

    /// The levels of a model of `model_levels` levels to draw at `ne`, and their shares
    /// (see the module's documentation). Depends on `ne` alone, so every frame and every IG
    /// agrees.
    pub fn levels_for(&self, ne: f64, model_levels: usize) -> LodBlend {
        self.blend_at(
            ne,
            self.step_of(ne),
            |step| self.level_of_step(step, model_levels),
            |step| self.blend_zone(step),
        )
    }

    /// [`Self::levels_for`] at `step` (`step_of(ne)`), with each step's level and
    /// combination zone from `level_of` and `zone`.
    #[inline(always)]
    fn blend_at(
        &self,
        ne: f64,
        step: u32,
        level_of: impl Fn(u32) -> usize,
        zone: impl Fn(u32) -> (f64, f64),
    ) -> LodBlend {
        if step == 0 {
            let coverage = if ne > 0.0 {
                (ne / self.value(1)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return LodBlend {
                coverage: coverage as f32,
                ..LodBlend::single(level_of(1))
            };
        }
        let level = level_of(step);
        if step >= self.steps {
            return LodBlend::single(level);
        }
        let next = level_of(step + 1);
        if next == level {
            return LodBlend::single(level);
        }
        let (start, end) = zone(step + 1);
        if ne <= start || end <= start {
            return LodBlend::single(level);
        }
        let share = ((ne - start) / (end - start)).clamp(0.0, 1.0);
        LodBlend {
            finer: next,
            coarser: Some(level),
            finer_share: share as f32,
            coverage: 1.0,
        }
    }
}

/// [`DetailTable::levels_for`] for models of one level count, each step's level and
/// combination zone worked out once: the same answers without the per-call integer divisions
/// and search (a selection per object of a dense scene).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelLookup {
    table: DetailTable,
    /// The level of each step 0..=64 (step 0 as step 1).
    level_of_step: [usize; 65],
    /// The combination zone below each step 2..=64 (`blend_zone`).
    zone: [(f64, f64); 65],
    /// Each step's table value.
    value: [f64; 65],
    levels: usize,
}

impl LevelLookup {
    pub fn new(table: &DetailTable, model_levels: usize) -> LevelLookup {
        let mut level_of_step = [0; 65];
        let mut zone = [(0.0, 0.0); 65];
        let mut value = [0.0; 65];
        for step in 0..=table.steps {
            level_of_step[step as usize] = table.level_of_step(step, model_levels);
            zone[step as usize] = table.blend_zone(step);
            value[step as usize] = table.value(step);
        }
        LevelLookup {
            table: *table,
            level_of_step,
            zone,
            value,
            levels: model_levels,
        }
    }

    /// As [`DetailTable::levels_for`] with this lookup's level count.
    pub fn levels_for(&self, ne: f64) -> LodBlend {
        self.table.blend_at(
            ne,
            self.step_of(ne),
            |step| self.level_of_step[step as usize],
            |step| self.zone[step as usize],
        )
    }

    pub fn table(&self) -> &DetailTable {
        &self.table
    }

    /// As [`DetailTable::step_of`]: the steps whose value `ne` reaches, counted without a
    /// branch (the values grow with the step; NaN reaches none).
    pub fn step_of(&self, ne: f64) -> u32 {
        let steps = self.table.steps as usize;
        self.value[1..=steps]
            .iter()
            .map(|&v| u32::from(ne >= v))
            .sum()
    }

    /// The coarsest level of the models.
    pub fn coarsest(&self) -> usize {
        self.levels.saturating_sub(1)
    }
}

/// The area of interest's fall-off of detail with the angle from the point of interest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaOfInterest {
    /// Full detail within this angle, degrees.
    pub inner_deg: f64,
    /// The periphery's factor from this angle on, degrees.
    pub outer_deg: f64,
    /// The factor on `N_e` in the periphery, 0..=1.
    pub periphery_factor: f64,
}

impl Default for AreaOfInterest {
    /// Full detail within 10°, half the `N_e` beyond 45° (a 60° view's edge, 30° out, keeps
    /// about 0.7).
    fn default() -> Self {
        AreaOfInterest {
            inner_deg: 10.0,
            outer_deg: 45.0,
            periphery_factor: 0.5,
        }
    }
}

impl AreaOfInterest {
    pub fn validate(&self) -> Result<(), DetailError> {
        let ok = self.inner_deg.is_finite()
            && self.outer_deg.is_finite()
            && 0.0 <= self.inner_deg
            && self.inner_deg <= self.outer_deg
            && (0.0..=1.0).contains(&self.periphery_factor);
        if ok {
            Ok(())
        } else {
            Err(DetailError::AreaOfInterest {
                inner: self.inner_deg,
                outer: self.outer_deg,
                factor: self.periphery_factor,
            })
        }
    }
}

/// The factor on `N_e` of a model `angle_deg` from the point of interest: 1 within
/// `inner_deg`, then `1 − (1 − periphery) · smoothstep(inner, outer, angle)`, the periphery's
/// factor beyond `outer_deg`. Continuous and non-increasing in the angle.
pub fn aoi_factor(angle_from_point_of_interest_deg: f64, aoi: &AreaOfInterest) -> f64 {
    let a = angle_from_point_of_interest_deg.abs();
    if a.is_nan() || a <= aoi.inner_deg {
        return 1.0;
    }
    if a >= aoi.outer_deg {
        return aoi.periphery_factor;
    }
    let t = (a - aoi.inner_deg) / (aoi.outer_deg - aoi.inner_deg);
    let smooth = t * t * (3.0 - 2.0 * t);
    1.0 - (1.0 - aoi.periphery_factor) * smooth
}

/// [`aoi_factor`] tabulated against the cosine of the angle from the point of interest, for a
/// factor per object of a dense scene without an arc cosine: linear between 257 samples even
/// in the cosine from the inner cone's edge to the outer's (within 1e-3 of the exact factor).
///
/// The angle is not smooth in its cosine at 0° and 180° (it goes as the square root of the
/// cosine's distance from ±1), so within four samples of either end the factor is worked out
/// exactly, with the arc cosine: there a straight line between samples would be degrees off.
#[derive(Clone, Debug, PartialEq)]
pub struct AoiByCosine {
    cos_inner: f64,
    cos_outer: f64,
    samples_per_unit: f64,
    /// Cosines below or above these are within four samples of ±1: worked out exactly.
    exact_below: f64,
    exact_above: f64,
    aoi: AreaOfInterest,
    samples: [f64; AOI_SAMPLES + 1],
}

const AOI_SAMPLES: usize = 256;

impl AoiByCosine {
    pub fn new(aoi: &AreaOfInterest) -> AoiByCosine {
        let cos_inner = aoi.inner_deg.clamp(0.0, 180.0).to_radians().cos();
        let cos_outer = aoi.outer_deg.clamp(0.0, 180.0).to_radians().cos();
        let span = cos_inner - cos_outer;
        let samples_per_unit = if span > 0.0 {
            AOI_SAMPLES as f64 / span
        } else {
            0.0
        };
        let mut samples = [aoi.periphery_factor; AOI_SAMPLES + 1];
        if span > 0.0 {
            for (i, sample) in samples.iter_mut().enumerate() {
                let cos = (cos_outer + i as f64 / samples_per_unit).clamp(-1.0, 1.0);
                *sample = aoi_factor(cos.acos().to_degrees(), aoi);
            }
        }
        let near_an_end = 4.0 * span / AOI_SAMPLES as f64;
        AoiByCosine {
            cos_inner,
            cos_outer,
            samples_per_unit,
            exact_below: -1.0 + near_an_end,
            exact_above: 1.0 - near_an_end,
            aoi: *aoi,
            samples,
        }
    }

    /// The factor for a model whose direction's cosine with the point of interest's is `cos`
    /// (1 for NaN, as [`aoi_factor`]).
    pub fn factor(&self, cos: f64) -> f64 {
        if cos.is_nan() || cos >= self.cos_inner {
            return 1.0;
        }
        if cos <= self.cos_outer && self.aoi.outer_deg <= 180.0 {
            return self.aoi.periphery_factor;
        }
        if cos < self.exact_below || cos > self.exact_above {
            return aoi_factor(cos.clamp(-1.0, 1.0).acos().to_degrees(), &self.aoi);
        }
        let x = (cos - self.cos_outer) * self.samples_per_unit;
        let i = (x as usize).min(AOI_SAMPLES - 1);
        let low = self.samples[i];
        low + (self.samples[i + 1] - low) * (x - i as f64)
    }
}

/// What a renderer needs to choose models' levels: the table, an optional fixed `K_LOD` (else
/// each view's own) and the area of interest (none: the same detail across the view).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DetailSettings {
    pub table: DetailTable,
    /// Overrides the view's `K_LOD`.
    pub klod: Option<f64>,
    pub aoi: Option<AreaOfInterest>,
}

impl DetailSettings {
    /// The default table and area of interest.
    pub fn standard() -> DetailSettings {
        DetailSettings {
            table: DetailTable::default(),
            klod: None,
            aoi: Some(AreaOfInterest::default()),
        }
    }

    /// `K_LOD` for a view: the override, else from its horizontal field of view and width.
    pub fn klod_for(&self, view: &crate::View) -> f64 {
        self.klod.unwrap_or_else(|| {
            klod(
                view.fov.left_deg + view.fov.right_deg,
                f64::from(view.width_px),
            )
        })
    }

    /// `N_e` of a 3-D model: Eq 16 with `f(v)` of its fade, times the area of interest's
    /// factor at `angle_deg` from the point of interest.
    pub fn ne(
        &self,
        klod: f64,
        critical_radius_m: f64,
        slant_range_m: f64,
        fade: f64,
        angle_deg: f64,
    ) -> f64 {
        let ne = ne_3d(
            klod,
            critical_radius_m,
            slant_range_m,
            visibility_factor(fade),
        );
        match &self.aoi {
            Some(aoi) => ne * aoi_factor(angle_deg, aoi),
            None => ne,
        }
    }
}

/// Checks a `K_LOD` given from outside (positive and finite).
pub fn validate_klod(klod: f64) -> Result<f64, DetailError> {
    if klod.is_finite() && klod > 0.0 {
        Ok(klod)
    } else {
        Err(DetailError::Klod(klod))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn aoi_by_cosine_is_within_1e3_of_the_exact_factor(
            inner in prop_oneof![0.0f64..200.0, Just(0.0), 170.0f64..180.0],
            width in prop_oneof![0.0f64..120.0, 0.0f64..2.0],
            periphery in 0.0f64..=1.0,
            angle in prop_oneof![0.0f64..180.0, 179.0f64..=180.0, 0.0f64..1.0],
        ) {
            let aoi = AreaOfInterest { inner_deg: inner, outer_deg: inner + width, periphery_factor: periphery };
            let table = AoiByCosine::new(&aoi);
            let cos = angle.to_radians().cos();
            let exact = aoi_factor(cos.clamp(-1.0, 1.0).acos().to_degrees(), &aoi);
            prop_assert!((table.factor(cos) - exact).abs() < 1e-3, "{} against {exact}", table.factor(cos));
        }
    }

    #[test]
    fn aoi_by_cosine_is_exact_enough_next_to_the_back_of_the_sphere() {
        // Found by the property above when the table stopped at the cosine's -1: there the angle
        // is the square root of the cosine's distance from -1, no straight line.
        let aoi = AreaOfInterest {
            inner_deg: 116.533_446_208_583_8,
            outer_deg: 116.533_446_208_583_8 + 108.913_939_432_155_27,
            periphery_factor: 0.0,
        };
        let table = AoiByCosine::new(&aoi);
        for angle in [
            170.0,
            175.0,
            178.0,
            179.0,
            179.590_727_812_212_92,
            179.9,
            180.0,
        ] {
            let cos = f64::to_radians(angle).cos();
            let exact = aoi_factor(angle, &aoi);
            assert!(
                (table.factor(cos) - exact).abs() < 1e-3,
                "{angle}°: {} against {exact}",
                table.factor(cos)
            );
        }
    }

    #[test]
    fn aoi_by_cosine_keeps_the_cone_and_the_periphery() {
        let aoi = AreaOfInterest::default();
        let table = AoiByCosine::new(&aoi);
        assert_eq!(table.factor(1.0), 1.0);
        assert_eq!(table.factor(5f64.to_radians().cos()), 1.0);
        assert_eq!(table.factor(f64::NAN), 1.0);
        assert_eq!(table.factor(60f64.to_radians().cos()), 0.5);
        assert_eq!(table.factor(-1.0), 0.5);
        let mid = table.factor(27.5f64.to_radians().cos());
        assert!((mid - 0.75).abs() < 1e-3, "{mid}");
    }

    proptest! {
        #[test]
        fn level_lookup_answers_as_the_table(
            k in 0.01f64..100.0,
            steps in 1u32..=64,
            blend in 0.0f64..=1.0,
            levels in 1usize..8,
            ne in prop_oneof![-1.0f64..1e5, Just(f64::INFINITY), Just(f64::NAN)],
        ) {
            let t = DetailTable::new(k, steps, blend).expect("valid table");
            let lookup = LevelLookup::new(&t, levels);
            prop_assert_eq!(lookup.step_of(ne), t.step_of(ne));
            let on = t.value(steps.min(1 + (k * 7.0) as u32));
            prop_assert_eq!(lookup.step_of(on), t.step_of(on));
            let (a, b) = (lookup.levels_for(ne), t.levels_for(ne, levels));
            prop_assert!(a == b || (a.coverage.is_nan() && b.coverage.is_nan()), "{a:?} {b:?}");
        }
    }

    #[test]
    fn klod_of_the_worked_example_is_1467() {
        let k = klod(40.0, 1024.0);
        assert!((k - 1467.0).abs() < 0.5, "{k}");
    }

    #[test]
    fn table_3_values() {
        let t = DetailTable::default();
        let expected = [1.5, 6.0, 13.5, 24.0, 37.5, 54.0, 73.5, 96.0];
        for (s, want) in (1..=8).zip(expected) {
            assert_eq!(t.value(s), want, "step {s}");
            assert_eq!(t.step_of(want), s);
            assert_eq!(t.step_of(want - 1e-9), s - 1);
        }
        assert_eq!(t.step_of(1000.0), 8);
        assert_eq!(t.step_of(0.0), 0);
        assert_eq!(t.step_of(f64::NAN), 0);
        assert_eq!(t.step_of(f64::INFINITY), 8);
    }

    #[test]
    fn effective_radius_is_the_long_radius_at_0_and_the_short_at_90() {
        assert!((effective_radius_m(30.0, 5.0, 0.0) - 30.0).abs() < 1e-12);
        assert!((effective_radius_m(30.0, 5.0, 90.0) - 5.0).abs() < 1e-9);
        let r = effective_radius_m(30.0, 5.0, 45.0);
        assert!(r > 5.0 && r < 30.0, "{r}");
        assert_eq!(effective_radius_m(0.0, 0.0, 10.0), 0.0);
    }

    #[test]
    fn eq_17_is_guarded_and_tends_to_eq_16_from_overhead() {
        // Straight overhead (R_g = 0, H = R_s) a face of radius r subtends K r / R_s.
        let ne = ne_2d(1467.0, 10.0, 500.0, 500.0, 0.0, 1.0);
        assert!((ne - ne_3d(1467.0, 10.0, 500.0, 1.0)).abs() < 1e-9);
        assert_eq!(ne_2d(1467.0, 10.0, 5.0, 10.0, 20.0, 1.0), f64::INFINITY);
        assert_eq!(ne_2d(1467.0, 10.0, -5.0, 100.0, 90.0, 1.0), 0.0);
        assert_eq!(ne_2d(1467.0, 10.0, 5.0, 100.0, 90.0, 0.0), 0.0);
        // Grazing views shrink the face.
        assert!(ne_2d(1467.0, 10.0, 5.0, 1000.0, 999.0, 1.0) < ne_3d(1467.0, 10.0, 1000.0, 1.0));
    }

    #[test]
    fn a_model_is_removed_at_98_percent_fade() {
        assert_eq!(visibility_factor(0.979), 1.0);
        assert_eq!(visibility_factor(0.98), 0.0);
        assert_eq!(visibility_factor(0.999), 0.0);
        let v = 5000.0;
        assert!(fog_fade(0.9 * v, v) < REMOVAL_FADE);
        assert!(fog_fade(1.01 * v, v) > REMOVAL_FADE);
        // The same as the renderer's fog.
        let fog = crate::Fog::from_visibility(crate::FogMode::Exponential, v);
        for r in [10.0, 1000.0, 4999.0, 5200.0] {
            assert!((fog_fade(r, v) - (1.0 - fog.factor(r))).abs() < 1e-12);
        }
        let settings = DetailSettings::standard();
        let near = settings.ne(1467.0, 5.0, 0.9 * v, fog_fade(0.9 * v, v), 0.0);
        assert!(near > 0.0);
        let far = settings.ne(1467.0, 5.0, 1.01 * v, fog_fade(1.01 * v, v), 0.0);
        assert_eq!(far, 0.0);
        assert_eq!(settings.table.levels_for(far, 3).coverage, 0.0);
    }

    #[test]
    fn three_levels_map_steps_6_to_8_finest_3_to_5_middle_1_2_coarsest() {
        let t = DetailTable::default();
        let levels: Vec<usize> = (1..=8).map(|s| t.level_of_step(s, 3)).collect();
        assert_eq!(levels, [2, 2, 1, 1, 1, 0, 0, 0]);
        assert!((1..=8).all(|s| t.level_of_step(s, 1) == 0));
        // Pure zones and §6.3's linear share in the combination zone.
        assert_eq!(t.levels_for(60.0, 3), LodBlend::single(0));
        assert_eq!(t.levels_for(40.0, 3), LodBlend::single(1));
        assert_eq!(t.levels_for(15.0, 3), LodBlend::single(1));
        assert_eq!(t.levels_for(8.0, 3), LodBlend::single(2));
        assert_eq!(t.levels_for(5.0, 3), LodBlend::single(2));
        let (start, end) = t.blend_zone(6);
        assert_eq!((start, end), (45.75, 54.0));
        let mid = t.levels_for((start + end) / 2.0, 3);
        assert_eq!((mid.finer, mid.coarser), (0, Some(1)));
        assert!((mid.finer_share - 0.5).abs() < 1e-6);
        let low = t.levels_for(t.blend_zone(3).1 - 0.1, 3);
        assert_eq!((low.finer, low.coarser), (1, Some(2)));
        // Below step 1 the coarsest level fades out with N_e.
        let fading = t.levels_for(0.75, 3);
        assert_eq!((fading.finer, fading.coarser), (2, None));
        assert!((fading.coverage - 0.5).abs() < 1e-6);
        assert_eq!(t.levels_for(0.0, 3).coverage, 0.0);
        assert_eq!(t.levels_for(f64::NAN, 3).coverage, 0.0);
        assert_eq!(t.levels_for(f64::INFINITY, 3), LodBlend::single(0));
    }

    #[test]
    fn bad_tables_and_areas_are_refused() {
        assert!(DetailTable::new(0.0, 8, 0.5).is_err());
        assert!(DetailTable::new(f64::NAN, 8, 0.5).is_err());
        assert!(DetailTable::new(1.5, 0, 0.5).is_err());
        assert!(DetailTable::new(1.5, 8, 1.5).is_err());
        assert!(DetailTable::new(2.0, 4, 0.3).is_ok());
        assert!(validate_klod(-1.0).is_err());
        assert!(validate_klod(f64::INFINITY).is_err());
        assert!(AreaOfInterest {
            inner_deg: 20.0,
            outer_deg: 10.0,
            periphery_factor: 0.5
        }
        .validate()
        .is_err());
        assert!(AreaOfInterest::default().validate().is_ok());
    }

    #[test]
    fn the_same_model_is_finer_at_the_centre_than_at_the_edge() {
        let settings = DetailSettings::standard();
        let k = klod(60.0, 640.0);
        let at = |angle: f64| {
            settings
                .table
                .step_of(settings.ne(k, 4.0, 98.0, 0.0, angle))
        };
        assert!(at(0.0) > at(30.0), "{} vs {}", at(0.0), at(30.0));
        assert_eq!(aoi_factor(0.0, &AreaOfInterest::default()), 1.0);
        assert_eq!(aoi_factor(180.0, &AreaOfInterest::default()), 0.5);
    }

    /// How coarse a blend looks: its levels weighted by their shares.
    fn coarseness(b: LodBlend) -> f64 {
        let share = f64::from(b.finer_share);
        match b.coarser {
            Some(c) => b.finer as f64 * share + c as f64 * (1.0 - share),
            None => b.finer as f64,
        }
    }

    proptest! {
        #[test]
        fn eq_16_round_trips(r in 0.1f64..100.0, s in 1.0f64..1e5, fov in 1.0f64..170.0, w in 64u32..8192) {
            let k = klod(fov, f64::from(w));
            let ne = ne_3d(k, r, s, 1.0);
            prop_assert!((ne * s / k - r).abs() <= 1e-9 * r);
            // The range at which a given N_e is reached gives it back.
            let range = k * r / ne;
            prop_assert!((range - s).abs() <= 1e-9 * s);
        }

        #[test]
        fn levels_get_coarser_and_fade_monotonically_with_range(
            r in 0.5f64..40.0, s1 in 1.0f64..20_000.0, ds in 0.0f64..5000.0, levels in 1usize..6
        ) {
            let t = DetailTable::default();
            let k = klod(40.0, 1024.0);
            let near = t.levels_for(ne_3d(k, r, s1, 1.0), levels);
            let far = t.levels_for(ne_3d(k, r, s1 + ds, 1.0), levels);
            prop_assert!(coarseness(far) >= coarseness(near) - 1e-6, "{near:?} {far:?}");
            prop_assert!(far.coverage <= near.coverage);
            prop_assert!(near.finer_share > 0.0 && near.finer_share <= 1.0);
        }

        #[test]
        fn levels_change_continuously(ne in 0.0f64..120.0) {
            // A small change of N_e changes the drawn shares little (no pop).
            let t = DetailTable::default();
            let a = t.levels_for(ne, 3);
            let b = t.levels_for(ne + 1e-3, 3);
            prop_assert!((coarseness(a) - coarseness(b)).abs() < 0.01, "{a:?} {b:?}");
            prop_assert!((a.coverage - b.coverage).abs() < 0.01);
        }

        #[test]
        fn aoi_is_non_increasing_from_the_centre(a in 0.0f64..180.0, d in 0.0f64..30.0) {
            let aoi = AreaOfInterest::default();
            prop_assert!(aoi_factor(a + d, &aoi) <= aoi_factor(a, &aoi) + 1e-12);
            // Gradual: a degree changes the factor by little.
            prop_assert!((aoi_factor(a + 1.0, &aoi) - aoi_factor(a, &aoi)).abs() < 0.03);
        }
    }
}
