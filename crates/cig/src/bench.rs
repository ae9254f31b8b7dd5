//! `cig bench db|imagery|particles|render|culture|net|env|channels|soak|sensor|sea`: the arguments mapped onto `cig-bench`'s options,
//! the reports printed (figures as JSON, or the benchmark's summary).

use crate::cli::{
    BenchChannelsArgs, BenchCultureArgs, BenchDbArgs, BenchDynterrainArgs, BenchEnvArgs,
    BenchImageryArgs, BenchNetArgs, BenchParticlesArgs, BenchRenderArgs, BenchSeaArgs,
    BenchSensorArgs, BenchSoakArgs,
};
use crate::config::Config;
use crate::output::build_progress;
use crate::render::parse_size;
use anyhow::Context;

/// The commit this binary was built from, for the reports.
fn commit() -> String {
    option_env!("CIG_GIT_COMMIT")
        .unwrap_or("unknown")
        .to_string()
}

/// Prints a report as one line with `--json`, else indented.
fn print_figures(report: &serde_json::Value, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{report}");
    } else {
        println!("{}", serde_json::to_string_pretty(report)?);
    }
    Ok(())
}

/// Prints a report indented with `--json`, else its summary.
fn print_report(report: &cig_bench::Report, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(&report.json)?);
    } else {
        println!("{}", report.summary);
    }
    Ok(())
}

pub fn db(args: &BenchDbArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::db::DbOptions {
        db: args.db.clone(),
        seconds: args.seconds,
        build: !args.no_build,
        paging: config.paging.clone(),
        tile_cells: config.database.tile_cells,
        commit: commit(),
    };
    let report = cig_bench::db::run(&options, &mut build_progress())?;
    print_figures(&report, args.json)
}

pub fn imagery(args: &BenchImageryArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::imagery::ImageryOptions {
        size: args.size,
        scratch: args.scratch.clone(),
        tile_cells: config.database.tile_cells,
        commit: commit(),
    };
    let report = cig_bench::imagery::run(&options, &mut build_progress())?;
    print_figures(&report, args.json)
}

pub fn particles(args: &BenchParticlesArgs) -> anyhow::Result<()> {
    let report = cig_bench::particles::run(&cig_bench::particles::ParticlesOptions {
        frames: args.frames,
        warm_seconds: args.warm_seconds,
        commit: commit(),
    })?;
    print_figures(&report, args.json)
}

pub fn render(args: &BenchRenderArgs, config: &Config) -> anyhow::Result<()> {
    let report = cig_bench::render::run(&cig_bench::render::RenderOptions {
        db: args.db.clone(),
        size: parse_size(&args.size)?,
        fov: args.fov,
        max_pixel_error: args.max_pixel_error,
        frames: args.frames,
        compare_frames: args.compare_frames,
        paging: config.paging.clone(),
        commit: commit(),
    })?;
    print_report(&report, args.json)
}

pub fn culture(args: &BenchCultureArgs, config: &Config) -> anyhow::Result<()> {
    let report = cig_bench::culture::run(&cig_bench::culture::CultureOptions {
        db: args.db.clone(),
        size: parse_size(&args.size)?,
        fov: args.fov,
        climb_frames: args.climb_frames,
        paging: config.paging.clone(),
        commit: commit(),
    })?;
    print_report(&report, args.json)
}

pub fn net(args: &BenchNetArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::net::NetOptions {
        seconds: args.seconds,
        db: args.db.clone(),
        flood: args.flood,
        flood_s: args.flood_s,
        flood_rate: args.flood_rate,
        paging: config.paging.clone(),
        tile_cells: config.database.tile_cells,
        commit: commit(),
    };
    let report = cig_bench::net::run(&options, &mut build_progress())?;
    print_figures(&report, args.json)
}

pub fn env(args: &BenchEnvArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::env::EnvOptions {
        db: args.db.clone(),
        size: parse_size(&args.size)?,
        frames: args.frames,
        rounds: args.rounds,
        paging: config.paging.clone(),
        tile_cells: config.database.tile_cells,
        commit: commit(),
    };
    let report = cig_bench::env::run(&options, &mut build_progress())?;
    print_report(&report, args.json)
}

/// This binary: the channels and the soak run it as `cig serve`.
fn this_binary() -> anyhow::Result<std::path::PathBuf> {
    std::env::current_exe().context("cannot find the cig binary to run its channels")
}

/// `--db`, or the demo database (built when missing).
fn database_or_demo(
    db: Option<&std::path::Path>,
    label: &str,
    config: &Config,
) -> anyhow::Result<std::path::PathBuf> {
    Ok(cig_bench::database::demo_or(
        db,
        label,
        config.database.tile_cells,
        &mut build_progress(),
    )?)
}

pub fn channels(args: &BenchChannelsArgs, config: &Config) -> anyhow::Result<()> {
    let report = cig_bench::channels::run(&cig_bench::channels::ChannelsOptions {
        cig_exe: this_binary()?,
        db: database_or_demo(args.db.as_deref(), "bench channels", config)?,
        size_px: parse_size(&args.size)?,
        rate_hz: args.rate_hz,
        warmup_s: args.warmup_s,
        seconds: args.seconds,
        keep_dir: args.keep_dir.clone(),
        commit: commit(),
    })?;
    print_report(&report, args.json)
}

pub fn soak(args: &BenchSoakArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::soak::SoakOptions {
        cig_exe: this_binary()?,
        db: database_or_demo(args.db.as_deref(), "bench soak", config)?,
        minutes: args.minutes,
        size_px: parse_size(&args.size)?,
        rate_hz: args.rate_hz,
        remote_entities: args.entities,
        speed_mps: args.speed_mps,
        sample_s: args.sample_s,
        rss_growth_max_pct: args.rss_growth_max_pct,
        keep_dir: args.keep_dir.clone(),
        commit: commit(),
    };
    let mut last_minute = -1.0;
    let report = cig_bench::soak::run(&options, &mut |sample| {
        let minute = (sample.t_s / 60.0).floor();
        if minute > last_minute {
            last_minute = minute;
            tracing::info!(
                "soak minute {minute}: {:.1} MiB resident, {} threads, {} descriptors",
                sample.rss_kib as f64 / 1024.0,
                sample.threads,
                sample.fds
            );
        }
    })?;
    print_report(&report, args.json)?;
    if report.json["passed"] != serde_json::Value::Bool(true) {
        anyhow::bail!("the soak drifted: {}", report.summary);
    }
    Ok(())
}

pub fn sensor(args: &BenchSensorArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::sensor::SensorOptions {
        db: args.db.clone(),
        size: parse_size(&args.size).context("--size")?,
        entities: args.entities,
        paging: config.paging.clone(),
        commit: commit(),
    };
    let report = cig_bench::sensor::run(&options)?;
    print_report(&report, args.json)
}

pub fn dynterrain(args: &BenchDynterrainArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::dynterrain::DynTerrainOptions {
        db: args.db.clone(),
        frames: args.frames,
        size: parse_size(&args.size).context("--size")?,
        paging: config.paging.clone(),
        commit: commit(),
    };
    let report = cig_bench::dynterrain::run(&options)?;
    print_report(&report, args.json)
}

pub fn sea(args: &BenchSeaArgs, config: &Config) -> anyhow::Result<()> {
    let options = cig_bench::sea::SeaOptions {
        db: args.db.clone(),
        size: parse_size(&args.size).context("--size")?,
        paging: config.paging.clone(),
        commit: commit(),
    };
    let report = cig_bench::sea::run(&options)?;
    print_report(&report, args.json)
}
