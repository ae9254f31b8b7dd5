//! A rate-limited log of bad datagrams.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

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
