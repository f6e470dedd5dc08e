#!/usr/bin/env bash
# Blender Cycles anchor for rondo's denoiser (issue 21): installs Blender as a Python module
# (PyPI `bpy`, pinned) and numpy into a virtual environment (never in the tests), and runs
# benches/cycles/cornell.py: the Cornell box of benches/mitsuba/ rendered by Cycles, raw and
# with OpenImageDenoise, timed, against the Mitsuba reference.
#
#   benches/cycles/run.sh [--spp-list 4,16,64] [--rondo target/release/rondo] [--process-wall] ...
#
# The reference (bench/mitsuba/reference.exr by default, --reference to change) comes from
# benches/mitsuba/run.sh, which makes it if missing. bpy 5.2 needs Python 3.13 exactly.
# Environment: CYCLES_VENV (default ~/.cache/rondo-cycles-venv), CYCLES_PYTHON (a Python 3.13;
# default python3.13 on PATH, else pyenv's 3.13.0), BPY_VERSION (default 5.2.3).
set -euo pipefail
cd "$(dirname "$0")/../.."
VENV="${CYCLES_VENV:-$HOME/.cache/rondo-cycles-venv}"
if [ ! -x "$VENV/bin/python" ]; then
  PY="${CYCLES_PYTHON:-$(command -v python3.13 || echo "$HOME/.pyenv/versions/3.13.0/bin/python3")}"
  if ! "$PY" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 13))' 2>/dev/null; then
    echo "bpy ${BPY_VERSION:-5.2.3} needs Python 3.13: set CYCLES_PYTHON (tried $PY)" >&2
    exit 1
  fi
  "$PY" -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet "bpy==${BPY_VERSION:-5.2.3}" numpy "OpenEXR>=3.3"
exec "$VENV/bin/python" benches/cycles/cornell.py "$@"
