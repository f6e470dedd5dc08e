# Sourced by the Cycles benches (benches/cycles/run.sh, benches/suite/run.sh): makes the virtual
# environment with Blender as a Python module (PyPI `bpy`, pinned) and numpy (never in the
# tests). bpy 5.2 needs Python 3.13 exactly. Sets CYCLES (the environment's directory).
# Environment: CYCLES_VENV (default ~/.cache/rondo-cycles-venv), CYCLES_PYTHON (a Python 3.13;
# default python3.13 on PATH, else pyenv's 3.13.0), BPY_VERSION (default 5.2.3).
CYCLES="${CYCLES_VENV:-$HOME/.cache/rondo-cycles-venv}"
if [ ! -x "$CYCLES/bin/python" ]; then
  # The first candidate that runs as Python 3.13 (a pyenv shim on PATH may not: pyenv runs it
  # only where 3.13 is the selected version).
  PY=""
  for candidate in ${CYCLES_PYTHON:-} "$(command -v python3.13 || true)" \
      "$HOME/.pyenv/versions/3.13.0/bin/python3"; do
    if [ -n "$candidate" ] &&
        "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 13))' 2>/dev/null; then
      PY="$candidate"
      break
    fi
  done
  if [ -z "$PY" ]; then
    echo "bpy ${BPY_VERSION:-5.2.3} needs Python 3.13: set CYCLES_PYTHON" >&2
    exit 1
  fi
  "$PY" -m venv "$CYCLES"
fi
"$CYCLES/bin/pip" install --quiet "bpy==${BPY_VERSION:-5.2.3}" numpy
