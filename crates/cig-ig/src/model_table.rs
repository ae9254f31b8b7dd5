//! The entity-type table: which model draws an entity of a given CIGI or DIS type.
//!
//! Algorithm: CIGI 3.3 entity types (and CIGI 4.0 short types) are looked up exactly; DIS
//! entity types (and CIGI 4.0 extended types, which are DIS types) take the most specific
//! matching pattern of the scenario's table (the one with the most fields given), the earlier
//! row on a tie. Types no row matches get the scenario's default model, so an unknown vehicle
//! is still seen. Models a row marks `cue_important` are important cues: the renderer keeps
//! their detail under overload ([`ModelTable::is_cue_important`]); a row may set a model's
//! critical radius for the detail control parameter ([`ModelTable::critical_radius_m`]) and
//! whether its vehicles raise dust ([`ModelTable::raises_dust`]).
//!
//! Limits: no substitution by country or by nearby categories beyond the patterns' wildcards.

use crate::scenario::{DisTypePattern, Scenario};
use cig_dis::EntityTypeCode;
use cig_dynterrain::soil::{RunningGear, VehicleLoad};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// An entity type as CIGI gives it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CigiEntityType {
    /// 16-bit type (CIGI 3.3 Entity Control; CIGI 4.0 without extended types).
    Short(u16),
    /// DIS-style type (CIGI 4.0 extended entity type).
    Dis(EntityTypeCode),
}

/// The table.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelTable {
    cigi: BTreeMap<u16, String>,
    dis: Vec<(DisTypePattern, String)>,
    default_model: String,
    gltf: Vec<(String, PathBuf)>,
    cue_important: BTreeSet<String>,
    critical_radius_m: BTreeMap<String, f32>,
    dust: BTreeMap<String, bool>,
    loads: BTreeMap<String, VehicleLoad>,
}

/// The ruts' vehicles when no row says: an M1-class tank (62 t on two 4.6 x 0.635 m tracks)
/// and a 10 t six-wheeled truck (six 0.35 x 0.38 m tyre patches).
const DEFAULT_LOADS: [(&str, f64, f64, RunningGear); 2] = [
    ("tank", 62_000.0, 5.8, RunningGear::Tracked),
    ("truck", 10_000.0, 0.8, RunningGear::Wheeled),
];

/// Models of ground vehicles that raise dust when they move on soil, unless a row says not.
const DUST_MODELS: [&str; 2] = ["tank", "truck"];

impl Default for ModelTable {
    fn default() -> Self {
        ModelTable {
            cigi: BTreeMap::new(),
            dis: Vec::new(),
            default_model: "truck".to_string(),
            gltf: Vec::new(),
            cue_important: BTreeSet::new(),
            critical_radius_m: BTreeMap::new(),
            dust: BTreeMap::new(),
            loads: BTreeMap::new(),
        }
    }
}

impl ModelTable {
    /// The table a scenario defines.
    pub fn from_scenario(scenario: &Scenario) -> ModelTable {
        let mut table = ModelTable {
            default_model: scenario.default_model.clone(),
            ..ModelTable::default()
        };
        for row in &scenario.models {
            if let Some(t) = row.cigi_type {
                table.cigi.entry(t).or_insert_with(|| row.model.clone());
            }
            if let Some(p) = row.dis_type.as_deref().and_then(DisTypePattern::parse) {
                table.dis.push((p, row.model.clone()));
            }
            if row.cue_important {
                table.cue_important.insert(row.model.clone());
            }
            if let Some(r) = row.critical_radius_m {
                table
                    .critical_radius_m
                    .entry(row.model.clone())
                    .or_insert(r as f32);
            }
            if let Some(dust) = row.dust {
                table.dust.entry(row.model.clone()).or_insert(dust);
            }
            if let (Some(mass_kg), Some(area_m2)) = (row.mass_kg, row.contact_area_m2) {
                let gear = match row.running_gear.as_deref() {
                    Some("wheeled") => RunningGear::Wheeled,
                    _ => RunningGear::Tracked,
                };
                if let Ok(load) = VehicleLoad::new(mass_kg, area_m2, gear) {
                    table.loads.entry(row.model.clone()).or_insert(load);
                }
            }
            if let Some(path) = &row.gltf {
                if !table.gltf.iter().any(|(name, _)| *name == row.model) {
                    table.gltf.push((row.model.clone(), path.clone()));
                }
            }
        }
        table
    }

    /// The model for a DIS entity type.
    pub fn model_for_dis(&self, t: &EntityTypeCode) -> &str {
        let mut best: Option<(usize, &str)> = None;
        for (pattern, model) in &self.dis {
            if let Some(score) = pattern.specificity(t) {
                if best.is_none_or(|(s, _)| score > s) {
                    best = Some((score, model));
                }
            }
        }
        best.map_or(self.default_model.as_str(), |(_, m)| m)
    }

    /// The model for a CIGI entity type.
    pub fn model_for_cigi(&self, t: CigiEntityType) -> &str {
        match t {
            CigiEntityType::Short(code) => self
                .cigi
                .get(&code)
                .map_or(self.default_model.as_str(), String::as_str),
            CigiEntityType::Dis(code) => self.model_for_dis(&code),
        }
    }

    /// Whether a row of the table marks `model` as an important cue.
    pub fn is_cue_important(&self, model: &str) -> bool {
        self.cue_important.contains(model)
    }

    /// The critical radius a row sets for `model` (the first row that does), metres.
    pub fn critical_radius_m(&self, model: &str) -> Option<f32> {
        self.critical_radius_m.get(model).copied()
    }

    /// Whether entities drawn with `model` raise dust when they move on soil: the first row
    /// that says, else the ground vehicles (tank, truck) do.
    pub fn raises_dust(&self, model: &str) -> bool {
        self.dust
            .get(model)
            .copied()
            .unwrap_or_else(|| DUST_MODELS.contains(&model))
    }

    /// The load a vehicle drawn with `model` puts on the ground, for its ruts: the first row
    /// that gives one, else the tank's and truck's defaults; `None` for models that leave none.
    pub fn vehicle_load(&self, model: &str) -> Option<VehicleLoad> {
        self.loads.get(model).copied().or_else(|| {
            DEFAULT_LOADS
                .iter()
                .find(|(name, ..)| *name == model)
                .and_then(|(_, mass_kg, area_m2, gear)| {
                    VehicleLoad::new(*mass_kg, *area_m2, *gear).ok()
                })
        })
    }

    /// glTF files to load: (model name, path relative to the scenario).
    pub fn gltf_files(&self) -> &[(String, PathBuf)] {
        &self.gltf
    }

    /// Every model name the table can give.
    pub fn model_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .cigi
            .values()
            .chain(self.dis.iter().map(|(_, m)| m))
            .cloned()
            .chain(std::iter::once(self.default_model.clone()))
            .collect();
        names.sort();
        names.dedup();
        names
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_most_specific_row_wins_and_unknown_types_get_the_default() {
        let scenario = Scenario::from_toml(
            r#"
default_model = "building"
[[models]]
model = "truck"
dis_type = "1:1"
[[models]]
model = "tank"
dis_type = "1:1:225:1"
cigi_type = 7
dust = false
[[models]]
model = "ship"
dis_type = "1:3:*"
cue_important = true
critical_radius_m = 60.0
dust = true
"#,
        )
        .expect("scenario");
        let table = ModelTable::from_scenario(&scenario);
        let t = |k, d, c, cat| EntityTypeCode {
            kind: k,
            domain: d,
            country: c,
            category: cat,
            subcategory: 0,
            specific: 0,
            extra: 0,
        };
        assert_eq!(table.model_for_dis(&t(1, 1, 225, 1)), "tank");
        assert_eq!(table.model_for_dis(&t(1, 1, 222, 1)), "truck");
        assert_eq!(table.model_for_dis(&t(1, 3, 225, 6)), "ship");
        assert_eq!(table.model_for_dis(&t(2, 9, 0, 0)), "building");
        assert_eq!(table.model_for_cigi(CigiEntityType::Short(7)), "tank");
        assert_eq!(table.model_for_cigi(CigiEntityType::Short(8)), "building");
        assert!(table.is_cue_important("ship"));
        assert!(!table.is_cue_important("tank"));
        assert!(!table.is_cue_important("building"));
        assert_eq!(table.critical_radius_m("ship"), Some(60.0));
        assert_eq!(table.critical_radius_m("tank"), None);
        // Dust: as a row says, else the ground vehicles only.
        assert!(!table.raises_dust("tank"));
        assert!(table.raises_dust("ship"));
        assert!(table.raises_dust("truck"));
        assert!(!table.raises_dust("building"));
    }

    #[test]
    fn a_critical_radius_must_be_positive_and_finite() {
        for bad in ["0.0", "-3.0", "1e9", "nan"] {
            let text =
                format!("[[models]]\nmodel = \"tank\"\ncigi_type = 1\ncritical_radius_m = {bad}\n");
            let e = Scenario::from_toml(&text).expect_err("refused");
            assert!(
                e.to_string().contains("models[0].critical_radius_m"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn cue_important_must_be_a_boolean() {
        let e = Scenario::from_toml("[[models]]\nmodel = \"tank\"\ncue_important = 1\n")
            .expect_err("not a boolean");
        assert!(
            e.to_string().contains("cue_important") || e.to_string().contains("bool"),
            "{e}"
        );
        let e = Scenario::from_toml("[[models]]\nmodel = \"tank\"\ncue_importnat = true\n")
            .expect_err("unknown key");
        assert!(e.to_string().contains("cue_importnat"), "{e}");
    }
}
