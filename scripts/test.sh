#!/usr/bin/env bash
# README command 2: the whole test suite (what CI runs).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --test
CIG_TEST_REAL_DEM="$(scripts/fetch-test-data.sh)"
export CIG_TEST_REAL_DEM
# The PyPI test peers live in .cache/py (see setup.sh): their python3 comes first.
PATH="$PWD/.cache/py/bin:$PATH"
export PATH
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
cargo test --workspace --locked
