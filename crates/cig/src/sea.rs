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

/// `--sea-wave HEIGHT_M,WAVELENGTH_M,PERIOD_S,TOWARD_DEG[,PHASE_DEG[,LEADING]]`, and where
/// it applies: everywhere, or (after `@`) over a CIGI environmental region
/// `LAT,LON,SIZE_X_M,SIZE_Y_M[,ROTATION_DEG[,CORNER_RADIUS_M[,TRANSITION_M]]]`.
pub fn parse_wave(
    text: &str,
) -> anyhow::Result<(
    cig_sea::surface::WaveComponent,
    Option<cig_cigi::EnvironmentalRegionControl>,
)> {
    let (wave_text, region_text) = match text.split_once('@') {
        Some((wave, region)) => (wave, Some(region)),
        None => (text, None),
    };
    let v = crate::render::parse_numbers(wave_text, "--sea-wave", &[4, 5, 6])?;
    let at = |i: usize| v.get(i).copied().unwrap_or_default();
    let wave = cig_sea::surface::WaveComponent::new(at(0), at(1), at(2), at(3), at(4), at(5))
        .with_context(|| format!("--sea-wave \"{text}\""))?;
    let Some(region_text) = region_text else {
        return Ok((wave, None));
    };
    let r = crate::render::parse_numbers(region_text, "--sea-wave's region", &[4, 5, 6, 7])?;
    let at = |i: usize| r.get(i).copied().unwrap_or_default();
    if !((-90.0..=90.0).contains(&at(0)) && (-180.0..=360.0).contains(&at(1))) {
        bail!("--sea-wave \"{text}\": the region's centre must be a latitude and longitude");
    }
    if [at(2), at(3), at(5), at(6)]
        .iter()
        .any(|v| !(0.0..=1.0e7).contains(v))
    {
        bail!("--sea-wave \"{text}\": the region's sizes, corner radius and transition must be 0-10,000 km");
    }
    #[expect(
        clippy::cast_possible_truncation,
        reason = "CIGI carries the region's sizes as f32; checked to be under 1e7 m"
    )]
    let region = cig_cigi::EnvironmentalRegionControl {
        region_state: 1,
        latitude_deg: at(0),
        longitude_deg: at(1),
        size_x_m: at(2) as f32,
        size_y_m: at(3) as f32,
        rotation_deg: at(4) as f32,
        corner_radius_m: at(5) as f32,
        transition_perimeter_m: at(6) as f32,
        ..cig_cigi::EnvironmentalRegionControl::default()
    };
    Ok((wave, Some(region)))
}

/// `--refraction K`: "standard" (0.13), "off" (0) or a coefficient in -1..0.9.
pub fn parse_refraction(text: &str) -> anyhow::Result<f64> {
    match text {
        "standard" => Ok(cig_sea::horizon::STANDARD_REFRACTION_K),
        "off" => Ok(0.0),
        _ => match text.parse::<f64>() {
            Ok(k) if k.is_finite() && (-1.0..=0.9).contains(&k) => Ok(k),
            _ => {
                bail!("--refraction \"{text}\": must be standard, off or a coefficient in -1..0.9")
            }
        },
    }
}

/// A periscope asked for by `--periscope HEIGHT_M,MAG`: the head's height above mean sea
/// level and the magnification.
pub fn parse_periscope(text: &str) -> anyhow::Result<(f64, cig_sea::periscope::Magnification)> {
    let v = crate::render::parse_numbers(text, "--periscope", &[2])?;
    let (height_m, power) = (v[0], v[1]);
    // The head may be anywhere from the deepest sea floor to 30 m up.
    cig_sea::periscope::PeriscopeMount::new(height_m, 11_000.0)
        .with_context(|| format!("--periscope \"{text}\": the head's height"))?;
    let magnification = cig_sea::periscope::Magnification::new(power)
        .with_context(|| format!("--periscope \"{text}\": the magnification"))?;
    Ok((height_m, magnification))
}

/// How much of a periscope's window the sea covers at the surface's time: the sea at the head
/// over the second before, sampled every 1/20 s on a surface of its own.
pub fn wash_over(
    surface: &SeaSurface,
    sea: &cig_scene::sea::SeaDraw,
    head: cig_geo::Geodetic,
    head_height_m: f64,
) -> anyhow::Result<f64> {
    let mut past = surface.clone();
    let now_s = surface.time_s();
    let [x, y] = cig_scene::sea::sea_plane_xy(
        &cig_geo::EnuFrame::new(sea.origin),
        head.lat_deg,
        head.lon_deg,
    );
    let mut history = Vec::with_capacity(21);
    for k in 0..=20 {
        let t_s = now_s - 1.0 + f64::from(k) * 0.05;
        past.update(t_s).context("the sea at the periscope")?;
        history.push((t_s, past.sample(x, y).height_m + sea.level_m));
    }
    cig_sea::periscope::WashOver::DEFAULT
        .coverage(head_height_m, &history, now_s)
        .context("the sea at the periscope")
}

/// Draws a periscope's reticle over a frame of `view`: the graduated line across its field and
/// the true bearing of its centre.
pub fn draw_reticle(image: &mut cig_render::Image, view: &cig_scene::View) {
    cig_scene::reticle::draw_periscope_reticle(
        &mut cig_scene::reticle::Canvas {
            rgba: &mut image.rgba,
            width: image.width,
            height: image.height,
        },
        view.fov.left_deg + view.fov.right_deg,
        view.orientation.heading_deg,
    );
}

/// Covers the lower `coverage` of a frame with sea water seen from inside it (draining from
/// the top down).
pub fn draw_wash(rgba: &mut [u8], width: u32, height: u32, coverage: f64) {
    let first_row = ((1.0 - coverage.clamp(0.0, 1.0)) * f64::from(height)).round() as usize;
    let water = [8.0, 38.0, 44.0];
    for px in rgba.chunks_exact_mut(4).skip(first_row * width as usize) {
        for (c, w) in px.iter_mut().zip(water) {
            *c = (f64::from(*c) * 0.1 + w * 0.9).round() as u8;
        }
    }
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
