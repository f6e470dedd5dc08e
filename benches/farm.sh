#!/usr/bin/env bash
# The cost of splitting a render into sample ranges (BENCHMARKS.md, "Splitting a render").
#
#   benches/farm.sh split SCENE SPP WxH ROUNDS     # CPU of K = 1, 2, 4, 16 tasks vs one process
#   benches/farm.sh merge SCENE PARTS [WxH]        # PARTS 1-spp partials (default 3840x2160),
#                                                  # then merges to .exr and .png
#
# Uses target/release/rondo (build it first). CPU times are user + sys of each process from
# /usr/bin/time; every task runs with --threads 1, so the sum is the work a farm pays. K values
# are interleaved within a round, so load on a shared machine hits them alike.
set -euo pipefail
cd "$(dirname "$0")/.."
RONDO="${RONDO:-$PWD/target/release/rondo}"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# cpu CMD...: runs CMD quietly and prints its user + sys seconds.
cpu() {
  /usr/bin/time -f "%U %S" -o "$TMP/time" "$@" >/dev/null 2>&1
  awk '{ printf "%.2f", $1 + $2 }' "$TMP/time"
}

# peak CMD...: runs CMD quietly and prints "CPU s, wall s, peak RSS MiB".
peak() {
  /usr/bin/time -f "%U %S %e %M" -o "$TMP/time" "$@" >/dev/null 2>&1
  awk '{ printf "%.1f s CPU, %.1f s wall, peak %.0f MiB", $1 + $2, $3, $4 / 1024 }' "$TMP/time"
}

split() {
  local scene="$1" spp="$2" size="$3" rounds="$4"
  local w="${size%x*}" h="${size#*x}"
  local common=(--width "$w" --height "$h" --threads 1)
  echo "| round | one process | K=1 | K=2 | K=4 | K=16 |"
  echo "|---|---:|---:|---:|---:|---:|"
  for round in $(seq 1 "$rounds"); do
    local row="| $round | $(cpu "$RONDO" render "$scene" -o "$TMP/one.exr" --spp "$spp" "${common[@]}") s"
    for k in 1 2 4 16; do
      local total=0
      for i in $(seq 0 $((k - 1))); do
        local a=$((i * spp / k)) b=$(((i + 1) * spp / k))
        local t
        t="$(cpu "$RONDO" render "$scene" --samples "$a..$b" -o "$TMP/part-$i.exr" "${common[@]}")"
        total="$(awk -v x="$total" -v y="$t" 'BEGIN { printf "%.2f", x + y }')"
      done
      local merge
      merge="$(cpu "$RONDO" merge "$TMP"/part-*.exr -o "$TMP/merged.exr" --spp "$spp")"
      row="$row | $total s (merge $merge s)"
      rm -f "$TMP"/part-*.exr
    done
    echo "$row |"
  done
}

merge() {
  local scene="$1" parts="$2" size="${3:-3840x2160}"
  local w="${size%x*}" h="${size#*x}"
  for i in $(seq 0 $((parts - 1))); do
    "$RONDO" render "$scene" --samples "$i..$((i + 1))" -o "$TMP/part-$i.exr" \
      --width "$w" --height "$h" >/dev/null 2>&1
  done
  echo "one partial: $(stat -c %s "$TMP/part-0.exr") bytes"
  echo "merge -> .exr: $(peak "$RONDO" merge "$TMP"/part-*.exr -o "$TMP/merged.exr" --spp "$parts")"
  echo "merged partial: $(stat -c %s "$TMP/merged.exr") bytes"
  echo "merge -> .png: $(peak "$RONDO" merge "$TMP"/part-*.exr -o "$TMP/merged.png" --spp "$parts")"
}

case "${1:-}" in
  split) shift; split "$@" ;;
  merge) shift; merge "$@" ;;
  *) echo "usage: $0 split SCENE SPP WxH ROUNDS | merge SCENE PARTS [WxH]" >&2; exit 2 ;;
esac
