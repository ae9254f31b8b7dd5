//! The UDP endpoint: socket options, bind, the receive thread and its bounded queue.

use crate::interface::BindTarget;
use crate::log::RateLimitedLog;
use crate::NetError;
use socket2::{Domain, Protocol, SockAddr, Socket, Type};
use std::collections::VecDeque;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Largest UDP payload IPv4 can carry (65,535 − 20 IP − 8 UDP octets).
pub const MAX_UDP_PAYLOAD_OCTETS: usize = 65_507;
/// Read timeout of the receive thread: how long a dropped endpoint may take to stop.
const RECEIVE_POLL: Duration = Duration::from_millis(50);
/// Receive buffer asked of the kernel (best effort: capped by net.core.rmem_max).
const SOCKET_RECEIVE_BUFFER_OCTETS: usize = 4 << 20;

/// How datagrams reach the other nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Delivery {
    /// To one address.
    #[default]
    Unicast,
    /// To every node of the subnet (SO_BROADCAST).
    Broadcast,
    /// To the members of an IPv4 multicast group.
    Multicast(Ipv4Addr),
}

/// What to open.
#[derive(Clone, Debug)]
pub struct EndpointConfig {
    /// "CIGI" or "DIS": names the endpoint in logs and errors.
    pub label: &'static str,
    /// Where to bind.
    pub bind: BindTarget,
    /// Local port; 0 picks a free one.
    pub port: u16,
    /// Unicast, broadcast or multicast.
    pub delivery: Delivery,
    /// Where [`UdpEndpoint::send`] sends; broadcast and multicast default to the broadcast
    /// address or the group at this endpoint's port.
    pub destination: Option<SocketAddr>,
    /// Datagrams held before the oldest is dropped.
    pub queue_limit: usize,
    /// Share the port with other processes (SO_REUSEADDR + SO_REUSEPORT).
    pub reuse_port: bool,
}

impl EndpointConfig {
    /// Unicast on the loopback at `port`, 1,024 datagrams of queue, no sharing.
    #[must_use]
    pub fn loopback(label: &'static str, port: u16) -> EndpointConfig {
        EndpointConfig {
            label,
            bind: BindTarget::Loopback,
            port,
            delivery: Delivery::Unicast,
            destination: None,
            queue_limit: 1024,
            reuse_port: false,
        }
    }
}

/// One received datagram.
#[derive(Clone, Debug)]
pub struct Datagram {
    /// Payload.
    pub bytes: Vec<u8>,
    /// Sender.
    pub from: SocketAddr,
    /// When the receive thread got it.
    pub received: Instant,
}

/// Counters of an endpoint since it opened.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EndpointStats {
    /// Datagrams received (queued, including those later dropped as oldest).
    pub received: u64,
    /// Datagrams dropped because the queue was full (the oldest ones).
    pub dropped_queue_full: u64,
    /// Datagrams over 65,507 octets, dropped.
    pub oversized: u64,
    /// Sends that failed.
    pub send_errors: u64,
    /// Receive calls that failed (other than the poll timeout).
    pub receive_errors: u64,
    /// Datagrams queued now.
    pub queue_len: usize,
    /// Most datagrams ever queued at once.
    pub peak_queue_len: usize,
}

#[derive(Default)]
struct Counters {
    received: AtomicU64,
    dropped_queue_full: AtomicU64,
    oversized: AtomicU64,
    send_errors: AtomicU64,
    receive_errors: AtomicU64,
}

struct Queue {
    items: VecDeque<Datagram>,
    peak: usize,
}

struct Shared {
    queue: Mutex<Queue>,
    arrived: Condvar,
    counters: Counters,
    stop: AtomicBool,
}

impl Shared {
    fn lock(&self) -> std::sync::MutexGuard<'_, Queue> {
        // The queue holds plain data; a panic elsewhere cannot leave it half-written.
        self.queue.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A UDP endpoint with its receive thread and bounded queue.
pub struct UdpEndpoint {
    label: &'static str,
    socket: Arc<UdpSocket>,
    local: SocketAddr,
    destination: Option<SocketAddr>,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl UdpEndpoint {
    /// Binds the socket as configured and starts the receive thread.
    ///
    /// # Errors
    /// One line naming the endpoint, the address and the reason (address in use, no such
    /// interface, multicast refused …).
    pub fn open(config: EndpointConfig) -> Result<UdpEndpoint, NetError> {
        let label = config.label;
        let fail = |reason: String| NetError::Endpoint { label, reason };
        // An operating-system refusal: what was refused, then the system's reason.
        let refused = |what: String| move |e: std::io::Error| fail(format!("{what}: {e}"));
        if config.queue_limit == 0 {
            return Err(fail(
                "the receive queue limit must be at least 1 datagram".into(),
            ));
        }
        let interface = config
            .bind
            .resolve()
            .map_err(|e| fail(format!("cannot bind to {}: {e}", config.bind)))?;
        let bind_ip: IpAddr = match config.delivery {
            Delivery::Unicast => interface.address,
            Delivery::Broadcast => {
                if !interface.address.is_ipv4() {
                    return Err(fail(format!(
                        "broadcast needs an IPv4 address, {} is not one",
                        interface.address
                    )));
                }
                let broadcast = interface.broadcast.ok_or_else(|| {
                    fail(format!(
                        "{} ({}) has no broadcast address",
                        config.bind, interface.address
                    ))
                })?;
                IpAddr::V4(broadcast)
            }
            Delivery::Multicast(group) => {
                if !group.is_multicast() {
                    return Err(fail(format!(
                        "{group} is not a multicast group address (224.0.0.0/4)"
                    )));
                }
                if !interface.address.is_ipv4() {
                    return Err(fail(format!(
                        "multicast needs an IPv4 interface address, {} is not one",
                        interface.address
                    )));
                }
                if cfg!(target_os = "linux") {
                    IpAddr::V4(group)
                } else {
                    IpAddr::V4(Ipv4Addr::UNSPECIFIED)
                }
            }
        };
        let bind_addr = SocketAddr::new(bind_ip, config.port);
        let socket = Socket::new(
            Domain::for_address(bind_addr),
            Type::DGRAM,
            Some(Protocol::UDP),
        )
        .map_err(refused("cannot create a UDP socket".into()))?;
        if config.reuse_port {
            socket
                .set_reuse_address(true)
                .map_err(refused("SO_REUSEADDR refused".into()))?;
            #[cfg(all(unix, not(target_os = "solaris"), not(target_os = "illumos")))]
            socket
                .set_reuse_port(true)
                .map_err(refused("SO_REUSEPORT refused".into()))?;
        }
        if let Err(e) = socket.set_recv_buffer_size(SOCKET_RECEIVE_BUFFER_OCTETS) {
            tracing::debug!("{label}: receive buffer size not raised: {e}");
        }
        if config.delivery == Delivery::Broadcast {
            socket
                .set_broadcast(true)
                .map_err(refused("SO_BROADCAST refused".into()))?;
        }
        socket
            .bind(&SockAddr::from(bind_addr))
            .map_err(refused(format!("cannot bind UDP {bind_addr}")))?;
        if let (Delivery::Multicast(group), IpAddr::V4(on)) = (config.delivery, interface.address) {
            socket
                .join_multicast_v4(&group, &on)
                .map_err(refused(format!(
                    "cannot join multicast group {group} on {on}"
                )))?;
            if !on.is_unspecified() {
                socket
                    .set_multicast_if_v4(&on)
                    .map_err(refused(format!("cannot send multicast through {on}")))?;
            }
            socket
                .set_multicast_loop_v4(true)
                .map_err(refused("IP_MULTICAST_LOOP refused".into()))?;
        }
        socket
            .set_read_timeout(Some(RECEIVE_POLL))
            .map_err(refused("cannot set the read timeout".into()))?;
        let socket: UdpSocket = socket.into();
        let local = socket
            .local_addr()
            .map_err(refused("no local address after bind".into()))?;
        let destination = config.destination.or(match config.delivery {
            Delivery::Unicast => None,
            Delivery::Broadcast | Delivery::Multicast(_) => Some(local),
        });
        let socket = Arc::new(socket);
        let shared = Arc::new(Shared {
            queue: Mutex::new(Queue {
                items: VecDeque::with_capacity(config.queue_limit.min(4096)),
                peak: 0,
            }),
            arrived: Condvar::new(),
            counters: Counters::default(),
            stop: AtomicBool::new(false),
        });
        let thread = {
            let socket = Arc::clone(&socket);
            let shared = Arc::clone(&shared);
            let limit = config.queue_limit;
            std::thread::Builder::new()
                .name(format!("cig-{}-rx", label.to_ascii_lowercase()))
                .spawn(move || receive_loop(label, &socket, &shared, limit))
                .map_err(refused("cannot start the receive thread".into()))?
        };
        tracing::info!(
            "{label}: listening on UDP {local} ({:?}, queue {} datagrams)",
            config.delivery,
            config.queue_limit
        );
        Ok(UdpEndpoint {
            label,
            socket,
            local,
            destination,
            shared,
            thread: Some(thread),
        })
    }

    /// The bound address (with the port the kernel chose for port 0).
    #[must_use]
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The default send target, if any.
    #[must_use]
    pub fn destination(&self) -> Option<SocketAddr> {
        self.destination
    }

    /// Moves every queued datagram to `out` (oldest first) without blocking.
    pub fn drain(&self, out: &mut Vec<Datagram>) {
        let mut queue = self.shared.lock();
        out.extend(queue.items.drain(..));
    }

    /// The oldest queued datagram, waiting up to `timeout` for one.
    #[must_use]
    pub fn recv_timeout(&self, timeout: Duration) -> Option<Datagram> {
        let deadline = Instant::now() + timeout;
        let mut queue = self.shared.lock();
        loop {
            if let Some(d) = queue.items.pop_front() {
                return Some(d);
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            if left.is_zero() {
                return None;
            }
            queue = self
                .shared
                .arrived
                .wait_timeout(queue, left)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }

    /// Sends to the default destination.
    ///
    /// # Errors
    /// When there is no destination, or the kernel refuses the datagram.
    pub fn send(&self, bytes: &[u8]) -> std::io::Result<()> {
        let Some(to) = self.destination else {
            self.shared
                .counters
                .send_errors
                .fetch_add(1, Ordering::Relaxed);
            return Err(std::io::Error::new(
                std::io::ErrorKind::NotConnected,
                format!("{}: no destination to send to", self.label),
            ));
        };
        self.send_to(bytes, to)
    }

    /// Sends one datagram to `to`.
    ///
    /// # Errors
    /// When the kernel refuses the datagram (too large, unreachable, buffer full …).
    pub fn send_to(&self, bytes: &[u8], to: SocketAddr) -> std::io::Result<()> {
        match self.socket.send_to(bytes, to) {
            Ok(n) if n == bytes.len() => Ok(()),
            Ok(n) => {
                self.shared
                    .counters
                    .send_errors
                    .fetch_add(1, Ordering::Relaxed);
                Err(std::io::Error::other(format!(
                    "{}: sent {n} of {} octets to {to}",
                    self.label,
                    bytes.len()
                )))
            }
            Err(e) => {
                self.shared
                    .counters
                    .send_errors
                    .fetch_add(1, Ordering::Relaxed);
                Err(e)
            }
        }
    }

    /// Counters since the endpoint opened.
    #[must_use]
    pub fn stats(&self) -> EndpointStats {
        let c = &self.shared.counters;
        let (queue_len, peak_queue_len) = {
            let q = self.shared.lock();
            (q.items.len(), q.peak)
        };
        EndpointStats {
            received: c.received.load(Ordering::Relaxed),
            dropped_queue_full: c.dropped_queue_full.load(Ordering::Relaxed),
            oversized: c.oversized.load(Ordering::Relaxed),
            send_errors: c.send_errors.load(Ordering::Relaxed),
            receive_errors: c.receive_errors.load(Ordering::Relaxed),
            queue_len,
            peak_queue_len,
        }
    }
}

impl Drop for UdpEndpoint {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            if thread.join().is_err() {
                tracing::error!("{}: the receive thread panicked", self.label);
            }
        }
    }
}

fn receive_loop(label: &'static str, socket: &UdpSocket, shared: &Shared, limit: usize) {
    // One octet more than any UDP payload: a datagram that fills it was cut by the kernel.
    let mut buffer = vec![0u8; 65_536];
    let mut queue_log = RateLimitedLog::new(label);
    let mut error_log = RateLimitedLog::new(label);
    while !shared.stop.load(Ordering::Relaxed) {
        match socket.recv_from(&mut buffer) {
            Ok((n, from)) => {
                let now = Instant::now();
                if n > MAX_UDP_PAYLOAD_OCTETS {
                    shared.counters.oversized.fetch_add(1, Ordering::Relaxed);
                    error_log.note(
                        now,
                        &from.to_string(),
                        &format!("datagram of {n} octets is over {MAX_UDP_PAYLOAD_OCTETS}"),
                    );
                    continue;
                }
                let datagram = Datagram {
                    bytes: buffer.get(..n).unwrap_or_default().to_vec(),
                    from,
                    received: now,
                };
                shared.counters.received.fetch_add(1, Ordering::Relaxed);
                let dropped = {
                    let mut queue = shared.lock();
                    let mut dropped = 0u64;
                    while queue.items.len() >= limit {
                        queue.items.pop_front();
                        dropped += 1;
                    }
                    queue.items.push_back(datagram);
                    queue.peak = queue.peak.max(queue.items.len());
                    dropped
                };
                shared.arrived.notify_one();
                if dropped > 0 {
                    shared
                        .counters
                        .dropped_queue_full
                        .fetch_add(dropped, Ordering::Relaxed);
                    queue_log.note(
                        now,
                        "receive queue",
                        &format!("full at {limit} datagrams, oldest dropped"),
                    );
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) => {}
            Err(e) => {
                shared
                    .counters
                    .receive_errors
                    .fetch_add(1, Ordering::Relaxed);
                error_log.note(Instant::now(), "socket", &format!("receive failed: {e}"));
                // Do not spin on a persistent error.
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
}

/// Counts bad datagrams and logs them at most once per second per source.
///
/// Every call to [`RateLimitedLog::note`] is counted; a `tracing::warn!` line goes out for a
/// source when it has not had one for `interval` (1 s), saying how many were suppressed since
/// its previous line. At most 256 sources are tracked; beyond that, sources silent for longer
/// than the interval are forgotten and the rest share one "other sources" line, so a sender
/// spoofing many addresses cannot grow memory.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::{interface_addresses, LOOPBACK_BROADCAST};

    fn open_loopback(queue_limit: usize) -> UdpEndpoint {
        UdpEndpoint::open(EndpointConfig {
            queue_limit,
            ..EndpointConfig::loopback("TEST", 0)
        })
        .expect("loopback endpoint opens")
    }

    #[test]
    fn round_trip_of_a_datagram_on_loopback() {
        let rx = open_loopback(16);
        let tx = UdpEndpoint::open(EndpointConfig {
            destination: Some(rx.local_addr()),
            ..EndpointConfig::loopback("TEST", 0)
        })
        .unwrap();
        tx.send(b"hello cig").unwrap();
        let d = rx.recv_timeout(Duration::from_secs(5)).expect("datagram");
        assert_eq!(d.bytes, b"hello cig");
        assert_eq!(d.from, tx.local_addr());
        tx.send_to(b"second", rx.local_addr()).unwrap();
        let mut out = Vec::new();
        let deadline = Instant::now() + Duration::from_secs(5);
        while out.is_empty() && Instant::now() < deadline {
            rx.drain(&mut out);
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].bytes, b"second");
        let s = rx.stats();
        assert_eq!(s.received, 2);
        assert_eq!(s.dropped_queue_full, 0);
        assert_eq!(s.queue_len, 0);
    }

    #[test]
    fn send_without_destination_is_an_error_and_counted() {
        let e = open_loopback(4);
        assert!(e.send(b"x").is_err());
        assert_eq!(e.stats().send_errors, 1);
    }

    #[test]
    fn full_queue_drops_the_oldest_and_counts_them() {
        let rx = open_loopback(4);
        let tx = open_loopback(4);
        for i in 0u8..10 {
            tx.send_to(&[i], rx.local_addr()).unwrap();
        }
        let deadline = Instant::now() + Duration::from_secs(5);
        while rx.stats().received < 10 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        let s = rx.stats();
        assert_eq!(s.received, 10);
        assert_eq!(s.dropped_queue_full, 6);
        assert_eq!(s.peak_queue_len, 4);
        let mut out = Vec::new();
        rx.drain(&mut out);
        let kept: Vec<u8> = out.iter().map(|d| d.bytes[0]).collect();
        assert_eq!(kept, vec![6, 7, 8, 9], "the newest four survive, in order");
    }

    #[test]
    fn loopback_binds_127_0_0_1() {
        let e = open_loopback(1);
        assert_eq!(e.local_addr().ip(), IpAddr::V4(Ipv4Addr::LOCALHOST));
        assert_ne!(e.local_addr().port(), 0);
    }

    #[test]
    fn unknown_interface_is_a_one_line_error_naming_it() {
        let e = UdpEndpoint::open(EndpointConfig {
            bind: BindTarget::Interface("nosuchif0".into()),
            ..EndpointConfig::loopback("DIS", 0)
        })
        .err()
        .expect("an unknown interface fails");
        let text = format!("{e:#}");
        assert!(!text.contains('\n'), "{text}");
        assert!(text.contains("nosuchif0") && text.contains("DIS"), "{text}");
    }

    #[test]
    fn interface_by_name_resolves_the_loopback() {
        let lo = interface_addresses()
            .unwrap()
            .into_iter()
            .find(|(_, a)| a.address == IpAddr::V4(Ipv4Addr::LOCALHOST));
        let Some((name, _)) = lo else {
            eprintln!("SKIPPED: no interface holds 127.0.0.1 here");
            return;
        };
        let e = UdpEndpoint::open(EndpointConfig {
            bind: BindTarget::Interface(name),
            ..EndpointConfig::loopback("TEST", 0)
        })
        .unwrap();
        assert_eq!(e.local_addr().ip(), IpAddr::V4(Ipv4Addr::LOCALHOST));
    }

    #[test]
    fn address_not_on_this_machine_is_refused() {
        let e = UdpEndpoint::open(EndpointConfig {
            bind: BindTarget::Address("192.0.2.77".parse().unwrap()),
            ..EndpointConfig::loopback("CIGI", 0)
        })
        .err()
        .expect("TEST-NET address is not local");
        assert!(format!("{e:#}").contains("192.0.2.77"));
    }

    /// Two broadcast endpoints sharing one loopback port, and their configuration.
    fn sharing_pair() -> (EndpointConfig, UdpEndpoint, UdpEndpoint) {
        let config = EndpointConfig {
            reuse_port: true,
            delivery: Delivery::Broadcast,
            ..EndpointConfig::loopback("DIS", 0)
        };
        let a = UdpEndpoint::open(config.clone()).unwrap();
        let b = UdpEndpoint::open(EndpointConfig {
            port: a.local_addr().port(),
            ..config.clone()
        })
        .unwrap();
        (config, a, b)
    }

    #[test]
    fn reuse_port_lets_two_endpoints_share_a_port() {
        let (config, a, b) = sharing_pair();
        assert_eq!(a.local_addr(), b.local_addr());
        // Without sharing, the same port is refused with a one-line error.
        let refused = UdpEndpoint::open(EndpointConfig {
            port: a.local_addr().port(),
            reuse_port: false,
            ..config
        })
        .err()
        .expect("port in use");
        assert!(format!("{refused:#}").contains("cannot bind"));
    }

    /// SO_BROADCAST is set, and a broadcast to the loopback's broadcast address reaches every
    /// endpoint sharing the port.
    #[test]
    fn broadcast_sets_the_flag_and_reaches_every_sharer() {
        let (_, a, b) = sharing_pair();
        let flag = socket2::SockRef::from(a.socket.as_ref())
            .broadcast()
            .unwrap();
        assert!(flag, "SO_BROADCAST set");
        assert_eq!(a.local_addr().ip(), IpAddr::V4(LOOPBACK_BROADCAST));
        assert_eq!(a.destination(), Some(a.local_addr()));
        if let Err(e) = a.send(b"to all") {
            eprintln!("SKIPPED: the kernel refuses loopback broadcast here: {e}");
            return;
        }
        for e in [&a, &b] {
            let d = e
                .recv_timeout(Duration::from_secs(5))
                .expect("broadcast arrives");
            assert_eq!(d.bytes, b"to all");
        }
    }

    #[test]
    fn multicast_on_the_loopback_joins_and_delivers() {
        let group = Ipv4Addr::new(239, 1, 2, 3);
        let config = EndpointConfig {
            reuse_port: true,
            delivery: Delivery::Multicast(group),
            ..EndpointConfig::loopback("DIS", 0)
        };
        let a = match UdpEndpoint::open(config.clone()) {
            Ok(a) => a,
            Err(e) => {
                eprintln!("SKIPPED: the kernel refuses multicast on the loopback: {e:#}");
                return;
            }
        };
        let b = UdpEndpoint::open(EndpointConfig {
            port: a.local_addr().port(),
            ..config
        })
        .unwrap();
        assert_eq!(a.local_addr().ip(), IpAddr::V4(group));
        let r = socket2::SockRef::from(a.socket.as_ref());
        assert!(r.multicast_loop_v4().unwrap());
        assert_eq!(r.multicast_if_v4().unwrap(), Ipv4Addr::LOCALHOST);
        if let Err(e) = a.send(b"group") {
            eprintln!("SKIPPED: the kernel refuses to send multicast on the loopback: {e}");
            return;
        }
        for e in [&a, &b] {
            let Some(d) = e.recv_timeout(Duration::from_secs(2)) else {
                eprintln!(
                    "SKIPPED: loopback multicast is not delivered here (no MULTICAST flag on lo)"
                );
                return;
            };
            assert_eq!(d.bytes, b"group");
        }
        // A unicast group address is refused.
        let bad = UdpEndpoint::open(EndpointConfig {
            delivery: Delivery::Multicast(Ipv4Addr::new(10, 0, 0, 1)),
            ..EndpointConfig::loopback("DIS", 0)
        });
        assert!(bad.is_err());
    }

    #[test]
    fn drop_stops_the_receive_thread_quickly() {
        let e = open_loopback(4);
        let started = Instant::now();
        drop(e);
        assert!(started.elapsed() < Duration::from_secs(2));
    }
}
