//! cig's network edge: the only crate of cig that opens sockets.
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
//! Bad datagrams are counted and logged at a limited rate ([`RateLimitedLog`]: every one
//! counted, one `tracing` warning a second per source). The addresses users type (HOST:PORT,
//! multicast groups, a scenario's DIS delivery) are parsed here too ([`resolve`],
//! [`parse_delivery`], [`parse_multicast_group`]).
//!
//! Limits: IPv4 for broadcast and multicast (IPv6 addresses work for unicast only); multicast
//! TTL is the kernel's default (1: one subnet); datagrams bound to a broadcast or multicast
//! address do not receive unicast sent to the host's own address; with SO_REUSEPORT the kernel
//! hands each unicast datagram to only one of the sharing sockets (broadcast and multicast reach
//! all of them). IPv4 cannot carry a UDP payload above 65,507 octets; larger ones (IPv6) are
//! counted as oversized and dropped. Nothing here prints: the caller reports.

mod address;
mod endpoint;
mod interface;
mod log;

pub use address::{free_udp_port, parse_delivery, parse_multicast_group, resolve, resolve_host};
pub use endpoint::{
    Datagram, Delivery, EndpointConfig, EndpointStats, UdpEndpoint, MAX_UDP_PAYLOAD_OCTETS,
};
pub use interface::{BindTarget, InterfaceAddress};
pub use log::RateLimitedLog;

/// Why an address could not be used or an endpoint could not open. One line each; the
/// endpoint's errors start with its label ("CIGI", "DIS").
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NetError {
    /// A bind target that is none of the accepted forms.
    #[error("bind target {0:?} is not \"loopback\", \"any\", an IP address or an interface name")]
    BadBindTarget(String),
    /// A bind address that no interface of this machine holds.
    #[error("bind address {0} is not an address of this machine")]
    NotLocal(std::net::IpAddr),
    /// A named interface without an IPv4 address.
    #[error("interface {0:?} has no IPv4 address")]
    NoIpv4(String),
    /// A named interface this machine does not have.
    #[error("interface {name:?} does not exist (this machine has: {known})")]
    NoSuchInterface { name: String, known: String },
    /// `getifaddrs` failed.
    #[error("listing network interfaces: {0}")]
    Interfaces(String),
    /// Text that should be an IPv4 address (`what` names it).
    #[error("{what} {text:?} is not an IPv4 address")]
    NotIpv4 { what: String, text: String },
    /// An IPv4 address outside 224.0.0.0/4.
    #[error("{what} {group} is not a multicast group (224.0.0.0 to 239.255.255.255)")]
    NotMulticast {
        what: String,
        group: std::net::Ipv4Addr,
    },
    /// Text that is not HOST:PORT.
    #[error("{what} {text:?} is not HOST:PORT: {reason}")]
    NotHostPort {
        what: String,
        text: String,
        reason: String,
    },
    /// A host name that does not resolve.
    #[error("{what} {host:?} does not resolve: {reason}")]
    Unresolved {
        what: String,
        host: String,
        reason: String,
    },
    /// A host name that resolves to nothing.
    #[error("{what} {text:?} names no address")]
    NoAddress { what: String, text: String },
    /// A host name that resolves to no address (a bare host, the port given apart).
    #[error("{what} {host:?} resolves to no address")]
    ResolvesToNothing { what: String, host: String },
    /// A scenario's DIS delivery that is none of the accepted forms.
    #[error("delivery {0:?} is not broadcast, multicast:GROUP or unicast:HOST:PORT")]
    BadDelivery(String),
    /// An endpoint that cannot open: its label, then why (and where).
    #[error("{label}: {reason}")]
    Endpoint { label: &'static str, reason: String },
    /// A free port could not be found.
    #[error("no free UDP port on the loopback: {0}")]
    NoFreePort(String),
}
