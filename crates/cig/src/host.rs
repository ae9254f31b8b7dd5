//! `cig host`: a small scripted CIGI host, for demos and tests.
//!
//! The script, each frame's message and the reading of the IG's replies are `cig-tools`'
//! `host`; here: the socket (`cig-net`), the frame clock, and printing the replies (one JSON
//! line each with `--json`) and the summary.

use crate::cli::HostArgs;
use anyhow::{bail, Context};
use cig_cigi::encode_message;
use cig_net::{BindTarget, Delivery, EndpointConfig, UdpEndpoint};
use cig_tools::host::{HostScript, Replies};
use std::io::Write;
use std::time::{Duration, Instant};

pub fn run(args: &HostArgs) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(&args.script)
        .with_context(|| format!("cannot read the host script {}", args.script.display()))?;
    let script = HostScript::from_toml(&text)
        .with_context(|| format!("host script {}", args.script.display()))?;
    let ig = cig_net::resolve(&args.ig, "--ig")?;
    let bind: BindTarget = args.bind.parse().context("--bind")?;
    let endpoint = UdpEndpoint::open(EndpointConfig {
        label: "CIGI host",
        bind,
        port: args.port,
        delivery: Delivery::Unicast,
        destination: Some(ig),
        queue_limit: 1024,
        reuse_port: false,
    })?;
    let period = Duration::from_secs_f64(1.0 / script.rate_hz());
    let started = Instant::now();
    let mut replies = Replies::new();
    let mut inbox = Vec::new();
    let mut out = std::io::stdout().lock();
    let frames = args.frames.unwrap_or(script.frames());
    for frame in 0..frames.saturating_add(args.drain_frames) {
        let tick = started + period * frame;
        if let Some(wait) = tick.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        if frame < frames {
            let message = script.frame(frame, replies.last_ig_frame())?;
            let mut bytes = Vec::new();
            encode_message(&message, &mut bytes).context("encoding the host's message")?;
            endpoint
                .send(&bytes)
                .with_context(|| format!("cannot send to the IG at {ig}"))?;
        }
        // What the IG sent since the last frame.
        inbox.clear();
        endpoint.drain(&mut inbox);
        for d in &inbox {
            match replies.read(&d.bytes, frame) {
                Ok(values) if args.json => {
                    for value in values {
                        writeln!(out, "{value}")?;
                    }
                }
                Ok(_) => {}
                Err(e) => tracing::warn!("{e}"),
            }
        }
    }
    if args.json {
        writeln!(out, "{}", replies.summary_json(frames))?;
    } else {
        eprintln!("{}", replies.summary_line(frames));
    }
    if replies.start_of_frames() == 0 {
        bail!("the IG at {ig} never answered");
    }
    Ok(())
}
