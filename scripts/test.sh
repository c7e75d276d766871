#!/usr/bin/env bash
# The whole test suite from a fresh clone (needs ../shared beside the
# repository): Rust tests (engine, exact references, FMU instance, C header
# and C program), then the FMU under fmpy (pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --all-targets 2>&1
cargo build --release --bin engine_run
.venv/bin/python -m pytest tests/python -q -rs -p no:cacheprovider 2>&1
