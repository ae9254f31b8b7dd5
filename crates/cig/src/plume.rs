//! `cig plume`: the smoke plume model at one downwind distance, for tuning and checking it.
//!
//! Briggs plume rise in ISC3's form and McMullen's dispersion sigmas from `cig_effects`; the
//! Pasquill class is given or derived from the weather with Turner's key.

use crate::cli::PlumeArgs;
use anyhow::Context;
use cig_effects::briggs::{buoyancy_flux_m4_s3, PlumeRise, Stack, Stratification};
use cig_effects::{pasquill_class, sigmas, PasquillWeather, StabilityClass};

pub fn run(args: &PlumeArgs) -> anyhow::Result<()> {
    let class = match (&args.class, args.sun_elevation_deg) {
        (Some(name), _) => name.parse::<StabilityClass>()?,
        (None, Some(sun)) => pasquill_class(&PasquillWeather {
            wind_speed_mps: args.wind,
            sun_elevation_deg: sun,
            cloud_cover_fraction: args.cloud_cover,
            cloud_ceiling_m: args.ceiling_m.unwrap_or(f64::INFINITY),
        })
        .context("cannot derive the stability class")?,
        (None, None) => anyhow::bail!(
            "no stability class: give --class A-F, or --sun-elevation-deg (with --cloud-cover, --ceiling-m) to derive it"
        ),
    };
    if args.stable_dtheta_dz.is_some() && !class.is_stable() {
        anyhow::bail!(
            "--stable-dtheta-dz applies to the stable classes E and F only, not class {class}"
        );
    }
    let flux = buoyancy_flux_m4_s3(&Stack {
        exit_velocity_mps: args.stack_velocity,
        diameter_m: args.stack_diameter,
        exit_temperature_k: args.stack_temp,
        air_temperature_k: args.air_temp,
    })
    .context("bad stack or air parameters")?;
    let stratification = Stratification::for_class(class, args.stable_dtheta_dz, args.air_temp)
        .context("bad --stable-dtheta-dz or --air-temp")?;
    let rise = PlumeRise::new(flux, args.wind, stratification).context("bad --wind")?;
    let spread = sigmas(class, args.x).context("bad --x")?;
    let rise_m = rise.rise_m(args.x);
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "rise_m": rise_m,
                "final_rise_m": rise.final_rise_m,
                "final_rise_x_m": rise.final_rise_x_m,
                "sigma_y_m": spread.y_m,
                "sigma_z_m": spread.z_m,
                "class": class.to_string(),
                "buoyancy_flux_m4_s3": flux,
            })
        );
    } else {
        println!(
            "class {class}, wind {} m/s, buoyancy flux {flux:.3} m^4/s^3",
            args.wind
        );
        println!(
            "at {} m downwind: rise {rise_m:.2} m ({}), sigma_y {:.2} m, sigma_z {:.2} m",
            args.x,
            if args.x >= rise.final_rise_x_m {
                "final"
            } else {
                "transitional"
            },
            spread.y_m,
            spread.z_m
        );
        println!(
            "final rise {:.2} m, reached {:.1} m downwind",
            rise.final_rise_m, rise.final_rise_x_m
        );
    }
    Ok(())
}
