#!/usr/bin/env bash
# The whole test suite from a fresh clone (needs ../shared beside the
# repository): Rust tests (engine, exact references, FMU instance, C header
# and C program), the benchmarks run once in test mode, then the FMU under
# fmpy (pytest). Ends with one line saying PASS and how long it took.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
step() { printf '\n== %s\n' "$*"; }
step "setup: .venv and the FMU"
bash scripts/setup.sh
step "Rust: library, integration tests, examples"
cargo test --lib --bins --tests --examples 2>&1
step "Rust: benchmarks, run once in test mode (a smoke test; their figures go to target/test-benches.log, the numbers are in docs/accuracy-speed.md)"
if cargo test --benches > target/test-benches.log 2>&1; then
  echo "benchmarks: ran once in test mode, ok"
else
  cat target/test-benches.log
  exit 1
fi
cargo build --release --bin engine_run
step "Python: the FMU under fmpy, the study, the advisor (pytest)"
.venv/bin/python -m pytest tests/python -q -p no:cacheprovider -rs 2>&1
seconds=$(( $(date +%s) - start ))
printf '\ntest.sh: PASS: Rust, C and Python tests all passed in %d min %02d s\n' $((seconds / 60)) $((seconds % 60))
