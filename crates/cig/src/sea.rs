//! `cig sea`: the simulated sea's statistics and the sea horizon (`cig_sea`).

use crate::cli::{SeaHorizonArgs, SeaStatsArgs};
use anyhow::{bail, Context};
use cig_sea::horizon::{self, Refraction};
use cig_sea::spectrum::SeaConditions;
use cig_sea::surface::{SeaSurface, SurfaceConfig};

/// The sea `--sea-state N` or `--sea-wind MPS[,FROM_DEG]` asks for (`None`: no sea).
pub fn conditions_from_args(
    sea_state: Option<f64>,
    sea_wind: Option<&str>,
) -> anyhow::Result<Option<SeaConditions>> {
    match (sea_state, sea_wind) {
        (Some(code), None) => Ok(Some(sea_state_conditions(code, 270.0)?)),
        (None, Some(text)) => {
            let v = crate::render::parse_numbers(text, "--sea-wind", &[1, 2])?;
            let from_deg = v.get(1).copied().unwrap_or(270.0);
            let wind_mps = v.first().copied().unwrap_or_default();
            Ok(Some(
                SeaConditions::new(wind_mps, from_deg)
                    .with_context(|| format!("--sea-wind \"{text}\""))?,
            ))
        }
        (None, None) => Ok(None),
        (Some(_), Some(_)) => bail!("--sea-state and --sea-wind: give one of them"),
    }
}

/// A fully developed sea for a WMO sea state code given as a number (checked: 0-9, whole).
fn sea_state_conditions(code: f64, wind_from_deg: f64) -> anyhow::Result<SeaConditions> {
    if !(code.is_finite() && (0.0..=9.0).contains(&code) && code.fract() == 0.0) {
        bail!("--sea-state {code}: must be a WMO sea state code, a whole number 0-9");
    }
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "a whole number in 0..=9, checked above"
    )]
    let code = code as u8;
    SeaConditions::for_sea_state(code, wind_from_deg).context("--sea-state")
}

/// The sea one frame at `unix_time_s` draws: the surface (seed 1) at that time, its plane's
/// origin the eye's whole degrees (the same waves for nearby eyes and every IG).
pub fn sea_draw(
    conditions: &SeaConditions,
    eye: cig_geo::Geodetic,
    unix_time_s: f64,
) -> anyhow::Result<cig_scene::sea::SeaDraw> {
    let mut surface =
        SeaSurface::new(conditions, 1, SurfaceConfig::default()).context("the sea surface")?;
    // The waves' clock: seconds of the day, so the same instant gives the same sea anywhere.
    surface
        .update(unix_time_s.rem_euclid(86_400.0))
        .context("the sea surface")?;
    let origin = cig_geo::Geodetic::new(eye.lat_deg.round(), eye.lon_deg.round(), 0.0);
    Ok(cig_scene::sea::SeaDraw::new(&surface, origin, 0.0))
}

/// Times (seconds) the statistics average over: a few wave periods apart, not a multiple of
/// any cascade's repeat.
const STATS_TIMES_S: [f64; 4] = [0.0, 7.3, 19.1, 31.7];

pub fn stats(args: &SeaStatsArgs) -> anyhow::Result<()> {
    let conditions = match (args.wind_mps, args.sea_state) {
        (Some(wind_mps), None) => {
            let c = SeaConditions::new(wind_mps, args.wind_from_deg).context("--wind-mps")?;
            match args.fetch_km {
                Some(km) => c.with_fetch_m(km * 1000.0).context("--fetch-km")?,
                None => c,
            }
        }
        (None, Some(code)) => sea_state_conditions(code, args.wind_from_deg)?,
        _ => bail!("give the sea by --wind-mps (with --fetch-km) or by --sea-state"),
    };
    let mut surface = SeaSurface::new(&conditions, args.seed, SurfaceConfig::default())
        .context("the sea surface")?;
    let measured = surface
        .measure(&STATS_TIMES_S)
        .context("measuring the sea surface")?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "hs_m": measured.hs_m,
                "peak_period_s": measured.peak_period_s,
                "whitecap_fraction": measured.whitecap_fraction,
                "wind_mps": conditions.wind_speed_mps,
                "expected_hs_m": conditions.expected_hs_m(),
            })
        );
    } else {
        println!(
            "Hs {:.2} m (the spectrum's {:.2} m)  peak period {:.1} s  whitecaps {:.2} %  (wind {:.1} m/s; measured on the simulated surface)",
            measured.hs_m,
            conditions.expected_hs_m(),
            measured.peak_period_s,
            measured.whitecap_fraction * 100.0,
            conditions.wind_speed_mps,
        );
    }
    Ok(())
}

pub fn horizon(args: &SeaHorizonArgs) -> anyhow::Result<()> {
    let refraction = Refraction::new(args.refraction_k).context("--refraction-k")?;
    let eye_m = args.eye_m;
    let distance_m = horizon::horizon_distance_m(eye_m, refraction).context("--eye-m")?;
    let dip_deg = horizon::dip_deg(eye_m, refraction).context("--eye-m")?;
    let top_range_m = args
        .top_m
        .map(|top_m| horizon::max_range_to_see_top_m(eye_m, top_m, refraction))
        .transpose()
        .context("--top-m")?;
    let hidden_m = args
        .range_m
        .map(|range_m| horizon::hidden_height_m(eye_m, range_m, refraction))
        .transpose()
        .context("--range-m")?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "refraction_k": refraction.k(),
                "horizon_m": distance_m,
                "dip_deg": dip_deg,
                "top_visible_to_m": top_range_m,
                "hidden_height_m": hidden_m,
            })
        );
    } else {
        println!(
            "horizon {:.0} m, dip {:.2}' (k = {})",
            distance_m,
            dip_deg * 60.0,
            refraction.k()
        );
        if let Some(m) = top_range_m {
            println!(
                "a top at {:?} m sinks below the horizon at {m:.0} m",
                args.top_m.unwrap_or_default()
            );
        }
        if let Some(m) = hidden_m {
            println!(
                "at {:?} m, {m:.2} m of a target is hidden below the horizon",
                args.range_m.unwrap_or_default()
            );
        }
    }
    Ok(())
}
