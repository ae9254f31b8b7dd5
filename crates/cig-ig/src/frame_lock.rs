//! Frame lock between the display channels of one IG: the master starts no frame while a
//! slave still draws an older one, so at any instant the channels show at most two adjacent
//! host frames (a network swap lock, as multi-channel IGs keep projectors on one frame).
//!
//! Protocol (docs/channels.md). After each frame drawn, a slave sends its master one
//! datagram of 16 octets, neither CIGI nor DIS: the magic `CIGLOCK1`, then the host frame it
//! drew (u32, little-endian), then its channel number (u32, the first view it draws; for logs).
//! The master keeps each slave's newest report ([`FrameLock`]), slaves told apart by their
//! address. Before it starts frame n + 1 (and so before its Start of Frame lets a synchronous
//! host send frame n + 2) it waits until every slave *in the lock* has drawn frame n, for at
//! most the lock timeout. A slave is in the lock from its first report. One that misses the
//! timeout is taken out (the IG must not stall on a dead channel) and comes back in with a
//! report of another frame no more than [`REJOIN_WITHIN_FRAMES`] from the master's: it is
//! alive and on the same host, and the master waits for it again (a slave skips to the newest
//! host frame, so one frame brings it level).
//!
//! Limits: slaves join by reporting (a slave that has never reported is not waited for); a
//! slave slower than the timeout every frame costs the IG a wait every frame, until the timeout
//! (a number of the IG's frames, which then include the waits) outgrows the slave's frame: the
//! IG runs at its slowest channel's rate; host frame numbers are compared with wrapping
//! arithmetic (a half-range apart is "behind"); the lock bounds which frames are drawn, not
//! when each display shows them (no genlock).

use std::collections::BTreeMap;
use std::net::SocketAddr;

/// The lock datagram's first eight octets.
pub const LOCK_MAGIC: &[u8; 8] = b"CIGLOCK1";
/// The lock datagram's length, octets.
pub const LOCK_DATAGRAM_LEN: usize = 16;
/// How far from the master's frame (behind or ahead) a dropped slave's report may be for it to
/// come back.
pub const REJOIN_WITHIN_FRAMES: u32 = 8;

/// A slave's report: it has drawn `host_frame`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameDrawn {
    pub host_frame: u32,
    /// The slave's channel number (its first view), for the master's logs.
    pub channel: u32,
}

/// Why a datagram is not a lock report.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LockDecodeError {
    #[error("a frame-lock datagram is {LOCK_DATAGRAM_LEN} octets, not {0}")]
    Length(usize),
    #[error("not a frame-lock datagram (no CIGLOCK1 magic)")]
    Magic,
}

impl FrameDrawn {
    /// The datagram.
    #[must_use]
    pub fn encode(&self) -> [u8; LOCK_DATAGRAM_LEN] {
        let mut out = [0u8; LOCK_DATAGRAM_LEN];
        out[..8].copy_from_slice(LOCK_MAGIC);
        out[8..12].copy_from_slice(&self.host_frame.to_le_bytes());
        out[12..16].copy_from_slice(&self.channel.to_le_bytes());
        out
    }

    /// Reads a datagram.
    ///
    /// # Errors
    /// When its length or magic is wrong.
    pub fn decode(bytes: &[u8]) -> Result<FrameDrawn, LockDecodeError> {
        let bytes: &[u8; LOCK_DATAGRAM_LEN] = bytes
            .try_into()
            .map_err(|_| LockDecodeError::Length(bytes.len()))?;
        if &bytes[..8] != LOCK_MAGIC {
            return Err(LockDecodeError::Magic);
        }
        let word =
            |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        Ok(FrameDrawn {
            host_frame: word(8),
            channel: word(12),
        })
    }
}

/// Whether host frame `a` is at or after `b` (wrapping).
#[must_use]
pub fn at_or_after(a: u32, b: u32) -> bool {
    a.wrapping_sub(b) < 1 << 31
}

/// A slave as the master knows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlaveState {
    pub last: FrameDrawn,
    /// Waited for (in the lock), or out until it reports another frame.
    pub in_lock: bool,
    /// The frame it was on when it was taken out.
    pub dropped_on: Option<u32>,
}

/// What changed in the lock, for the master's log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LockEvent {
    /// A slave (re)entered the lock.
    Joined(SocketAddr, FrameDrawn),
    /// A slave missed the timeout and was taken out.
    Dropped(SocketAddr, FrameDrawn),
}

/// The master's side of the frame lock.
#[derive(Clone, Debug, Default)]
pub struct FrameLock {
    slaves: BTreeMap<SocketAddr, SlaveState>,
}

impl FrameLock {
    #[must_use]
    pub fn new() -> FrameLock {
        FrameLock::default()
    }

    /// Notes a report from `from`; `master_frame` is the newest host frame the master drew.
    pub fn note(
        &mut self,
        from: SocketAddr,
        drawn: FrameDrawn,
        master_frame: Option<u32>,
    ) -> Option<LockEvent> {
        let slave = self.slaves.entry(from).or_insert(SlaveState {
            last: drawn,
            in_lock: false,
            dropped_on: None,
        });
        // The newest arrival (a restarted slave, or a restarted host, counts again from its
        // own numbers; a reordered datagram at worst makes the master wait for the next).
        slave.last = drawn;
        let rejoins = match slave.dropped_on {
            // New: in from its first report.
            None => true,
            Some(dropped_on) => {
                dropped_on != drawn.host_frame
                    && master_frame.is_none_or(|m| {
                        let f = drawn.host_frame;
                        at_or_after(f.wrapping_add(REJOIN_WITHIN_FRAMES), m)
                            && at_or_after(m.wrapping_add(REJOIN_WITHIN_FRAMES), f)
                    })
            }
        };
        if !slave.in_lock && rejoins {
            slave.dropped_on = None;
            slave.in_lock = true;
            return Some(LockEvent::Joined(from, slave.last));
        }
        None
    }

    /// Whether every slave in the lock has drawn `master_frame` (the master may start its next).
    #[must_use]
    pub fn all_drawn(&self, master_frame: u32) -> bool {
        self.slaves
            .values()
            .filter(|s| s.in_lock)
            .all(|s| at_or_after(s.last.host_frame, master_frame))
    }

    /// The timeout passed: every slave in the lock that has not drawn `master_frame` is taken
    /// out.
    pub fn drop_late(&mut self, master_frame: u32) -> Vec<LockEvent> {
        self.slaves
            .iter_mut()
            .filter(|(_, s)| s.in_lock && !at_or_after(s.last.host_frame, master_frame))
            .map(|(addr, s)| {
                s.in_lock = false;
                s.dropped_on = Some(s.last.host_frame);
                LockEvent::Dropped(*addr, s.last)
            })
            .collect()
    }

    /// Slaves in the lock.
    #[must_use]
    pub fn in_lock(&self) -> usize {
        self.slaves.values().filter(|s| s.in_lock).count()
    }

    /// Every slave that has reported.
    #[must_use]
    pub fn slaves(&self) -> &BTreeMap<SocketAddr, SlaveState> {
        &self.slaves
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn addr(port: u16) -> SocketAddr {
        SocketAddr::from(([127, 0, 0, 1], port))
    }

    fn drawn(host_frame: u32) -> FrameDrawn {
        FrameDrawn {
            host_frame,
            channel: 0,
        }
    }

    proptest! {
        #[test]
        fn reports_round_trip(host_frame: u32, channel: u32) {
            let d = FrameDrawn { host_frame, channel };
            prop_assert_eq!(FrameDrawn::decode(&d.encode()), Ok(d));
        }

        #[test]
        fn any_other_bytes_are_refused_not_misread(bytes in proptest::collection::vec(any::<u8>(), 0..40)) {
            match FrameDrawn::decode(&bytes) {
                Ok(d) => prop_assert_eq!(&d.encode()[..], &bytes[..]),
                Err(LockDecodeError::Length(n)) => prop_assert!(n != LOCK_DATAGRAM_LEN),
                Err(LockDecodeError::Magic) => prop_assert!(&bytes[..8] != LOCK_MAGIC),
            }
        }
    }

    #[test]
    fn a_cigi_message_is_no_lock_report() {
        // IG Control's first octets: packet 1, size 24.
        let mut cigi = [0u8; LOCK_DATAGRAM_LEN];
        cigi[0] = 1;
        cigi[1] = 24;
        assert_eq!(FrameDrawn::decode(&cigi), Err(LockDecodeError::Magic));
        assert_eq!(
            FrameDrawn::decode(&[0; 24]),
            Err(LockDecodeError::Length(24))
        );
    }

    #[test]
    fn frames_compare_across_the_wrap() {
        assert!(at_or_after(5, 5) && at_or_after(6, 5) && !at_or_after(4, 5));
        assert!(at_or_after(2, u32::MAX - 1) && !at_or_after(u32::MAX - 1, 2));
    }

    #[test]
    fn the_master_waits_for_slaves_in_the_lock_and_drops_the_late() {
        let mut lock = FrameLock::new();
        // No slave yet: nothing to wait for.
        assert!(lock.all_drawn(10));
        // Two slaves join with their first reports, one still behind.
        assert!(matches!(
            lock.note(addr(1), drawn(10), Some(10)),
            Some(LockEvent::Joined(..))
        ));
        assert!(matches!(
            lock.note(addr(2), drawn(7), Some(10)),
            Some(LockEvent::Joined(..))
        ));
        assert_eq!(lock.in_lock(), 2);
        assert!(!lock.all_drawn(10), "slave 2 is still on 7");
        assert_eq!(lock.note(addr(2), drawn(10), Some(10)), None);
        assert!(lock.all_drawn(10));
        // Slave 1 dies on 10: the master, on 11, times out and drops it, then waits for
        // slave 2 only.
        lock.note(addr(2), drawn(11), Some(11));
        assert!(!lock.all_drawn(11));
        assert_eq!(
            lock.drop_late(11),
            vec![LockEvent::Dropped(addr(1), drawn(10))]
        );
        assert!(lock.all_drawn(11) && lock.in_lock() == 1);
        assert!(lock.drop_late(11).is_empty());
        // A late datagram of the frame it was dropped on does not bring it back, nor one far
        // behind the master's (a slave of another host, or one still catching up); another
        // frame near the master's does, and the master waits for it again.
        assert_eq!(lock.note(addr(1), drawn(10), Some(20)), None);
        assert_eq!(lock.note(addr(1), drawn(11), Some(20)), None);
        assert_eq!(lock.note(addr(1), drawn(4_000_000), Some(20)), None);
        assert_eq!(lock.in_lock(), 1);
        assert!(matches!(
            lock.note(addr(1), drawn(19), Some(20)),
            Some(LockEvent::Joined(..))
        ));
        assert_eq!(lock.in_lock(), 2);
        assert!(!lock.all_drawn(20));
        lock.note(addr(1), drawn(20), Some(20));
        lock.note(addr(2), drawn(20), Some(20));
        assert!(lock.all_drawn(20));
    }
}
