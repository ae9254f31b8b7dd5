//! Overload control of the detail control parameter, after the GE study of level of detail
//! (source 004, §4.4 and Table 4 of §4.8.2), and cue importance (§4.6).
//!
//! # The algorithm
//!
//! Each frame the IG measures counters that would break its frame time: drawn triangles,
//! drawn models and, where the backend reports it, the GPU frame time (0 means unknown and is
//! ignored). Each monitored counter has a **capacity**, a **begin-decrement** level and a
//! **begin-increment** level (`0 < increment < decrement <= capacity`), as Table 4's rows.
//! After each frame, for the next one ([`OverloadControl::update`]):
//!
//! - while any counter is above its begin-decrement level, `K_LOD` falls by the decrement step
//!   per frame, never below the floor;
//! - while every counter is below its begin-increment level, it rises by the increment step
//!   per frame, up to the nominal `K_LOD` (the view's, from its field of view and width, or a
//!   fixed one the operator gives);
//! - between the two it holds (the hysteresis that keeps it from oscillating).
//!
//! The control keeps `K_LOD` as a **fraction of the nominal**, so a view whose field of view
//! or size changes keeps its state. Steps and floor are fractions of the nominal too:
//! Table 4's fixed step of 10 is 0.7 % of the worked example's 1467 and would take about 70
//! frames to halve the detail, so the default decrement step is 10 % of the nominal (a
//! halving in five frames at 60 Hz), the increment step 5 % (recovery twice as slow as the
//! retreat, which damps the swing back into overload) and the floor 10 %. The level blend of
//! [`crate::detail`] masks the changes (§4.8.1).
//!
//! # Cue importance (§4.6)
//!
//! Models the modeler marks as important cues (the runway, the target vehicles) keep the
//! nominal `K_LOD`; everything else takes the controlled one ([`klod_for`]).
//!
//! # Limits
//!
//! The counters are the frame's, so the control acts one frame late; the drawn triangles
//! include the terrain's, which `K_LOD` does not reduce (a terrain alone over the level drives
//! the models to the floor). Light points are not counted: they do not exist yet.

/// One monitored counter's levels (a row of Table 4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CounterLimits {
    /// The system's capacity.
    pub capacity: f64,
    /// Above this `K_LOD` decrements.
    pub begin_decrement: f64,
    /// Below this (every counter) `K_LOD` increments.
    pub begin_increment: f64,
}

impl CounterLimits {
    /// Checks `0 < begin_increment < begin_decrement <= capacity`, all finite; `name` is the
    /// counter's key in errors.
    pub fn validate(&self, name: &'static str) -> Result<(), OverloadError> {
        let values = [
            ("capacity", self.capacity),
            ("begin_decrement", self.begin_decrement),
            ("begin_increment", self.begin_increment),
        ];
        for (key, value) in values {
            if !(value.is_finite() && value > 0.0) {
                return Err(OverloadError::NotPositive {
                    counter: name,
                    key,
                    value,
                });
            }
        }
        if self.begin_decrement > self.capacity {
            return Err(OverloadError::DecrementAboveCapacity {
                counter: name,
                decrement: self.begin_decrement,
                capacity: self.capacity,
            });
        }
        if self.begin_increment >= self.begin_decrement {
            return Err(OverloadError::IncrementNotBelowDecrement {
                counter: name,
                increment: self.begin_increment,
                decrement: self.begin_decrement,
            });
        }
        Ok(())
    }
}

/// Why overload settings were refused. Each message names the key (relative to the
/// settings' table).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OverloadError {
    #[error("{counter}.{key} = {value} must be positive and finite")]
    NotPositive {
        counter: &'static str,
        key: &'static str,
        value: f64,
    },
    #[error(
        "{counter}.begin_decrement = {decrement} must not exceed {counter}.capacity = {capacity}"
    )]
    DecrementAboveCapacity {
        counter: &'static str,
        decrement: f64,
        capacity: f64,
    },
    #[error("{counter}.begin_increment = {increment} must be below {counter}.begin_decrement = {decrement}")]
    IncrementNotBelowDecrement {
        counter: &'static str,
        increment: f64,
        decrement: f64,
    },
    #[error("{key} = {value} must lie in (0, 1]")]
    Fraction { key: &'static str, value: f64 },
}

/// The control's settings: the monitored counters (`None`: not monitored), the steps and the
/// floor as fractions of the nominal `K_LOD`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverloadSettings {
    pub triangles: Option<CounterLimits>,
    pub models: Option<CounterLimits>,
    /// GPU frame time, milliseconds.
    pub gpu_ms: Option<CounterLimits>,
    /// `K_LOD` falls by this fraction of the nominal per frame in overload.
    pub decrement_step: f64,
    /// `K_LOD` rises by this fraction of the nominal per frame below the increment levels.
    pub increment_step: f64,
    /// `K_LOD` never falls below this fraction of the nominal.
    pub floor: f64,
}

impl Default for OverloadSettings {
    /// Generous defaults that a normal scene never reaches: 8,192 models (the renderer's
    /// instance pool; Table 4's edge row, 8000 and 6000, scaled to it), 8 M triangles (7.8 M,
    /// 6 M), the GPU time not monitored (its budget depends on the display's frame rate); steps
    /// 10 % down and 5 % up, floor 10 %.
    fn default() -> Self {
        OverloadSettings {
            triangles: Some(CounterLimits {
                capacity: 8_000_000.0,
                begin_decrement: 7_800_000.0,
                begin_increment: 6_000_000.0,
            }),
            models: Some(CounterLimits {
                capacity: 8192.0,
                begin_decrement: 8000.0,
                begin_increment: 6000.0,
            }),
            gpu_ms: None,
            decrement_step: 0.1,
            increment_step: 0.05,
            floor: 0.1,
        }
    }
}

impl OverloadSettings {
    pub fn validate(&self) -> Result<(), OverloadError> {
        let counters = [
            ("triangles", self.triangles),
            ("models", self.models),
            ("gpu_ms", self.gpu_ms),
        ];
        for (name, limits) in counters {
            if let Some(l) = limits {
                l.validate(name)?;
            }
        }
        let fractions = [
            ("decrement_step", self.decrement_step),
            ("increment_step", self.increment_step),
            ("floor", self.floor),
        ];
        for (key, value) in fractions {
            if !(value > 0.0 && value <= 1.0) {
                return Err(OverloadError::Fraction { key, value });
            }
        }
        Ok(())
    }
}

/// One frame's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OverloadCounters {
    pub triangles: u64,
    pub models: u32,
    /// GPU frame time, milliseconds; 0 (or not finite) when the backend does not report it.
    pub gpu_ms: f64,
}

/// What the control did on its last update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OverloadAction {
    /// Some counter above its begin-decrement level.
    Decrement,
    /// Between the levels: hysteresis.
    #[default]
    Hold,
    /// Every counter below its begin-increment level.
    Increment,
}

impl OverloadAction {
    pub fn name(self) -> &'static str {
        match self {
            OverloadAction::Decrement => "decrement",
            OverloadAction::Hold => "hold",
            OverloadAction::Increment => "increment",
        }
    }
}

/// The overload control's state: `K_LOD` as a fraction of the nominal, in `[floor, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverloadControl {
    settings: OverloadSettings,
    fraction: f64,
    last: OverloadAction,
}

impl OverloadControl {
    /// A control at the nominal `K_LOD`.
    pub fn new(settings: OverloadSettings) -> Result<OverloadControl, OverloadError> {
        settings.validate()?;
        Ok(OverloadControl {
            settings,
            fraction: 1.0,
            last: OverloadAction::Hold,
        })
    }

    pub fn settings(&self) -> &OverloadSettings {
        &self.settings
    }

    /// `K_LOD` now, as a fraction of the nominal.
    pub fn fraction(&self) -> f64 {
        self.fraction
    }

    /// `K_LOD` now for a view of nominal `K_LOD` `nominal`.
    pub fn klod(&self, nominal: f64) -> f64 {
        nominal * self.fraction
    }

    /// What the last update did.
    pub fn last_action(&self) -> OverloadAction {
        self.last
    }

    /// What a frame's counters call for (see the module's documentation).
    pub fn action(&self, counters: &OverloadCounters) -> OverloadAction {
        // (value, limits); an unknown GPU time is left out.
        let gpu = (counters.gpu_ms.is_finite() && counters.gpu_ms > 0.0).then_some(counters.gpu_ms);
        let measured = [
            (Some(counters.triangles as f64), self.settings.triangles),
            (Some(f64::from(counters.models)), self.settings.models),
            (gpu, self.settings.gpu_ms),
        ];
        let monitored = measured
            .iter()
            .filter_map(|(value, limits)| Some((value.as_ref()?, limits.as_ref()?)));
        let mut all_below = true;
        for (&value, limits) in monitored {
            if value > limits.begin_decrement {
                return OverloadAction::Decrement;
            }
            if value >= limits.begin_increment {
                all_below = false;
            }
        }
        if all_below {
            OverloadAction::Increment
        } else {
            OverloadAction::Hold
        }
    }

    /// Takes a frame's counters and returns `K_LOD` for the next frame of a view of nominal
    /// `K_LOD` `nominal`: a step down in overload, a step up (to the nominal) below every
    /// increment level, unchanged between.
    pub fn update(&mut self, nominal: f64, counters: &OverloadCounters) -> f64 {
        let action = self.action(counters);
        let s = &self.settings;
        self.fraction = match action {
            OverloadAction::Decrement => (self.fraction - s.decrement_step).max(s.floor),
            OverloadAction::Hold => self.fraction,
            OverloadAction::Increment => (self.fraction + s.increment_step).min(1.0),
        };
        self.last = action;
        self.klod(nominal)
    }
}

/// `K_LOD` for a model: the nominal for cue-important models (§4.6), the controlled one for
/// the rest.
pub fn klod_for(cue_important: bool, nominal: f64, controlled: f64) -> f64 {
    if cue_important {
        nominal
    } else {
        controlled
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detail::{klod, DetailSettings};
    use proptest::prelude::*;

    fn models_only(capacity: f64, decrement: f64, increment: f64) -> OverloadSettings {
        OverloadSettings {
            triangles: None,
            models: Some(CounterLimits {
                capacity,
                begin_decrement: decrement,
                begin_increment: increment,
            }),
            ..OverloadSettings::default()
        }
    }

    fn models(n: u32) -> OverloadCounters {
        OverloadCounters {
            models: n,
            ..OverloadCounters::default()
        }
    }

    #[test]
    fn decrements_above_holds_between_increments_below() {
        let nominal = klod(40.0, 1024.0);
        let mut c = OverloadControl::new(models_only(4096.0, 4000.0, 2700.0)).expect("valid");
        // Above the decrement level: 10 % of the nominal per frame.
        let k1 = c.update(nominal, &models(4001));
        assert!((k1 - 0.9 * nominal).abs() < 1e-9);
        assert_eq!(c.last_action(), OverloadAction::Decrement);
        let k2 = c.update(nominal, &models(4096));
        assert!((k2 - 0.8 * nominal).abs() < 1e-9);
        // Between the levels (the decrement level itself included): no change, frame after frame.
        for n in [4000, 3500, 2700, 3999] {
            assert_eq!(c.update(nominal, &models(n)), k2, "{n}");
            assert_eq!(c.last_action(), OverloadAction::Hold);
        }
        // Below the increment level: 5 % per frame back up.
        let k3 = c.update(nominal, &models(2699));
        assert!((k3 - 0.85 * nominal).abs() < 1e-9);
        assert_eq!(c.last_action(), OverloadAction::Increment);
    }

    #[test]
    fn floor_and_ceiling_hold() {
        let nominal = 1467.0;
        let mut c = OverloadControl::new(models_only(10.0, 8.0, 4.0)).expect("valid");
        for _ in 0..100 {
            c.update(nominal, &models(1000));
        }
        assert!((c.klod(nominal) - 0.1 * nominal).abs() < 1e-9);
        for _ in 0..100 {
            c.update(nominal, &models(0));
        }
        assert_eq!(c.klod(nominal), nominal);
        assert_eq!(c.fraction(), 1.0);
    }

    #[test]
    fn any_counter_over_decrements_and_all_must_be_under_to_increment() {
        let settings = OverloadSettings {
            gpu_ms: Some(CounterLimits {
                capacity: 16.7,
                begin_decrement: 15.0,
                begin_increment: 12.0,
            }),
            ..OverloadSettings::default()
        };
        let mut c = OverloadControl::new(settings).expect("valid");
        let slow = OverloadCounters {
            triangles: 1000,
            models: 10,
            gpu_ms: 20.0,
        };
        assert_eq!(c.action(&slow), OverloadAction::Decrement);
        c.update(1000.0, &slow);
        // The GPU time between its levels holds even with the rest far below.
        let middling = OverloadCounters {
            gpu_ms: 13.0,
            ..slow
        };
        assert_eq!(c.action(&middling), OverloadAction::Hold);
        // An unknown GPU time (0) is ignored.
        let unknown = OverloadCounters {
            gpu_ms: 0.0,
            ..slow
        };
        assert_eq!(c.action(&unknown), OverloadAction::Increment);
    }

    #[test]
    fn bad_settings_are_refused_naming_the_key() {
        let e = OverloadControl::new(models_only(10.0, 8.0, 8.0)).expect_err("equal levels");
        assert_eq!(
            e.to_string(),
            "models.begin_increment = 8 must be below models.begin_decrement = 8"
        );
        let e = OverloadControl::new(models_only(10.0, 11.0, 8.0)).expect_err("over capacity");
        assert!(
            e.to_string().starts_with("models.begin_decrement = 11"),
            "{e}"
        );
        let e = OverloadControl::new(models_only(10.0, 8.0, -1.0)).expect_err("negative");
        assert!(
            e.to_string().starts_with("models.begin_increment = -1"),
            "{e}"
        );
        let e = OverloadControl::new(models_only(f64::NAN, 8.0, 1.0)).expect_err("NaN");
        assert!(e.to_string().starts_with("models.capacity"), "{e}");
        let e = OverloadControl::new(OverloadSettings {
            floor: 0.0,
            ..OverloadSettings::default()
        })
        .expect_err("floor");
        assert_eq!(e.to_string(), "floor = 0 must lie in (0, 1]");
        assert!(OverloadControl::new(OverloadSettings::default()).is_ok());
    }

    #[test]
    fn a_cue_important_model_keeps_its_step_under_load() {
        let nominal = klod(60.0, 640.0);
        let mut c = OverloadControl::new(models_only(100.0, 90.0, 50.0)).expect("valid");
        for _ in 0..5 {
            c.update(nominal, &models(200));
        }
        let controlled = c.klod(nominal);
        assert!(controlled < nominal);
        let detail = DetailSettings::standard();
        // Two models of the same size at the same range, one a cue.
        let step = |cue: bool| {
            let k = klod_for(cue, nominal, controlled);
            detail.table.step_of(detail.ne(k, 4.0, 80.0, 0.0, 0.0))
        };
        let unloaded = detail
            .table
            .step_of(detail.ne(nominal, 4.0, 80.0, 0.0, 0.0));
        assert_eq!(step(true), unloaded);
        assert!(step(false) < unloaded, "{} vs {unloaded}", step(false));
    }

    proptest! {
        #[test]
        fn klod_never_leaves_floor_to_nominal(
            frames in proptest::collection::vec((0u64..20_000_000, 0u32..20_000, 0.0f64..40.0), 1..200),
            nominal in 10.0f64..5000.0,
        ) {
            let settings = OverloadSettings {
                gpu_ms: Some(CounterLimits { capacity: 16.7, begin_decrement: 15.0, begin_increment: 12.0 }),
                ..OverloadSettings::default()
            };
            let mut c = OverloadControl::new(settings).expect("valid");
            for (triangles, models, gpu_ms) in frames {
                let k = c.update(nominal, &OverloadCounters { triangles, models, gpu_ms });
                prop_assert!(k >= 0.1 * nominal - 1e-9 && k <= nominal + 1e-9, "{k}");
            }
        }
    }
}
