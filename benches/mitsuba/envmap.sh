#!/usr/bin/env bash
# Mitsuba 3 side by side for scenes/envmap.ron (the environment map): sets up the virtual
# environment as benches/mitsuba/run.sh does, builds rondo, writes scenes/textures/sky.hdr if
# missing, and runs benches/mitsuba/envmap.py, which makes its converged reference
# (bench/mitsuba/envmap_reference.exr, 4096 spp ldsampler) on first use.
#
#   benches/mitsuba/envmap.sh [--spp-list 4,16,64] [--mean-spp 1024] [--mitsuba-only] ...
#
# Environment: MITSUBA_VENV (default ~/.cache/rondo-mitsuba-venv), DRJIT_LIBLLVM_PATH (default:
# the newest libLLVM found; Dr.Jit 1.5 needs LLVM >= 19, see run.sh).
set -euo pipefail
cd "$(dirname "$0")/../.."
source benches/mitsuba/venv.sh
if [ ! -f scenes/textures/sky.hdr ]; then
  python3 scripts/make-sky.py
fi
case " $* " in
  *" --mitsuba-only "*) exec "$VENV/bin/python" benches/mitsuba/envmap.py "$@" ;;
esac
cargo build --release --quiet
# A private copy: target/ is shared, and another build (other features, another checkout's
# work in progress) may replace target/release/rondo while the comparison runs.
bin_dir="$(mktemp -d)"
trap 'rm -rf "$bin_dir"' EXIT
cp target/release/rondo "$bin_dir/rondo"
RONDO_BIN="$bin_dir/rondo" "$VENV/bin/python" benches/mitsuba/envmap.py "$@"
