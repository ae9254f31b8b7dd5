//! `cig lod ne`: the detail control parameter of a model (`cig_scene::detail`).

use crate::cli::LodNeArgs;
use anyhow::bail;
use cig_scene::detail::{klod, ne_3d, DetailTable};

/// Checks that `value` of `option` is positive and finite.
fn positive(option: &str, value: f64, unit: &str) -> anyhow::Result<f64> {
    if !(value.is_finite() && value > 0.0) {
        bail!("{option} {value}: must be a positive, finite number of {unit}");
    }
    Ok(value)
}

pub fn ne(args: &LodNeArgs) -> anyhow::Result<()> {
    let radius_m = positive("--radius-m", args.radius_m, "metres")?;
    let range_m = positive("--range-m", args.range_m, "metres")?;
    let fov_deg = args.fov_deg;
    if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
        bail!("--fov-deg {fov_deg}: must lie between 0 and 180 degrees");
    }
    let width_px = args.width_px;
    if !(width_px.is_finite() && width_px >= 1.0 && width_px.fract() == 0.0) {
        bail!("--width-px {width_px}: must be a whole number of pixels, 1 or more");
    }
    let k = match args.klod {
        Some(k) => positive("--klod", k, "resolution elements per unit of tangent")?,
        None => klod(fov_deg, width_px),
    };
    let ne = ne_3d(k, radius_m, range_m, 1.0);
    let step = DetailTable::default().step_of(ne);
    if args.json {
        println!(
            "{}",
            serde_json::json!({ "klod": k, "ne": ne, "step": step })
        );
    } else {
        println!("K_LOD {k:.1}  N_e {ne:.3}  step {step} (Table 3: 1.5 step^2, 1..8; 0 fades out)");
    }
    Ok(())
}
