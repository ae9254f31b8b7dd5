//! What every report carries (the machine and the date) and the statistics of the figures.

/// The machine: CPU model, cores, OS and architecture.
pub(crate) fn machine() -> serde_json::Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    serde_json::json!({
        "cpu": cpu,
        "cores": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        "os": std::env::consts::OS,
        "arch": std::env::consts::ARCH,
    })
}

/// The UTC date and time now, "YYYY-MM-DDTHH:MM:SSZ" (1970-01-01T00:00:00Z for a clock
/// outside 1900..2100).
pub(crate) fn date_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    cig_environment::UtcTime::from_unix_seconds(secs as f64).map_or_else(
        |_| "1970-01-01T00:00:00Z".into(),
        |t| t.to_iso8601_seconds(),
    )
}

/// The element at half the length of the sorted values (the upper median); NaN when empty.
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The sorted values' element at `q` (0..1) of the way, rounded to the nearest; NaN when empty.
pub(crate) fn percentile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((s.len() as f64 - 1.0) * q).round() as usize;
    s.get(i).copied().unwrap_or(f64::NAN)
}

/// A process's `/proc/PROCESS/status` (`PROCESS`: a pid, or `self`), read as its numeric
/// fields (Linux; `None` elsewhere, or when the process has ended).
pub(crate) struct ProcStatus(String);

impl ProcStatus {
    pub fn read(process: &str) -> Option<ProcStatus> {
        std::fs::read_to_string(format!("/proc/{process}/status"))
            .ok()
            .map(ProcStatus)
    }

    /// The first number of the line that starts with `name` ("VmRSS:" → kB).
    pub fn field(&self, name: &str) -> Option<u64> {
        self.0
            .lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<u64>().ok())
    }
}

/// The CPU time a process (a pid, or `self`) has used, user and system, seconds (Linux's
/// `/proc/PROCESS/stat`, in its clock ticks of 1/100 s; `None` elsewhere, or when it has ended).
pub(crate) fn cpu_time_s(process: &str) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{process}/stat")).ok()?;
    // The name in parentheses may hold spaces: the fields are counted after its ')'.
    let after = stat.get(stat.rfind(')')? + 1..)?;
    let fields: Vec<&str> = after.split_whitespace().collect();
    // Fields 14 and 15 of the line (utime, stime) are the 12th and 13th after the name.
    let ticks = |i: usize| fields.get(i).and_then(|v| v.parse::<u64>().ok());
    Some((ticks(11)? + ticks(12)?) as f64 / 100.0)
}

/// VmRSS and VmHWM of this process, kB (Linux; `None` elsewhere).
pub(crate) fn memory_kb() -> (Option<u64>, Option<u64>) {
    match ProcStatus::read("self") {
        Some(status) => (status.field("VmRSS:"), status.field("VmHWM:")),
        None => (None, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_of_a_few_values() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0, 6.0];
        assert_eq!(median(&v), 4.0);
        assert_eq!(percentile(&v, 0.5), 4.0);
        assert_eq!(percentile(&v, 1.0), 6.0);
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert!(median(&[]).is_nan() && percentile(&[], 0.9).is_nan());
        let date = date_utc();
        assert_eq!((date.len(), &date[10..11]), (20, "T"));
        if cfg!(target_os = "linux") {
            // Work done shows as CPU time.
            let before = cpu_time_s("self").expect("cpu time");
            let until = std::time::Instant::now() + std::time::Duration::from_millis(150);
            let mut x = 0u64;
            while std::time::Instant::now() < until {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            let after = cpu_time_s("self").expect("cpu time");
            assert!(after - before >= 0.05, "{before} {after}");
        }
        assert!(cpu_time_s("no-such-process").is_none());
    }
}
