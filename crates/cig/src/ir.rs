//! `cig ir`: thermal infrared physics from the command line (band radiance, surface
//! temperatures). The physics is `cig-thermal`'s; this is parsing and printing.

use crate::cli::{IrRadianceArgs, IrSurfaceTempArgs, IrTransmittanceArgs};
use crate::ephem::parse_time;
use anyhow::Context;
use cig_thermal::{
    band_radiance, Aerosol, AirTemperature, Band, IrAtmosphere, IrBand, ModelAtmosphere,
    Orientation, Orientations, SurfaceTable, ThermalMaterial, ThermalWeather, CELSIUS_0_K,
};

pub fn transmittance(args: &IrTransmittanceArgs) -> anyhow::Result<()> {
    let band = IrBand::parse(&args.band).context("--band")?;
    let model = ModelAtmosphere::from_name(&args.atmosphere).context("--atmosphere")?;
    let aerosol = Aerosol::from_name(&args.aerosol).context("--aerosol")?;
    let mut atmosphere = IrAtmosphere::model(model, aerosol);
    if let Some(c) = args.air_temp_c {
        atmosphere.air_k = c + CELSIUS_0_K;
        atmosphere.validate().context("--air-temp-c")?;
    }
    if let Some(rh) = args.rh {
        atmosphere.relative_humidity_pct = rh;
        atmosphere.validate().context("--rh")?;
    }
    if let Some(v) = args.visibility_m {
        atmosphere.visibility_m = v;
        atmosphere.validate().context("--visibility-m")?;
    }
    let path = atmosphere
        .horizontal(band, args.range_m, args.altitude_m)
        .context("--range-m/--altitude-m")?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "transmittance": path.transmittance,
                "path_radiance_w_m2_sr": path.path_radiance_w_m2_sr,
            })
        );
    } else {
        println!(
            "transmittance {:.4}, path radiance {:.4} W m-2 sr-1",
            path.transmittance, path.path_radiance_w_m2_sr
        );
    }
    Ok(())
}

pub fn radiance(args: &IrRadianceArgs) -> anyhow::Result<()> {
    let band = Band::parse(&args.band).context("--band")?;
    let radiance = band_radiance(band, args.temp_k).context("--temp-k")?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "band_um": [band.lo_um, band.hi_um],
                "temp_k": args.temp_k,
                "radiance_w_m2_sr": radiance,
            })
        );
    } else {
        println!(
            "{}-{} um at {} K: {radiance:.6} W m-2 sr-1",
            band.lo_um, band.hi_um, args.temp_k
        );
    }
    Ok(())
}

pub fn surface_temp(args: &IrSurfaceTempArgs) -> anyhow::Result<()> {
    let material = ThermalMaterial::from_name(&args.material).context("--material")?;
    let time = parse_time(&args.time)?;
    let air = AirTemperature::diurnal_c(args.air_min_c, args.air_max_c)
        .context("--air-min-c/--air-max-c")?;
    let deep_ground_k = match args.deep_ground_c {
        Some(c) if !(c.is_finite() && (-60.0..=60.0).contains(&c)) => {
            anyhow::bail!("--deep-ground-c: {c} is out of range: expected -60..60 C")
        }
        Some(c) => Some(c + CELSIUS_0_K),
        None => None,
    };
    let weather = ThermalWeather {
        air,
        relative_humidity_pct: args.rh,
        wind_mps: args.wind_mps,
        cloud_cover: args.cloud,
        deep_ground_k,
    };
    let orientation = Orientation::new(args.tilt_deg, args.facing_deg).context("--tilt-deg")?;
    let table = SurfaceTable::spin_up(
        args.lat,
        args.lon,
        time,
        weather,
        &[material],
        Orientations::Single(orientation),
    )
    .context("surface temperature")?;
    let surface_c = table.surface_k(0, 0) - CELSIUS_0_K;
    let air_c = table.air_k() - CELSIUS_0_K;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "material": material.name(),
                "surface_temp_c": surface_c,
                "air_temp_c": air_c,
            })
        );
    } else {
        println!(
            "{} at {}: surface {surface_c:.2} C, air {air_c:.2} C",
            material.name(),
            time.to_iso8601_seconds()
        );
    }
    Ok(())
}
