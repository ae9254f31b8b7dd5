//! A channel's display correction files (`--warp`, `--blend`; docs/channels.md), read into
//! `cig_scene::display`'s checked types.
//!
//! Warp file (TOML): `columns` and `rows` of the grid (at least 2 each), and `display`, each
//! node's position on the display as `[x, y]`, fractions of the display's width and height
//! from its top left, row by row from the view's top left. Blend file (TOML): `left`, `right`,
//! `top`, `bottom` (ramp widths, fractions of the display, 0 to 0.5; absent ones 0) and
//! `gamma` (the projector's, 1 to 4; default 2.2).

use anyhow::Context;
use cig_scene::display::{DisplayCorrection, EdgeBlend, WarpMesh};
use serde::Deserialize;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WarpFile {
    columns: u32,
    rows: u32,
    display: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BlendFile {
    #[serde(default)]
    left: f64,
    #[serde(default)]
    right: f64,
    #[serde(default)]
    top: f64,
    #[serde(default)]
    bottom: f64,
    #[serde(default = "projector_gamma")]
    gamma: f64,
}

fn projector_gamma() -> f64 {
    2.2
}

/// Reads the warp and blend files given (either may be absent).
pub fn read_display_correction(
    warp: Option<&Path>,
    blend: Option<&Path>,
) -> anyhow::Result<DisplayCorrection> {
    let warp = warp.map(read_warp).transpose()?;
    let blend = blend.map(read_blend).transpose()?;
    Ok(DisplayCorrection { warp, blend })
}

fn read_toml<T: serde::de::DeserializeOwned>(path: &Path, what: &str) -> anyhow::Result<T> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the {what} file {}", path.display()))?;
    toml::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{what} file: {} ({})",
            e.message().lines().next().unwrap_or("syntax error"),
            path.display()
        )
    })
}

fn read_warp(path: &Path) -> anyhow::Result<WarpMesh> {
    let file: WarpFile = read_toml(path, "warp")?;
    WarpMesh::new(file.columns, file.rows, file.display)
        .map_err(|e| anyhow::anyhow!("warp file: {e} ({})", path.display()))
}

fn read_blend(path: &Path) -> anyhow::Result<EdgeBlend> {
    let file: BlendFile = read_toml(path, "blend")?;
    let blend = EdgeBlend {
        left: file.left,
        right: file.right,
        top: file.top,
        bottom: file.bottom,
        gamma: file.gamma,
    };
    blend
        .validate()
        .map_err(|e| anyhow::anyhow!("blend file: {e} ({})", path.display()))?;
    Ok(blend)
}
