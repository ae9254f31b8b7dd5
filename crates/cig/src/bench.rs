//! `cig bench db|imagery|particles|render|net|env`: the arguments mapped onto `cig-bench`'s options,
//! the reports printed (figures as JSON, or the benchmark's summary).

use crate::cli::{
    BenchCultureArgs, BenchDbArgs, BenchEnvArgs, BenchImageryArgs, BenchNetArgs,
    BenchParticlesArgs, BenchRenderArgs,
};
use crate::config::Config;
use crate::output::build_progress;
use crate::render::parse_size;

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
