//! Bind targets and this machine's interface addresses (`getifaddrs(3)`).

use crate::NetError;
use std::net::{IpAddr, Ipv4Addr};
use std::str::FromStr;

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
    type Err = NetError;

    /// "loopback", "any", an IP address, or an interface name.
    fn from_str(text: &str) -> Result<BindTarget, NetError> {
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
        if !plausible {
            return Err(NetError::BadBindTarget(text.to_string()));
        }
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
pub(crate) const LOOPBACK_BROADCAST: Ipv4Addr = Ipv4Addr::new(127, 255, 255, 255);

impl BindTarget {
    /// The local address this target names.
    ///
    /// # Errors
    /// One line naming the interface or address when it does not exist on this machine.
    pub fn resolve(&self) -> Result<InterfaceAddress, NetError> {
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
                    None => return Err(NetError::NotLocal(*address)),
                })
            }
            BindTarget::Interface(name) => {
                let all = interface_addresses()?;
                if let Some((_, found)) = all.iter().find(|(n, a)| n == name && a.address.is_ipv4())
                {
                    return Ok(*found);
                }
                if all.iter().any(|(n, _)| n == name) {
                    return Err(NetError::NoIpv4(name.clone()));
                }
                let mut names: Vec<&str> = all.iter().map(|(n, _)| n.as_str()).collect();
                names.dedup();
                Err(NetError::NoSuchInterface {
                    name: name.clone(),
                    known: names.join(", "),
                })
            }
        }
    }
}

/// Every (interface name, address) pair of this machine, in the kernel's order.
pub(crate) fn interface_addresses() -> Result<Vec<(String, InterfaceAddress)>, NetError> {
    let mut list: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: getifaddrs writes a pointer to a list it allocates, released below.
    let rc = unsafe { libc::getifaddrs(&mut list) };
    if rc != 0 {
        return Err(NetError::Interfaces(
            std::io::Error::last_os_error().to_string(),
        ));
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
