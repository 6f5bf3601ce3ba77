#!/usr/bin/env bash
# Writes a long TUM-layout sequence made from a real one played forward and back (ping-pong):
# an associations.txt whose lines point at the real images (absolute paths; nothing is copied),
# with new timestamps at 30 Hz so that they strictly increase, and, when the source has a
# groundtruth.txt, a groundtruth.txt giving each new timestamp the source's pose nearest in time
# to the frame played (none where the nearest is more than 20 ms away), so that
# `noctua slam --dataset OUT` reports the trajectory error.
# Played backward, a frame of a rolling-shutter camera still has the shear of the motion it was
# recorded in, which now runs against the played motion: no camera makes that, and the SLAM's
# correction (Camera.rolling_shutter_s) then doubles the shear instead of undoing it. Run such a
# sequence with `Camera.rolling_shutter_s: 0` (docs/slam.md, "Rolling shutter").
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
truth="$source_dir/groundtruth.txt"
[ -f "$truth" ] || truth=/dev/null
awk -v dir="$source_dir" -v frames="$frames" -v truth_out="$out/groundtruth.txt.partial" '
  BEGIN { n = 0; m = 0 }
  FNR == NR { if (!/^#/ && NF == 8) { gt_t[m] = $1; gt[m] = $2 " " $3 " " $4 " " $5 " " $6 " " $7 " " $8; m++ }
              next }
  !/^#/ && NF == 4 { t_rgb[n] = $1; rgb[n] = $2; depth[n] = $4; n++ }
  END {
    if (n < 2) { print "long_sequence: fewer than 2 frames in the source" > "/dev/stderr"; exit 1 }
    # The ground truth nearest to each source frame (both lists are in time order).
    j = 0
    for (i = 0; i < n; i++) {
      while (j + 1 < m && (gt_t[j + 1] - t_rgb[i]) ^ 2 <= (gt_t[j] - t_rgb[i]) ^ 2) j++
      pose[i] = (m > 0 && (gt_t[j] - t_rgb[i]) ^ 2 <= 0.02 ^ 2) ? gt[j] : ""
    }
    period = 2 * (n - 1)
    print "# t_rgb rgb t_depth depth: " frames " frames, " dir " played forward and back"
    if (m > 0) print "# timestamp tx ty tz qx qy qz qw: the source frame'"'"'s pose" > truth_out
    for (k = 0; k < frames; k++) {
      j = k % period
      i = j < n ? j : period - j
      t = 1000 + k / 30.0
      printf "%.6f %s/%s %.6f %s/%s\n", t, dir, rgb[i], t + 0.0005, dir, depth[i]
      if (pose[i] != "") printf "%.6f %s\n", t, pose[i] > truth_out
    }
  }' "$truth" "$list" >"$out/associations.txt.partial"
if [ -f "$out/groundtruth.txt.partial" ]; then
  mv "$out/groundtruth.txt.partial" "$out/groundtruth.txt"
fi
mv "$out/associations.txt.partial" "$out/associations.txt"
echo "long_sequence: wrote $out/associations.txt ($frames frames)" \
  "$([ -f "$out/groundtruth.txt" ] && echo "and groundtruth.txt")"
