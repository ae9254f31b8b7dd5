//! The configuration file: TOML, every table optional, unknown keys refused.

use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    pub paging: cig_terrain::PagingConfig,
    pub database: DatabaseConfig,
    pub overload: OverloadConfig,
    pub culture: CultureConfig,
}

/// `[culture]`: how the database's culture is drawn.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CultureConfig {
    /// Kinds that keep their detail under overload (cue-important, source 004 §4.6), by name:
    /// conifer_tree, broadleaf_tree, bush, house, shed, large_building, wall, fence, power_pole
    /// (e.g. `["power_pole"]` for a helicopter trainer's wire-strike cues).
    pub cue_important: Vec<String>,
    /// Cull culture the terrain hides behind ridges (the picture is the same either way).
    pub occlusion: bool,
}

impl Default for CultureConfig {
    fn default() -> Self {
        CultureConfig {
            cue_important: Vec::new(),
            occlusion: true,
        }
    }
}

impl CultureConfig {
    /// The kinds named, or the first name that is no kind.
    pub fn cue_important_kinds(&self) -> Result<Vec<cig_terrain::CultureKind>, String> {
        self.cue_important
            .iter()
            .map(|name| {
                cig_terrain::CultureKind::from_name(name).ok_or_else(|| {
                    format!("culture.cue_important: \"{name}\" is not a culture kind")
                })
            })
            .collect()
    }
}

/// `[overload]`: the renderer's overload control of models' detail (source 004 Table 4,
/// `cig_scene::overload`). While any monitored counter of a view's frame is above its
/// `begin_decrement`, the detail control parameter's `K_LOD` falls by `decrement_step` of the
/// nominal per frame (not below `floor` of it); while all are below their `begin_increment`, it
/// rises by `increment_step` per frame back to the nominal; between the two it holds.
/// Cue-important models (the scenario's model table) keep the nominal.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OverloadConfig {
    /// Off: every model at the view's nominal `K_LOD`.
    pub enabled: bool,
    /// Fractions of the nominal `K_LOD`, each in (0, 1].
    pub decrement_step: f64,
    pub increment_step: f64,
    pub floor: f64,
    /// Drawn triangles (terrain and models) of a view's frame.
    pub triangles: CounterConfig,
    /// Drawn models of a view's frame.
    pub models: CounterConfig,
    /// GPU frame time, milliseconds, where the device has timestamp queries (e.g.
    /// `{ capacity = 16.7, begin_decrement = 15.0, begin_increment = 12.0 }` for 60 Hz); not
    /// monitored unless given.
    pub gpu_ms: Option<CounterConfig>,
}

/// One monitored counter: `0 < begin_increment < begin_decrement <= capacity`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CounterConfig {
    pub capacity: f64,
    pub begin_decrement: f64,
    pub begin_increment: f64,
}

impl From<cig_scene::overload::CounterLimits> for CounterConfig {
    fn from(l: cig_scene::overload::CounterLimits) -> Self {
        CounterConfig {
            capacity: l.capacity,
            begin_decrement: l.begin_decrement,
            begin_increment: l.begin_increment,
        }
    }
}

impl From<CounterConfig> for cig_scene::overload::CounterLimits {
    fn from(c: CounterConfig) -> Self {
        cig_scene::overload::CounterLimits {
            capacity: c.capacity,
            begin_decrement: c.begin_decrement,
            begin_increment: c.begin_increment,
        }
    }
}

impl Default for OverloadConfig {
    /// On, with `OverloadSettings::default()`'s generous levels (8 M triangles, 8,192 models).
    fn default() -> Self {
        let d = cig_scene::overload::OverloadSettings::default();
        let fallback = CounterConfig {
            capacity: 1.0,
            begin_decrement: 1.0,
            begin_increment: 0.5,
        };
        OverloadConfig {
            enabled: true,
            decrement_step: d.decrement_step,
            increment_step: d.increment_step,
            floor: d.floor,
            triangles: d.triangles.map_or(fallback, CounterConfig::from),
            models: d.models.map_or(fallback, CounterConfig::from),
            gpu_ms: d.gpu_ms.map(CounterConfig::from),
        }
    }
}

impl OverloadConfig {
    /// The renderer's settings (`None` when off), checked; the error names the key below
    /// `overload.`.
    pub fn settings(
        &self,
    ) -> Result<Option<cig_scene::overload::OverloadSettings>, cig_scene::overload::OverloadError>
    {
        let settings = cig_scene::overload::OverloadSettings {
            triangles: Some(self.triangles.into()),
            models: Some(self.models.into()),
            gpu_ms: self.gpu_ms.map(Into::into),
            decrement_step: self.decrement_step,
            increment_step: self.increment_step,
            floor: self.floor,
        };
        settings.validate()?;
        Ok(self.enabled.then_some(settings))
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DatabaseConfig {
    /// Cells along a tile side (power of two, 16 to 4096).
    pub tile_cells: u32,
}

impl Default for DatabaseConfig {
    fn default() -> Self {
        DatabaseConfig { tile_cells: 128 }
    }
}

impl Config {
    /// Reads `path`, or the defaults when none is given.
    pub fn load(path: Option<&Path>) -> anyhow::Result<Config> {
        let Some(path) = path else {
            return Ok(Config::default());
        };
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read configuration {}", path.display()))?;
        let config: Config = toml::from_str(&text).map_err(|e| {
            // Where it is: the line and what it says.
            let place = e
                .span()
                .and_then(|span| {
                    let line = text.get(..span.start)?.matches('\n').count() + 1;
                    let said = text.lines().nth(line - 1)?.trim();
                    Some(format!("line {line} (`{said}`): "))
                })
                .unwrap_or_default();
            anyhow::anyhow!(
                "bad configuration: {place}{}: {}",
                e.message().trim(),
                path.display()
            )
        })?;
        config
            .paging
            .validate()
            .with_context(|| format!("bad configuration {}", path.display()))?;
        let t = config.database.tile_cells;
        anyhow::ensure!(
            t.is_power_of_two() && (16..=4096).contains(&t),
            "bad configuration: database.tile_cells = {t} must be a power of two from 16 to 4096: {}",
            path.display()
        );
        if let Err(e) = config.overload.settings() {
            anyhow::bail!("bad configuration: overload.{e}: {}", path.display());
        }
        if let Err(e) = config.culture.cue_important_kinds() {
            anyhow::bail!("bad configuration: {e}: {}", path.display());
        }
        Ok(config)
    }

    /// The renderer's overload control (`None`: off), already checked by [`Config::load`].
    pub fn overload(&self) -> anyhow::Result<Option<cig_scene::overload::OverloadSettings>> {
        self.overload
            .settings()
            .map_err(|e| anyhow::anyhow!("bad configuration: overload.{e}"))
    }

    /// Applies the configuration's overload control to a renderer.
    pub fn configure_renderer(&self, renderer: &mut cig_render::Renderer) -> anyhow::Result<()> {
        renderer.culture_cue_important = self
            .culture
            .cue_important_kinds()
            .map_err(|e| anyhow::anyhow!("bad configuration: {e}"))?;
        renderer.culture_occlusion = self.culture.occlusion;
        renderer
            .set_overload(self.overload()?)
            .map_err(|e| anyhow::anyhow!("bad configuration: overload.{e}"))
    }

    pub fn default_toml() -> anyhow::Result<String> {
        Ok(toml::to_string_pretty(&Config::default())?)
    }
}
