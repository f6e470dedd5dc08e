#!/usr/bin/env bash
# Fetches Intel Open Image Denoise 2.5.1 (CPU device only) into .oidn/lib/ in the repository,
# where rondo finds it at run time (src/denoise/). Nothing is installed system-wide.
#
# Debian has no OIDN package; the source is the PyPI wheel pyoidn 2.5.1.0, which ships Intel's
# prebuilt libraries. The wheel is pinned by version and SHA-256 and downloaded with pip (no
# install); only the four files the CPU device needs are extracted: libOpenImageDenoise.so.2,
# its core, the CPU device module and TBB (about 56 MB), not the GPU devices.
#
# Usage: scripts/fetch-oidn.sh [WHEEL]   (WHEEL: an already downloaded copy of the wheel)
# Needs: python3 with pip (python3-pip on Debian). Linux x86_64 only.
set -euo pipefail
# rondo refuses a library folder or file others can write: make none, whatever the caller's umask.
umask 022

VERSION=2.5.1
WHEEL_NAME=pyoidn-2.5.1.0-py3-none-manylinux2014_x86_64.whl
WHEEL_SHA256=32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e

repo="$(cd "$(dirname "$0")/.." && pwd)"
dest="$repo/.oidn"

if [ "$(uname -s)" != Linux ] || [ "$(uname -m)" != x86_64 ]; then
  echo "fetch-oidn: only Linux x86_64 is supported (this is $(uname -s) $(uname -m))" >&2
  exit 1
fi

if [ -f "$dest/VERSION" ] && [ "$(cat "$dest/VERSION")" = "$VERSION" ]; then
  echo "fetch-oidn: Open Image Denoise $VERSION already in $dest/lib"
  exit 0
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

if [ $# -ge 1 ]; then
  wheel="$1"
else
  echo "fetch-oidn: downloading $WHEEL_NAME (88 MB) with pip"
  python3 -m pip download --quiet --no-deps --only-binary=:all: \
    --platform manylinux2014_x86_64 \
    --dest "$work" "pyoidn==$VERSION.0"
  wheel="$work/$WHEEL_NAME"
fi

actual="$(sha256sum "$wheel" | cut -d' ' -f1)"
if [ "$actual" != "$WHEEL_SHA256" ]; then
  echo "fetch-oidn: checksum mismatch for $wheel" >&2
  echo "  expected $WHEEL_SHA256" >&2
  echo "  got      $actual" >&2
  exit 1
fi

# Extract into a staging directory beside the destination, then move it into place, so that an
# interrupted run never leaves a half-written .oidn/.
stage="$(mktemp -d "$repo/.oidn-stage.XXXXXX")"
trap 'rm -rf "$work" "$stage"' EXIT
chmod 755 "$stage"
mkdir -p "$stage/lib"
python3 - "$wheel" "$stage" <<'EOF'
import os, sys, zipfile

wheel, stage = sys.argv[1], sys.argv[2]
# wheel member -> name in .oidn/ (the loader's soname for the main library)
members = {
    "pyoidn/oidn/lib/libOpenImageDenoise.so.2.5.1": "lib/libOpenImageDenoise.so.2",
    "pyoidn/oidn/lib/libOpenImageDenoise_core.so.2.5.1": "lib/libOpenImageDenoise_core.so.2.5.1",
    "pyoidn/oidn/lib/libOpenImageDenoise_device_cpu.so.2.5.1": "lib/libOpenImageDenoise_device_cpu.so.2.5.1",
    "pyoidn/oidn/lib/libtbb.so.12.19": "lib/libtbb.so.12",
    "pyoidn-2.5.1.0.dist-info/licenses/LICENSE": "LICENSE-pyoidn",
}
with zipfile.ZipFile(wheel) as z:
    for member, name in members.items():
        target = os.path.join(stage, name)
        with z.open(member) as src, open(target, "wb") as dst:
            while chunk := src.read(1 << 20):
                dst.write(chunk)
        if name.startswith("lib/"):
            os.chmod(target, 0o755)
EOF
cat > "$stage/README" <<EOF
Intel Open Image Denoise $VERSION (Apache-2.0) and oneTBB (Apache-2.0), CPU device only,
extracted by scripts/fetch-oidn.sh from the PyPI wheel $WHEEL_NAME
(sha256 $WHEEL_SHA256). rondo loads lib/libOpenImageDenoise.so.2 at run time.
Delete this directory to remove them.
EOF
echo "$VERSION" > "$stage/VERSION"

rm -rf "$dest"
mv "$stage" "$dest"
echo "fetch-oidn: Open Image Denoise $VERSION installed in $dest/lib"
