#!/usr/bin/env bash
# FLIP next to the lamp-out RMSE for EXR images against a reference (benches/flip/flip.py):
# installs flip-evaluator, OpenEXR and numpy into a virtual environment (never in the tests).
#
#   benches/flip/run.sh REFERENCE.exr IMAGE_OR_DIRECTORY... [--csv OUT.csv] [--mode ldr|hdr]
#
# Paths are taken as given (relative to the current directory).
# Environment: FLIP_VENV (default ~/.cache/rondo-flip-venv), PYTHON (default python3).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
VENV="${FLIP_VENV:-$HOME/.cache/rondo-flip-venv}"
if [ ! -x "$VENV/bin/python" ]; then
  "${PYTHON:-python3}" -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet "flip-evaluator==1.7" "OpenEXR>=3.3" numpy
exec "$VENV/bin/python" "$HERE/flip.py" "$@"
