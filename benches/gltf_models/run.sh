#!/usr/bin/env bash
# rondo against Blender Cycles' default (multiple-scattering GGX) Principled BSDF on the Khronos
# glTF sample models, each alone under the sky of scenes/gltf.ron (a bench, never the tests):
#
#   benches/gltf_models/run.sh [--out bench/gltf_models] [--rondo target/release/rondo]
#                              [--label rondo] [--models DIR] [--only A,B] [--size 320 240]
#                              [--spp 256] [--cycles-spp N]
#
# --models DIR holds the real sample models as the Khronos repository lays them out
# (DIR/DamagedHelmet/glTF/DamagedHelmet.gltf ...); any model missing there is written as a
# stand-in (benches/gltf_models/standins.py). The environment: benches/cycles/venv.sh
# (CYCLES_VENV, CYCLES_PYTHON, BPY_VERSION). See README.md beside this file.
set -euo pipefail
cd "$(dirname "$0")/../.."
. benches/cycles/venv.sh
"$CYCLES/bin/pip" install --quiet "OpenEXR>=3.3"
exec "$CYCLES/bin/python" benches/gltf_models/compare.py "$@"
