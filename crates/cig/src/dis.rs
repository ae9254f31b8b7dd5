//! `cig dis listen` and `cig dis send`: DIS diagnostic tools on the network edge.
//!
//! What each PDU says, and the Entity States to send, are `cig-tools`' `dis`; here: the
//! endpoint (`cig-net`), the clock (--count, --timeout-s, --interval-s) and printing. Nothing
//! ends the listener but --count, --timeout-s or a signal.

use crate::cli::{DisListenArgs, DisSendArgs};
use anyhow::Context;
use cig_net::{BindTarget, Delivery, EndpointConfig, UdpEndpoint};
use cig_tools::dis::{EntitySender, Listing, SendSpec};
use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::{Duration, Instant};

fn bind_of(text: &str) -> anyhow::Result<BindTarget> {
    text.parse::<BindTarget>().context("--bind")
}

/// `cig dis listen`.
pub fn listen(args: &DisListenArgs) -> anyhow::Result<()> {
    let bind = bind_of(&args.bind)?;
    let delivery = Delivery::from_flags(args.broadcast, args.multicast.as_deref(), "--multicast")?;
    let timeout = match args.timeout_s {
        Some(s) => {
            anyhow::ensure!(
                s.is_finite() && s > 0.0 && s <= 1.0e7,
                "--timeout-s {s} must be a number of seconds above 0"
            );
            Some(Duration::from_secs_f64(s))
        }
        None => None,
    };
    if let Some(0) = args.count {
        return Ok(());
    }
    let endpoint = UdpEndpoint::open(EndpointConfig {
        label: "DIS",
        bind,
        port: args.port,
        delivery,
        destination: None,
        queue_limit: 65_536,
        reuse_port: delivery != Delivery::Unicast,
    })?;
    tracing::info!("DIS: listening on {}", endpoint.local_addr());
    let started = Instant::now();
    let mut listing = Listing::new(args.exercise, args.count, args.json);
    let stdout = std::io::stdout();
    loop {
        let wait = match timeout {
            Some(t) => match t.checked_sub(started.elapsed()) {
                Some(left) if !left.is_zero() => left.min(Duration::from_millis(250)),
                _ => break,
            },
            None => Duration::from_millis(250),
        };
        let Some(datagram) = endpoint.recv_timeout(wait) else {
            continue;
        };
        let mut out = stdout.lock();
        // The listing stops at --count, so every line it returns is printed.
        for line in listing.lines(&datagram.bytes, datagram.from) {
            writeln!(out, "{line}").context("writing to standard output")?;
        }
        out.flush().context("writing to standard output")?;
        if listing.done() {
            return Ok(());
        }
    }
    let stats = endpoint.stats();
    if let Some(n) = args.count {
        anyhow::bail!(
            "DIS: --timeout-s passed with {} of {n} PDUs received on {} ({} bad datagrams, {} datagrams in all)",
            listing.printed(),
            endpoint.local_addr(),
            listing.bad(),
            stats.received
        );
    }
    Ok(())
}

/// `cig dis send`.
pub fn send(args: &DisSendArgs) -> anyhow::Result<()> {
    let sender = EntitySender::new(SendSpec {
        entity: args.entity.clone(),
        entity_type: args.entity_type.clone(),
        lat_deg: args.lat,
        lon_deg: args.lon,
        alt_m: args.alt,
        velocity: args.velocity.clone(),
        heading_deg: args.heading_deg,
        appearance: args.appearance.clone(),
        marking: args.marking.clone(),
        force_id: args.force_id,
        exercise: args.exercise,
        dr: args.dr,
        version: args.version,
        count: args.count,
        interval_s: args.interval_s,
    })?;
    let bind = bind_of(&args.bind)?;
    let delivery = Delivery::from_flags(args.broadcast, args.multicast.as_deref(), "--multicast")?;
    let endpoint = UdpEndpoint::open(EndpointConfig {
        label: "DIS",
        bind,
        port: 0,
        delivery,
        destination: None,
        queue_limit: 16,
        reuse_port: false,
    })?;
    let to = match &args.to {
        Some(host) => cig_net::resolve_host(host, args.port, "--to")?,
        // Broadcast or multicast: the broadcast address or group, at the destination port.
        None => match endpoint.destination() {
            Some(d) => SocketAddr::new(d.ip(), args.port),
            None => SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), args.port),
        },
    };
    let started = Instant::now();
    let mut octets = 0usize;
    for k in 0..args.count {
        let due = Duration::from_secs_f64(args.interval_s * k as f64);
        if let Some(wait) = due.checked_sub(started.elapsed()) {
            std::thread::sleep(wait);
        }
        let elapsed_s = started.elapsed().as_secs_f64();
        let utc_s = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0);
        let bytes = sender.pdu(elapsed_s, utc_s)?;
        octets = bytes.len();
        endpoint
            .send_to(&bytes, to)
            .with_context(|| format!("DIS: cannot send to {to}"))?;
    }
    println!("{}", sender.summary(octets, to));
    Ok(())
}
