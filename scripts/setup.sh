#!/usr/bin/env bash
# Creates .venv/ (if missing) with the Python packages, and builds the FMU.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
if ! .venv/bin/python -c "import fmpy, numpy, matplotlib, pytest, reqpy_M" 2>/dev/null; then
  .venv/bin/pip install --quiet --disable-pip-version-check -r requirements.txt
fi
bash scripts/build_fmu.sh >/dev/null
