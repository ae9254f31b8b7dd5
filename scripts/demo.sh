#!/usr/bin/env bash
# README command 1: install what is missing, build, generate the demo database, run the demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo build --release -p cig
exec target/release/cig demo "$@"
