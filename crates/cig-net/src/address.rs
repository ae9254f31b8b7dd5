//! The addresses users type: HOST:PORT, multicast groups, a scenario's DIS delivery, the
//! delivery of the DIS tools' flags; and a free port for a child process to bind.

use crate::endpoint::Delivery;
use crate::NetError;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, ToSocketAddrs, UdpSocket};

/// Parses an IPv4 multicast group (224.0.0.0/4); `what` names the value in errors.
///
/// # Errors
/// When the text is not an IPv4 address, or not a multicast one.
pub fn parse_multicast_group(text: &str, what: &str) -> Result<Ipv4Addr, NetError> {
    let group: Ipv4Addr = text.trim().parse().map_err(|_| NetError::NotIpv4 {
        what: what.to_string(),
        text: text.to_string(),
    })?;
    if !group.is_multicast() {
        return Err(NetError::NotMulticast {
            what: what.to_string(),
            group,
        });
    }
    Ok(group)
}

impl Delivery {
    /// The delivery of the DIS tools' flags: multicast to `multicast`'s group when given
    /// (`what` names the flag in errors), else broadcast or unicast.
    ///
    /// # Errors
    /// When the group is not an IPv4 multicast address.
    pub fn from_flags(
        broadcast: bool,
        multicast: Option<&str>,
        what: &str,
    ) -> Result<Delivery, NetError> {
        if let Some(group) = multicast {
            return Ok(Delivery::Multicast(parse_multicast_group(group, what)?));
        }
        Ok(if broadcast {
            Delivery::Broadcast
        } else {
            Delivery::Unicast
        })
    }
}

/// Resolves "HOST:PORT"; `what` names the value in errors.
///
/// # Errors
/// When the text is not HOST:PORT or names no address.
pub fn resolve(text: &str, what: &str) -> Result<SocketAddr, NetError> {
    text.to_socket_addrs()
        .map_err(|e| NetError::NotHostPort {
            what: what.to_string(),
            text: text.to_string(),
            reason: e.to_string(),
        })?
        .next()
        .ok_or_else(|| NetError::NoAddress {
            what: what.to_string(),
            text: text.to_string(),
        })
}

/// Resolves a host (a name or an address) at `port`, preferring an IPv4 address; `what` names
/// the value in errors.
///
/// # Errors
/// When the name does not resolve, or resolves to nothing.
pub fn resolve_host(host: &str, port: u16, what: &str) -> Result<SocketAddr, NetError> {
    let host = host.trim();
    if let Ok(ip) = host.parse::<IpAddr>() {
        return Ok(SocketAddr::new(ip, port));
    }
    let found: Vec<SocketAddr> = (host, port)
        .to_socket_addrs()
        .map_err(|e| NetError::Unresolved {
            what: what.to_string(),
            host: host.to_string(),
            reason: e.to_string(),
        })?
        .collect();
    found
        .iter()
        .find(|a| a.is_ipv4())
        .or(found.first())
        .copied()
        .ok_or_else(|| NetError::ResolvesToNothing {
            what: what.to_string(),
            host: host.to_string(),
        })
}

/// Parses a scenario's DIS delivery: "broadcast", "multicast:GROUP" or "unicast:HOST:PORT";
/// returns the delivery and where to send (the group at `port` for multicast).
///
/// # Errors
/// When the text is none of those forms, the group is not multicast or the host does not
/// resolve.
pub fn parse_delivery(text: &str, port: u16) -> Result<(Delivery, Option<SocketAddr>), NetError> {
    let text = text.trim();
    if text == "broadcast" {
        return Ok((Delivery::Broadcast, None));
    }
    if let Some(group) = text.strip_prefix("multicast:") {
        let group = parse_multicast_group(group, "delivery multicast group")?;
        return Ok((
            Delivery::Multicast(group),
            Some(SocketAddr::from((group, port))),
        ));
    }
    if let Some(to) = text.strip_prefix("unicast:") {
        return Ok((Delivery::Unicast, Some(resolve(to, "delivery")?)));
    }
    Err(NetError::BadDelivery(text.to_string()))
}

/// A UDP port free on the loopback now (bound, then released), for a child process to bind.
///
/// # Errors
/// When no socket can be bound on the loopback.
pub fn free_udp_port() -> Result<u16, NetError> {
    let socket = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0))
        .map_err(|e| NetError::NoFreePort(e.to_string()))?;
    Ok(socket
        .local_addr()
        .map_err(|e| NetError::NoFreePort(e.to_string()))?
        .port())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deliveries_parse_and_refuse_with_one_line() {
        assert_eq!(
            parse_delivery("broadcast", 3000).unwrap(),
            (Delivery::Broadcast, None)
        );
        let (d, to) = parse_delivery("multicast:239.1.2.3", 3000).unwrap();
        assert_eq!(d, Delivery::Multicast(Ipv4Addr::new(239, 1, 2, 3)));
        assert_eq!(to, Some("239.1.2.3:3000".parse().unwrap()));
        let (d, to) = parse_delivery("unicast:127.0.0.1:3001", 3000).unwrap();
        assert_eq!(d, Delivery::Unicast);
        assert_eq!(to, Some("127.0.0.1:3001".parse().unwrap()));
        let e = parse_delivery("multicast:10.0.0.1", 3000).unwrap_err();
        assert!(e.to_string().contains("not a multicast group"), "{e}");
        assert!(parse_delivery("anycast", 3000).is_err());
        assert_eq!(
            Delivery::from_flags(true, None, "--multicast").unwrap(),
            Delivery::Broadcast
        );
        assert!(Delivery::from_flags(false, Some("1.2.3.4"), "--multicast")
            .unwrap_err()
            .to_string()
            .starts_with("--multicast"));
    }

    #[test]
    fn hosts_resolve_preferring_ipv4() {
        assert_eq!(
            resolve_host("127.0.0.1", 3000, "--to").unwrap(),
            "127.0.0.1:3000".parse().unwrap()
        );
        assert_eq!(
            resolve("127.0.0.1:8004", "--ig").unwrap(),
            "127.0.0.1:8004".parse().unwrap()
        );
        assert!(resolve("no port", "--ig")
            .unwrap_err()
            .to_string()
            .starts_with("--ig"));
        assert_ne!(free_udp_port().unwrap(), 0);
    }
}
