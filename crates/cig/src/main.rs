//! `cig`: the command line of the cig image generator. Thin glue: parses arguments (clap),
//! reads the configuration, calls the library crates (the network edge is `cig-net`, the
//! protocol tools `cig-tools`, the benchmarks `cig-bench`), prints results. See
//! `ARCHITECTURE.md`.

mod bench;
mod cli;
mod config;
mod db;
mod demo;
mod dis;
mod display;
mod dynterrain;
mod ephem;
mod host;
mod ir;
mod lod;
mod output;
mod plume;
mod query;
mod render;
mod sea;
mod serve;
mod thermal_view;
mod view;

use clap::Parser;

fn main() -> std::process::ExitCode {
    restore_default_sigpipe();
    let cli = cli::Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_from_env("CIG_LOG").unwrap_or_else(|_| {
        tracing_subscriber::EnvFilter::new(match cli.verbose {
            0 => "warn",
            1 => "info",
            _ => "debug",
        })
    });
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_target(false)
        .init();
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Rust ignores SIGPIPE, so printing into a closed pipe (`cig db info DB | head`) would panic;
/// like every Unix command-line tool, let the signal end the process quietly instead.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid handler.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn run(cli: cli::Cli) -> anyhow::Result<()> {
    let config = config::Config::load(cli.config.as_deref())?;
    match cli.command {
        cli::Command::Db(cli::DbCommand::Synth(args)) => db::synth(&args, &config),
        cli::Command::Db(cli::DbCommand::Import(args)) => db::import(&args, &config),
        cli::Command::Db(cli::DbCommand::Info(args)) => db::info(&args),
        cli::Command::Db(cli::DbCommand::Imagery(args)) => db::imagery(&args),
        cli::Command::Db(cli::DbCommand::Culture(args)) => db::culture(&args),
        cli::Command::Db(cli::DbCommand::Crater(args)) => dynterrain::crater(&args, &config),
        cli::Command::Db(cli::DbCommand::Edits(args)) => dynterrain::edits(&args, &config),
        cli::Command::Query(cli::QueryCommand::Hat(args)) => query::hat(&args, &config),
        cli::Command::Query(cli::QueryCommand::Los(args)) => query::los(&args, &config),
        cli::Command::Query(cli::QueryCommand::Soil(args)) => dynterrain::soil(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Db(args)) => bench::db(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Imagery(args)) => bench::imagery(&args, &config),
        cli::Command::Render(args) => render::run(&args, &config),
        cli::Command::View(args) => view::run(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Particles(args)) => bench::particles(&args),
        cli::Command::Bench(cli::BenchCommand::Render(args)) => bench::render(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Culture(args)) => bench::culture(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Net(args)) => bench::net(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Env(args)) => bench::env(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Channels(args)) => bench::channels(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Soak(args)) => bench::soak(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Sensor(args)) => bench::sensor(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Sea(args)) => bench::sea(&args, &config),
        cli::Command::Bench(cli::BenchCommand::Dynterrain(args)) => {
            bench::dynterrain(&args, &config)
        }
        cli::Command::Plume(args) => plume::run(&args),
        cli::Command::Demo(args) => demo::run(&args, &config),
        cli::Command::Ephem(args) => ephem::run(&args),
        cli::Command::Serve(args) => serve::run(&args, &config),
        cli::Command::Host(args) => host::run(&args),
        cli::Command::Dis(cli::DisCommand::Listen(args)) => dis::listen(&args),
        cli::Command::Dis(cli::DisCommand::Send(args)) => dis::send(&args),
        cli::Command::Lod(cli::LodCommand::Ne(args)) => lod::ne(&args),
        cli::Command::Ir(cli::IrCommand::Radiance(args)) => ir::radiance(&args),
        cli::Command::Ir(cli::IrCommand::SurfaceTemp(args)) => ir::surface_temp(&args),
        cli::Command::Ir(cli::IrCommand::Transmittance(args)) => ir::transmittance(&args),
        cli::Command::Sea(cli::SeaCommand::Stats(args)) => sea::stats(&args),
        cli::Command::Sea(cli::SeaCommand::Horizon(args)) => sea::horizon(&args),
        cli::Command::Config(cli::ConfigCommand::Default) => {
            print!("{}", config::Config::default_toml()?);
            Ok(())
        }
    }
}
