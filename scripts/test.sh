#!/usr/bin/env bash
# The whole test suite from a fresh clone: Rust tests (engine, oracles,
# exact reference). Needs ../shared beside the repository.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --all-targets 2>&1
