#!/usr/bin/env bash
# Writes a long TUM-layout sequence made from a real one played forward and back (ping-pong):
# only an associations.txt whose lines point at the real images (absolute paths; nothing is
# copied), with new timestamps at 30 Hz so that they strictly increase. No ground truth.
# Usage: scripts/long_sequence.sh <source TUM folder> <output folder> [frames (default 10000)]
set -euo pipefail
source_dir=$(cd "$1" && pwd)
out=$2
frames=${3:-10000}
list="$source_dir/associations.txt"
[ -f "$list" ] || { echo "long_sequence: $list: no such file" >&2; exit 1; }
if [ -e "$out/associations.txt" ]; then
  echo "long_sequence: $out/associations.txt exists; not overwriting it" >&2
  exit 1
fi
mkdir -p "$out"
awk -v dir="$source_dir" -v frames="$frames" 'BEGIN { n = 0 }
  !/^#/ && NF == 4 { rgb[n] = $2; depth[n] = $4; n++ }
  END {
    if (n < 2) { print "long_sequence: fewer than 2 frames in the source" > "/dev/stderr"; exit 1 }
    period = 2 * (n - 1)
    print "# t_rgb rgb t_depth depth: " frames " frames, " dir " played forward and back"
    for (k = 0; k < frames; k++) {
      j = k % period
      i = j < n ? j : period - j
      t = 1000 + k / 30.0
      printf "%.6f %s/%s %.6f %s/%s\n", t, dir, rgb[i], t + 0.0005, dir, depth[i]
    }
  }' "$list" >"$out/associations.txt.partial"
mv "$out/associations.txt.partial" "$out/associations.txt"
echo "long_sequence: wrote $out/associations.txt ($frames frames)"
