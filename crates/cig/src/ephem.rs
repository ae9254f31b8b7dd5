//! `cig ephem`: sun, moon, events and natural illuminance for a place and time.

use crate::cli::EphemArgs;
use anyhow::{anyhow, Context};
use cig_environment::{
    day_events, ephemeris, natural_illuminance, nvg_irradiance, DayEvents, Ephemeris, Illuminance,
    NvgIrradiance, Observer, UtcTime,
};
/// Parses an ISO 8601 instant (RFC 3339, or ISO 8601 with or without an offset; no
/// offset means UTC; a date alone means its midnight UTC) into a UTC instant of 1900..=2100.
pub fn parse_time(text: &str) -> anyhow::Result<UtcTime> {
    UtcTime::parse_iso8601(text).map_err(|e| anyhow!("--time: {e}"))
}

fn event_list(e: &DayEvents) -> [(&'static str, Option<UtcTime>); 10] {
    [
        ("sunrise", e.sunrise),
        ("sunset", e.sunset),
        ("civil_dawn", e.civil_dawn),
        ("civil_dusk", e.civil_dusk),
        ("nautical_dawn", e.nautical_dawn),
        ("nautical_dusk", e.nautical_dusk),
        ("astronomical_dawn", e.astronomical_dawn),
        ("astronomical_dusk", e.astronomical_dusk),
        ("moonrise", e.moonrise),
        ("moonset", e.moonset),
    ]
}

/// The unit of `nvg_irradiance`, as printed.
pub const NVG_UNIT: &str = "lx_A (2856 K-equivalent lux)";

/// The JSON shape: sun, moon, illuminance_lux, nvg_irradiance, events.
pub fn ephem_json(
    e: &Ephemeris,
    lux: &Illuminance,
    nvg: &NvgIrradiance,
    events: &DayEvents,
) -> serde_json::Value {
    let mut ev = serde_json::Map::new();
    for (name, t) in event_list(events) {
        ev.insert(
            name.to_string(),
            t.map_or(serde_json::Value::Null, |t| t.to_iso8601_seconds().into()),
        );
    }
    serde_json::json!({
        "sun": {
            "azimuth_deg": e.sun.azimuth_deg,
            "altitude_deg": e.sun.altitude_deg,
            "apparent_altitude_deg": e.sun.apparent_altitude_deg,
        },
        "moon": {
            "azimuth_deg": e.moon.azimuth_deg,
            "altitude_deg": e.moon.altitude_deg,
            "apparent_altitude_deg": e.moon.apparent_altitude_deg,
            "illuminated_fraction": e.moon_illuminated_fraction,
            "phase_angle_deg": e.moon_phase_angle_deg,
        },
        "illuminance_lux": {
            "sun": lux.sun_lux,
            "moon": lux.moon_lux,
            "sky": lux.sky_lux,
            "total": lux.total_lux,
        },
        "nvg_irradiance": {
            "sun": nvg.sun_lxa,
            "moon": nvg.moon_lxa,
            "sky": nvg.sky_lxa,
            "night_sky": nvg.night_sky_lxa,
            "total": nvg.total_lxa,
            "unit": NVG_UNIT,
            "total_w_m2": nvg.total_w_m2,
        },
        "events": ev,
    })
}

pub fn run(args: &EphemArgs) -> anyhow::Result<()> {
    let time = parse_time(&args.time)?;
    let observer = Observer::new(args.lat, args.lon, args.alt)?;
    let e = ephemeris(&observer, time);
    let lux = natural_illuminance(&e, args.cloud_cover).context("--cloud-cover")?;
    let nvg = nvg_irradiance(&e, args.cloud_cover).context("--cloud-cover")?;
    let events = day_events(&observer, time);
    if args.json {
        println!("{}", ephem_json(&e, &lux, &nvg, &events));
        return Ok(());
    }
    println!(
        "{} at {:.6}, {:.6}, {:.1} m",
        time.to_iso8601_seconds(),
        args.lat,
        args.lon,
        args.alt
    );
    println!(
        "sun          azimuth {:8.3} deg   altitude {:8.3} deg (apparent {:8.3} deg)",
        e.sun.azimuth_deg, e.sun.altitude_deg, e.sun.apparent_altitude_deg
    );
    println!(
        "moon         azimuth {:8.3} deg   altitude {:8.3} deg (apparent {:8.3} deg)",
        e.moon.azimuth_deg, e.moon.altitude_deg, e.moon.apparent_altitude_deg
    );
    println!(
        "moon phase   {:.1} % lit, phase angle {:.2} deg, {}",
        e.moon_illuminated_fraction * 100.0,
        e.moon_phase_angle_deg,
        if e.moon_waxing { "waxing" } else { "waning" }
    );
    println!(
        "illuminance  {:.4e} lux total (sun {:.4e}, moon {:.4e}, night sky {:.4e}; cloud cover {})",
        lux.total_lux, lux.sun_lux, lux.moon_lux, lux.sky_lux, args.cloud_cover
    );
    println!(
        "nvg          {:.4e} {NVG_UNIT} total (sun {:.4e}, moon {:.4e}, sky {:.4e}, night sky {:.4e}; {:.4e} W/m2 NVG-weighted)",
        nvg.total_lxa, nvg.sun_lxa, nvg.moon_lxa, nvg.sky_lxa, nvg.night_sky_lxa, nvg.total_w_m2
    );
    if let Some(start) = events.day_start {
        println!(
            "local mean day from {} to {} (UTC)",
            start.to_iso8601_seconds(),
            start.plus_seconds(86_400.0).to_iso8601_seconds()
        );
    }
    for (name, t) in event_list(&events) {
        println!(
            "  {:<18} {}",
            name.replace('_', " "),
            t.map_or_else(|| "none".to_string(), |t| t.to_iso8601_seconds())
        );
    }
    Ok(())
}
