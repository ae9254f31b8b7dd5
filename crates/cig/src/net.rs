//! The network edge: the only place in cig where sockets are opened.
//!
//! Algorithm: one UDP socket per protocol endpoint (CIGI, DIS), created with `socket2` so the
//! address-sharing options (SO_REUSEADDR, SO_REUSEPORT: several IGs on one machine share the
//! DIS port) are set before `bind`. One receive thread per endpoint blocks in `recv_from` with a
//! 50 ms read timeout (so dropping the endpoint stops it within that time) and pushes each
//! datagram, stamped with its monotonic receive time, into a bounded FIFO. When the FIFO is full
//! the OLDEST datagram is dropped and counted: a frame loop that falls behind sees the newest
//! state, and memory stays bounded (`queue_limit` × 64 KiB at worst). The frame loop takes
//! everything queued once per frame ([`UdpEndpoint::drain`]), never blocking.
//!
//! Where it binds ([`BindTarget`]): the loopback interface by default; an interface by name
//! (its IPv4 address, read with `getifaddrs(3)`) or an address when told; all interfaces only
//! with `any`. Delivery ([`Delivery`]) follows IEEE 1278.2 §4 (DIS over UDP/IP: unicast,
//! broadcast or multicast) and the Linux rules for which socket a datagram reaches (ip(7),
//! udp(7)): a socket bound to a unicast address receives only datagrams sent to that address,
//! so
//! * unicast binds the interface address;
//! * broadcast binds the interface's broadcast address (127.255.255.255 on the loopback,
//!   255.255.255.255 with `any`) with SO_BROADCAST, and sends there by default;
//! * multicast binds the group address, joins the group on the interface address
//!   (IP_ADD_MEMBERSHIP), sends through that interface (IP_MULTICAST_IF) with loopback on (so
//!   IGs on one machine see each other) and sends to the group by default.
//!
//! Limits: IPv4 for broadcast and multicast (IPv6 addresses work for unicast only); multicast
//! TTL is the kernel's default (1: one subnet); datagrams bound to a broadcast or multicast
//! address do not receive unicast sent to the host's own address; with SO_REUSEPORT the kernel
//! hands each unicast datagram to only one of the sharing sockets (broadcast and multicast reach
//! all of them). IPv4 cannot carry a UDP payload above 65,507 octets; larger ones (IPv6) are
//! counted as oversized and dropped.

use anyhow::Context;
use socket2::{Domain, Protocol, SockAddr, Socket, Type};
use std::collections::{BTreeMap, VecDeque};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::str::FromStr;
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

/// Where an endpoint binds.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum BindTarget {
    /// 127.0.0.1 (the default: nothing outside this machine can reach it).
    #[default]
    Loopback,
    /// Every interface (0.0.0.0); only when the user asks for it.
    Any,
    /// One local address.
    Address(IpAddr),
    /// The IPv4 address of a named interface (e.g. `eth0`).
    Interface(String),
}

impl FromStr for BindTarget {
    type Err = anyhow::Error;

    /// "loopback", "any", an IP address, or an interface name.
    fn from_str(text: &str) -> anyhow::Result<BindTarget> {
        let text = text.trim();
        match text {
            "loopback" | "lo" => return Ok(BindTarget::Loopback),
            "any" => return Ok(BindTarget::Any),
            _ => {}
        }
        if let Ok(address) = text.parse::<IpAddr>() {
            return Ok(BindTarget::Address(address));
        }
        // Interface names: at most IFNAMSIZ − 1 = 15 octets, no '/', ':' or white space
        // (netdevice(7)); anything else is a typo of one of the forms above.
        let plausible = !text.is_empty()
            && text.len() <= 15
            && text
                .chars()
                .all(|c| c.is_ascii_graphic() && c != '/' && c != ':');
        anyhow::ensure!(
            plausible,
            "bind target {text:?} is not \"loopback\", \"any\", an IP address or an interface name"
        );
        Ok(BindTarget::Interface(text.to_string()))
    }
}

impl std::fmt::Display for BindTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BindTarget::Loopback => write!(f, "loopback"),
            BindTarget::Any => write!(f, "any"),
            BindTarget::Address(a) => write!(f, "{a}"),
            BindTarget::Interface(name) => write!(f, "interface {name}"),
        }
    }
}

/// An interface address and, where it has one, its IPv4 broadcast address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InterfaceAddress {
    /// The address to bind for unicast and to join multicast groups on.
    pub address: IpAddr,
    /// The subnet's broadcast address, when the interface broadcasts.
    pub broadcast: Option<Ipv4Addr>,
}

/// The loopback's directed broadcast address (Linux routes 127.255.255.255 to `lo` as
/// broadcast in its local table).
const LOOPBACK_BROADCAST: Ipv4Addr = Ipv4Addr::new(127, 255, 255, 255);

impl BindTarget {
    /// The local address this target names.
    ///
    /// # Errors
    /// One line naming the interface or address when it does not exist on this machine.
    pub fn resolve(&self) -> anyhow::Result<InterfaceAddress> {
        match self {
            BindTarget::Loopback => Ok(InterfaceAddress {
                address: IpAddr::V4(Ipv4Addr::LOCALHOST),
                broadcast: Some(LOOPBACK_BROADCAST),
            }),
            BindTarget::Any => Ok(InterfaceAddress {
                address: IpAddr::V4(Ipv4Addr::UNSPECIFIED),
                broadcast: Some(Ipv4Addr::BROADCAST),
            }),
            BindTarget::Address(address) if address.is_unspecified() => Ok(InterfaceAddress {
                // 0.0.0.0 or :: typed out: every interface, as `any`.
                address: *address,
                broadcast: address.is_ipv4().then_some(Ipv4Addr::BROADCAST),
            }),
            BindTarget::Address(address) => {
                let listed = interface_addresses()?
                    .into_iter()
                    .find(|(_, a)| a.address == *address);
                Ok(match listed {
                    Some((_, found)) => found,
                    None if address.is_loopback() => InterfaceAddress {
                        address: *address,
                        broadcast: Some(LOOPBACK_BROADCAST),
                    },
                    None => {
                        anyhow::bail!("bind address {address} is not an address of this machine")
                    }
                })
            }
            BindTarget::Interface(name) => {
                let all = interface_addresses()?;
                if let Some((_, found)) = all.iter().find(|(n, a)| n == name && a.address.is_ipv4())
                {
                    return Ok(*found);
                }
                if all.iter().any(|(n, _)| n == name) {
                    anyhow::bail!("interface {name:?} has no IPv4 address");
                }
                let mut names: Vec<&str> = all.iter().map(|(n, _)| n.as_str()).collect();
                names.dedup();
                anyhow::bail!(
                    "interface {name:?} does not exist (this machine has: {})",
                    names.join(", ")
                )
            }
        }
    }
}

/// Every (interface name, address) pair of this machine, in the kernel's order.
fn interface_addresses() -> anyhow::Result<Vec<(String, InterfaceAddress)>> {
    let mut list: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: getifaddrs writes a pointer to a list it allocates, released below.
    let rc = unsafe { libc::getifaddrs(&mut list) };
    if rc != 0 {
        return Err(std::io::Error::last_os_error()).context("listing network interfaces");
    }
    let mut out = Vec::new();
    let mut node = list;
    while !node.is_null() {
        // SAFETY: `node` is an element of the list getifaddrs returned, not yet freed.
        let entry = unsafe { &*node };
        node = entry.ifa_next;
        if entry.ifa_name.is_null() || entry.ifa_addr.is_null() {
            continue;
        }
        // SAFETY: ifa_name is a NUL-terminated string owned by the list.
        let name = unsafe { std::ffi::CStr::from_ptr(entry.ifa_name) }
            .to_string_lossy()
            .into_owned();
        // SAFETY: ifa_addr points to a sockaddr whose family says which struct it is.
        let address = unsafe { socket_address_ip(entry.ifa_addr) };
        let Some(address) = address else { continue };
        let broadcasts = entry.ifa_flags & (libc::IFF_BROADCAST as libc::c_uint) != 0;
        let broadcast = if broadcasts && address.is_ipv4() {
            // SAFETY: with IFF_BROADCAST the union holds the broadcast address (or null).
            let raw = entry.ifa_ifu;
            if raw.is_null() {
                None
            } else {
                match unsafe { socket_address_ip(raw) } {
                    Some(IpAddr::V4(b)) => Some(b),
                    _ => None,
                }
            }
        } else if address.is_loopback() {
            Some(LOOPBACK_BROADCAST)
        } else {
            None
        };
        out.push((name, InterfaceAddress { address, broadcast }));
    }
    // SAFETY: `list` came from getifaddrs and is freed once.
    unsafe { libc::freeifaddrs(list) };
    Ok(out)
}

/// The IP address in a `sockaddr` of family AF_INET or AF_INET6.
///
/// # Safety
/// `raw` must point to a valid `sockaddr` at least as large as its family's struct.
unsafe fn socket_address_ip(raw: *const libc::sockaddr) -> Option<IpAddr> {
    // SAFETY: the caller guarantees `raw` is valid; the family field is common to all.
    let family = i32::from(unsafe { (*raw).sa_family });
    match family {
        libc::AF_INET => {
            // SAFETY: family AF_INET means the struct is a sockaddr_in.
            let v4 = unsafe { &*raw.cast::<libc::sockaddr_in>() };
            Some(IpAddr::V4(Ipv4Addr::from(u32::from_be(v4.sin_addr.s_addr))))
        }
        libc::AF_INET6 => {
            // SAFETY: family AF_INET6 means the struct is a sockaddr_in6.
            let v6 = unsafe { &*raw.cast::<libc::sockaddr_in6>() };
            Some(IpAddr::V6(std::net::Ipv6Addr::from(v6.sin6_addr.s6_addr)))
        }
        _ => None,
    }
}

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

/// Parses an IPv4 multicast group (224.0.0.0/4); `what` names the value in errors.
pub fn parse_multicast_group(text: &str, what: &str) -> anyhow::Result<Ipv4Addr> {
    let group: Ipv4Addr = text
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("{what} {text:?} is not an IPv4 address"))?;
    anyhow::ensure!(
        group.is_multicast(),
        "{what} {group} is not a multicast group (224.0.0.0 to 239.255.255.255)"
    );
    Ok(group)
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
    pub fn open(config: EndpointConfig) -> anyhow::Result<UdpEndpoint> {
        let label = config.label;
        anyhow::ensure!(
            config.queue_limit > 0,
            "{label}: the receive queue limit must be at least 1 datagram"
        );
        let interface = config
            .bind
            .resolve()
            .with_context(|| format!("{label}: cannot bind to {}", config.bind))?;
        let bind_ip: IpAddr = match config.delivery {
            Delivery::Unicast => interface.address,
            Delivery::Broadcast => {
                anyhow::ensure!(
                    interface.address.is_ipv4(),
                    "{label}: broadcast needs an IPv4 address, {} is not one",
                    interface.address
                );
                let broadcast = interface.broadcast.with_context(|| {
                    format!(
                        "{label}: {} ({}) has no broadcast address",
                        config.bind, interface.address
                    )
                })?;
                IpAddr::V4(broadcast)
            }
            Delivery::Multicast(group) => {
                anyhow::ensure!(
                    group.is_multicast(),
                    "{label}: {group} is not a multicast group address (224.0.0.0/4)"
                );
                anyhow::ensure!(
                    interface.address.is_ipv4(),
                    "{label}: multicast needs an IPv4 interface address, {} is not one",
                    interface.address
                );
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
        .with_context(|| format!("{label}: cannot create a UDP socket"))?;
        if config.reuse_port {
            socket
                .set_reuse_address(true)
                .with_context(|| format!("{label}: SO_REUSEADDR refused"))?;
            #[cfg(all(unix, not(target_os = "solaris"), not(target_os = "illumos")))]
            socket
                .set_reuse_port(true)
                .with_context(|| format!("{label}: SO_REUSEPORT refused"))?;
        }
        if let Err(e) = socket.set_recv_buffer_size(SOCKET_RECEIVE_BUFFER_OCTETS) {
            tracing::debug!("{label}: receive buffer size not raised: {e}");
        }
        if config.delivery == Delivery::Broadcast {
            socket
                .set_broadcast(true)
                .with_context(|| format!("{label}: SO_BROADCAST refused"))?;
        }
        socket
            .bind(&SockAddr::from(bind_addr))
            .with_context(|| format!("{label}: cannot bind UDP {bind_addr}"))?;
        if let (Delivery::Multicast(group), IpAddr::V4(on)) = (config.delivery, interface.address) {
            socket
                .join_multicast_v4(&group, &on)
                .with_context(|| format!("{label}: cannot join multicast group {group} on {on}"))?;
            if !on.is_unspecified() {
                socket
                    .set_multicast_if_v4(&on)
                    .with_context(|| format!("{label}: cannot send multicast through {on}"))?;
            }
            socket
                .set_multicast_loop_v4(true)
                .with_context(|| format!("{label}: IP_MULTICAST_LOOP refused"))?;
        }
        socket
            .set_read_timeout(Some(RECEIVE_POLL))
            .with_context(|| format!("{label}: cannot set the read timeout"))?;
        let socket: UdpSocket = socket.into();
        let local = socket
            .local_addr()
            .with_context(|| format!("{label}: no local address after bind"))?;
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
                .with_context(|| format!("{label}: cannot start the receive thread"))?
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
#[derive(Debug)]
pub struct RateLimitedLog {
    label: &'static str,
    interval: Duration,
    total: u64,
    logged: u64,
    sources: BTreeMap<String, SourceLog>,
}

#[derive(Debug, Clone, Copy)]
struct SourceLog {
    last_logged: Instant,
    suppressed: u64,
}

const MAX_TRACKED_SOURCES: usize = 256;
const OTHER_SOURCES: &str = "(other sources)";

impl RateLimitedLog {
    /// A log whose lines start with `label` ("CIGI", "DIS").
    #[must_use]
    pub fn new(label: &'static str) -> RateLimitedLog {
        RateLimitedLog::with_interval(label, Duration::from_secs(1))
    }

    /// The same with another minimum interval between two lines of one source.
    #[must_use]
    pub fn with_interval(label: &'static str, interval: Duration) -> RateLimitedLog {
        RateLimitedLog {
            label,
            interval,
            total: 0,
            logged: 0,
            sources: BTreeMap::new(),
        }
    }

    /// Counts one bad datagram from `source`; logs it unless that source logged within the
    /// interval. Returns whether a line went out.
    pub fn note(&mut self, now: Instant, source: &str, reason: &str) -> bool {
        self.total += 1;
        if !self.sources.contains_key(source) && self.sources.len() >= MAX_TRACKED_SOURCES {
            let interval = self.interval;
            self.sources
                .retain(|_, s| now.saturating_duration_since(s.last_logged) < interval);
        }
        let key = if self.sources.contains_key(source) || self.sources.len() < MAX_TRACKED_SOURCES {
            source
        } else {
            OTHER_SOURCES
        };
        if let Some(entry) = self.sources.get_mut(key) {
            if now.saturating_duration_since(entry.last_logged) < self.interval {
                entry.suppressed += 1;
                return false;
            }
            let suppressed = entry.suppressed;
            *entry = SourceLog {
                last_logged: now,
                suppressed: 0,
            };
            self.emit(key, reason, suppressed);
        } else {
            self.sources.insert(
                key.to_string(),
                SourceLog {
                    last_logged: now,
                    suppressed: 0,
                },
            );
            self.emit(key, reason, 0);
        }
        true
    }

    fn emit(&mut self, source: &str, reason: &str, suppressed: u64) {
        self.logged += 1;
        if suppressed > 0 {
            tracing::warn!(
                "{}: dropped a datagram from {source}: {reason} ({suppressed} more from there since the last report)",
                self.label
            );
        } else {
            tracing::warn!("{}: dropped a datagram from {source}: {reason}", self.label);
        }
    }

    /// Bad datagrams noted so far.
    #[must_use]
    pub fn count(&self) -> u64 {
        self.total
    }

    /// Lines logged so far.
    #[must_use]
    pub fn lines_logged(&self) -> u64 {
        self.logged
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open_loopback(queue_limit: usize) -> UdpEndpoint {
        UdpEndpoint::open(EndpointConfig {
            queue_limit,
            ..EndpointConfig::loopback("TEST", 0)
        })
        .expect("loopback endpoint opens")
    }

    #[test]
    fn bind_target_parses_every_form() {
        assert_eq!(
            "loopback".parse::<BindTarget>().unwrap(),
            BindTarget::Loopback
        );
        assert_eq!("any".parse::<BindTarget>().unwrap(), BindTarget::Any);
        assert_eq!(
            "10.1.2.3".parse::<BindTarget>().unwrap(),
            BindTarget::Address(IpAddr::V4(Ipv4Addr::new(10, 1, 2, 3)))
        );
        assert_eq!(
            "::1".parse::<BindTarget>().unwrap(),
            BindTarget::Address("::1".parse().unwrap())
        );
        assert_eq!(
            "eth0".parse::<BindTarget>().unwrap(),
            BindTarget::Interface("eth0".into())
        );
        for bad in [
            "",
            "a name",
            "10.1.2.3:80",
            "eth0/1",
            "averyveryverylongname",
        ] {
            assert!(
                bad.parse::<BindTarget>().is_err(),
                "{bad:?} must be refused"
            );
        }
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

    #[test]
    fn reuse_port_lets_two_endpoints_share_a_port() {
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
        let config = EndpointConfig {
            reuse_port: true,
            delivery: Delivery::Broadcast,
            ..EndpointConfig::loopback("DIS", 0)
        };
        let a = UdpEndpoint::open(config.clone()).unwrap();
        let b = UdpEndpoint::open(EndpointConfig {
            port: a.local_addr().port(),
            ..config
        })
        .unwrap();
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

    #[test]
    fn rate_limited_log_counts_everything_and_logs_once_per_interval_per_source() {
        let mut log = RateLimitedLog::new("DIS");
        let t0 = Instant::now();
        assert!(log.note(t0, "10.0.0.1:3000", "garbage"));
        for k in 1..=50 {
            assert!(!log.note(
                t0 + Duration::from_millis(k * 10),
                "10.0.0.1:3000",
                "garbage"
            ));
        }
        assert!(
            log.note(t0, "10.0.0.2:3000", "truncated"),
            "another source logs"
        );
        assert!(log.note(t0 + Duration::from_millis(1001), "10.0.0.1:3000", "garbage"));
        assert_eq!(log.count(), 53);
        assert_eq!(log.lines_logged(), 3);
    }

    #[test]
    fn rate_limited_log_memory_is_bounded_under_spoofed_sources() {
        let mut log = RateLimitedLog::new("DIS");
        let t0 = Instant::now();
        for k in 0..10_000u32 {
            log.note(t0, &format!("10.{}.{}.1:1", k / 256, k % 256), "garbage");
        }
        assert_eq!(log.count(), 10_000);
        assert!(log.sources.len() <= MAX_TRACKED_SOURCES + 1);
        // 256 sources logged once, the rest shared one line.
        assert_eq!(log.lines_logged(), MAX_TRACKED_SOURCES as u64 + 1);
    }
}
