#!/usr/bin/env bash
# Soak: `cig serve` for MINUTES (default 60) over the demo database under a host flying at
# 300 m/s, 200 dead-reckoned DIS entities, smoke, clouds and a storm; its resident memory,
# frame time, descriptors and threads watched for drift (`cig bench soak`). Writes the report
# to soak-out/ and exits 1 when memory grows more than 2 % after minute 5, frame time grows,
# or a descriptor or thread leaks.
#   scripts/soak.sh [MINUTES] [more `cig bench soak` options, e.g. --db DIR --size 640x480]
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-60}"
shift || true
case "$minutes" in
  '' | *[!0-9.]* | *.*.*) echo "soak.sh: MINUTES must be a number, not '$minutes'" >&2; exit 2 ;;
esac
scripts/setup.sh
cargo build --release --locked -p cig
mkdir -p soak-out
report="soak-out/soak-$(date -u +%Y%m%dT%H%M%SZ).json"
echo "soak: $minutes min; the report goes to $report" >&2
status=0
target/release/cig bench soak --minutes "$minutes" --json "$@" >"$report" || status=$?
python3 - "$report" <<'PY' || true
import json, sys
r = json.load(open(sys.argv[1]))
print(f"resident memory {r['rss_kib_at_warm']/1024:.1f} -> {r['rss_kib_end']/1024:.1f} MiB ({r['rss_growth_pct']:+.2f} %), "
      f"frame time x{r['frame_time_ratio']:.2f}, descriptors {r['fds']}, threads {r['threads']}: "
      f"{'passed' if r['passed'] else 'FAILED'}")
PY
exit "$status"
