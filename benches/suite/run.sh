#!/usr/bin/env bash
# The benchmark suite, one command (README.md beside this file): builds rondo, sets up the
# Mitsuba 3 and Blender Cycles virtual environments, then runs suite.py.
#
#   benches/suite/run.sh [--scenes cornell,envmap] [--quick] [--scale 0.5] [--spp-list 4,16,64]
#                        [--reference-spp 1024] [--denoise-times 1,10] [--threads N] [--no-cycles]
#                        [--repeat N] [--out bench/suite]
#
# Environment: MITSUBA_VENV, CYCLES_VENV, CYCLES_PYTHON, BPY_VERSION (see benches/mitsuba/venv.sh
# and benches/cycles/venv.sh, which set up both environments), RONDO_OIDN_DIR (src/denoise/).
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet
# Dr.Jit (Mitsuba's JIT) needs libLLVM >= 19. Debian 12 has it in its main archive
# (libllvm19 1:19.1.7-3~deb12u1): install it when no libLLVM 19+ is present.
if ! ls /usr/lib/x86_64-linux-gnu/libLLVM.so.{19,2}* /usr/lib/llvm-{19,2}*/lib/libLLVM.so.* \
    >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19
  else
    echo "Dr.Jit needs libLLVM >= 19: sudo apt-get install libllvm19" >&2
    exit 1
  fi
fi
. benches/mitsuba/venv.sh
"$VENV/bin/pip" install --quiet matplotlib pillow
. benches/cycles/venv.sh
# rondo's denoiser (the suite's denoised columns): Open Image Denoise in .oidn/lib, unless
# RONDO_OIDN_DIR names another folder.
if [ -z "${RONDO_OIDN_DIR:-}" ]; then
  scripts/fetch-oidn.sh
fi
lscpu | grep -E 'Model name' || true
if grep -qw avx512f /proc/cpuinfo; then echo "AVX-512: yes"; else echo "AVX-512: no"; fi
exec "$VENV/bin/python" benches/suite/suite.py --cycles-python "$CYCLES/bin/python" "$@"
