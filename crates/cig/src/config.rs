//! The configuration file: TOML, every table optional, unknown keys refused.

use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    pub paging: cig_terrain::PagingConfig,
    pub database: DatabaseConfig,
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
            anyhow::anyhow!(
                "bad configuration: {}: {}",
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
        Ok(config)
    }

    pub fn default_toml() -> anyhow::Result<String> {
        Ok(toml::to_string_pretty(&Config::default())?)
    }
}
