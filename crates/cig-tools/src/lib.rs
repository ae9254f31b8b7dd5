//! The pure parts of cig's protocol tools, for the `cig host` and `cig dis` commands.
//!
//! - [`host`]: the scripted CIGI host — the script file (TOML), each host frame's message
//!   (IG Control, entities moved along their paths, the view, HAT/HOT and LOS requests), and
//!   the IG's replies read into counters and one JSON object per packet.
//! - [`dis`]: the DIS diagnostic tools — each PDU of a datagram described as one readable line
//!   or one JSON object (IEEE 1278.1-2012 header and the fields an IG uses), and the Entity
//!   State PDUs `cig dis send` sends, built by cig's own publisher.
//!
//! Pure: bytes and text in, messages, bytes, lines and JSON values out. No sockets (the binary
//! opens them through `cig-net`), clocks or terminal (the binary prints what these return).
//! Limits: see each module.

pub mod dis;
pub mod host;

/// Why a tool refused its input. One line each.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ToolError {
    /// A command-line value that is malformed or out of range; the message names the option.
    #[error("{0}")]
    Argument(String),
    /// A host script that does not parse or holds a value out of range.
    #[error("{0}")]
    Script(String),
    /// A host script's time that is not an ISO 8601 instant.
    #[error("time: {0}")]
    Time(String),
    /// A message from the IG the host cannot decode.
    #[error("the IG sent a message this host cannot read: {0}")]
    Unreadable(String),
    /// A PDU that cannot be encoded.
    #[error("DIS: cannot encode the Entity State: {0}")]
    Encode(String),
}
