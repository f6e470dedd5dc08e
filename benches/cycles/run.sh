#!/usr/bin/env bash
# Blender Cycles anchor for rondo's denoiser: installs Blender as a Python module
# (PyPI `bpy`, pinned) and numpy into a virtual environment (never in the tests), and runs
# benches/cycles/cornell.py: the Cornell box of benches/mitsuba/ rendered by Cycles, raw and
# with OpenImageDenoise, timed, against the Mitsuba reference.
#
#   benches/cycles/run.sh [--spp-list 4,16,64] [--rondo target/release/rondo] [--process-wall] ...
#
# The reference (bench/mitsuba/reference.exr by default, --reference to change) comes from
# benches/mitsuba/run.sh, which makes it if missing. The environment: benches/cycles/venv.sh
# (CYCLES_VENV, CYCLES_PYTHON, BPY_VERSION).
set -euo pipefail
cd "$(dirname "$0")/../.."
. benches/cycles/venv.sh
"$CYCLES/bin/pip" install --quiet "OpenEXR>=3.3"
exec "$CYCLES/bin/python" benches/cycles/cornell.py "$@"
