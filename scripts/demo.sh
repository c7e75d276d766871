#!/usr/bin/env bash
# The main job on the embedded default record: builds everything, runs the
# paper's Fig. 5a scene through the FMU with fmpy, writes out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/python scripts/simulate.py --out out/demo "$@"
