#!/usr/bin/env bash
# README command 1: install what is missing, build, generate the demo database, run the demo.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec cargo run --release --locked -p cig -- demo "$@"
