# Sourced by the Mitsuba benches (run.sh, envmap.sh): makes the virtual environment with mitsuba
# and numpy (never in the tests) and points Dr.Jit at the newest libLLVM found, unless
# DRJIT_LIBLLVM_PATH is set (Dr.Jit 1.5 needs LLVM >= 19; see run.sh). Sets VENV.
VENV="${MITSUBA_VENV:-$HOME/.cache/rondo-mitsuba-venv}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
"$VENV/bin/pip" install --quiet mitsuba numpy
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  newest="$(ls /usr/lib/x86_64-linux-gnu/libLLVM.so.* /usr/lib/llvm-*/lib/libLLVM.so.* 2>/dev/null \
    | sort -V | tail -n 1 || true)"
  if [ -n "$newest" ]; then export DRJIT_LIBLLVM_PATH="$newest"; fi
fi
echo "DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-(unset: Dr.Jit searches itself)}"
