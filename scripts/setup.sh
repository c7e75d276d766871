#!/usr/bin/env bash
# Creates .venv/ (if missing) with the Python packages, and builds the FMU.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
if ! .venv/bin/python -c "import fmpy, numpy, scipy, matplotlib, pytest, reqpy_M, dask, distributed, openseespy, fmu_manipulation_toolbox" 2>/dev/null; then
  .venv/bin/pip install --quiet --disable-pip-version-check -r requirements.txt
fi
# openseespy's binary needs the system BLAS/LAPACK (Debian: libblas3, liblapack3).
# Without them the OpenSees points of the accuracy chart are left out, with a notice.
if ! ldconfig -p | grep -q "libblas.so.3"; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo -n"
  { $SUDO apt-get install -y -qq libblas3 liblapack3 >/dev/null 2>&1 \
    || { $SUDO apt-get update -qq >/dev/null 2>&1 && $SUDO apt-get install -y -qq libblas3 liblapack3 >/dev/null 2>&1; }; } \
    || echo "setup: could not install libblas3/liblapack3; OpenSees comparisons will be skipped" >&2
fi
bash scripts/build_fmu.sh >/dev/null
