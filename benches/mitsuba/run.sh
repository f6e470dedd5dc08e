#!/usr/bin/env bash
# Mitsuba 3 anchor for the Cornell box: installs mitsuba into a virtual environment (never in
# the tests), builds rondo, makes the reference if missing, and runs benches/mitsuba/cornell.py.
#
#   benches/mitsuba/run.sh [--spp-list 4,16,64,256] [--variant llvm_ad_rgb] ...
#
# Environment: MITSUBA_VENV (default ~/.cache/rondo-mitsuba-venv), REFERENCE (default
# bench/mitsuba/reference.exr), REFERENCE_SPP (default 1024: a Mitsuba reference; see
# BENCHMARKS.md for why), REFERENCE_SAMPLER (default independent), DRJIT_LIBLLVM_PATH.
#
# The llvm_* variants JIT-compile through the system's libLLVM. Dr.Jit 1.5 (mitsuba 3.9) emits
# `llvm.minimum`, which LLVM 14 and 15 (Debian 12's default) cannot compile for x86 ("LLVM
# ERROR: Cannot select ... fminimum"); LLVM 19 can (`apt-get install libllvm19`). This script
# picks the newest libLLVM it finds unless DRJIT_LIBLLVM_PATH is set; without a usable one, pass
# --variant scalar_rgb (much slower, and the comparison then says so).
set -euo pipefail
cd "$(dirname "$0")/../.."
source benches/mitsuba/venv.sh
REFERENCE="${REFERENCE:-bench/mitsuba/reference.exr}"
cargo build --release --quiet
mkdir -p "$(dirname "$REFERENCE")"
if [ ! -f "$REFERENCE" ]; then
  "$VENV/bin/python" benches/mitsuba/cornell.py --reference "$REFERENCE" \
    --make-reference "${REFERENCE_SPP:-1024}" --reference-sampler "${REFERENCE_SAMPLER:-independent}"
fi
exec "$VENV/bin/python" benches/mitsuba/cornell.py --reference "$REFERENCE" --rondo target/release/rondo "$@"
