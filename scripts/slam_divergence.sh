#!/usr/bin/env bash
# Where do runs part? Runs the SLAM on one sequence with the frames scaled by several brightness
# factors (a change of a few grey levels) and, per method, compares every run with the first:
# the first frame whose tracking decision differs (keyframe made or not, how the frame was
# tracked: motion model, reference keyframe, relocalisation, coasting, lost) and the first frames
# where the two trajectories are more than 1 cm and 5 cm apart (both start at the identity, so no
# alignment is needed). A SLAM whose runs part at a decision is fixed at that decision, not by
# luckier thresholds.
# Writes OUT/divergence.md (ATE per run, worst/best ratio, and where each run parts from the
# first) and OUT/runs/<method>_b<factor>/ (each run's noctua slam output).
# Usage: scripts/slam_divergence.sh [OUT (default slam-divergence)]
# Environment: NOCTUA_DATASET (default ../shared/data/tum_fr1_rpy_200), NOCTUA_CONFIG
# (config/tum_fr1.yaml), NOCTUA_METHODS ("orb clahe-orb paper"), NOCTUA_BRIGHTNESS
# ("1 0.99 0.98 0.97 0.96", the first is the reference), NOCTUA_JOBS (2).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-slam-divergence}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
dataset=${NOCTUA_DATASET:-$shared/data/tum_fr1_rpy_200}
config=${NOCTUA_CONFIG:-$root/config/tum_fr1.yaml}
methods=${NOCTUA_METHODS:-orb clahe-orb paper}
brightness=${NOCTUA_BRIGHTNESS:-1 0.99 0.98 0.97 0.96}
jobs=${NOCTUA_JOBS:-2}
for file in "$noctua" "$dataset" "$config"; do
  [ -e "$file" ] || { echo "slam_divergence: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "slam_divergence: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out/runs"

runs=$out/runs.txt
: >"$runs"
for method in $methods; do
  for b in $brightness; do echo "$method $b" >>"$runs"; done
done
run_one() {
  local dir=$out/runs/$1_b$2
  [ -e "$dir/report.json" ] && return 0
  echo "slam_divergence: $1, brightness $2" >&2
  "$noctua" slam --dataset "$dataset" --config "$config" --method "$1" --brightness "$2" \
    --out "$dir" --force --progress-every 100000 --deterministic >/dev/null 2>"$dir.log" ||
    { echo "slam_divergence: $dir failed (see $dir.log)" >&2; return 1; }
}
export -f run_one
export out dataset config noctua
xargs -P "$jobs" -L 1 bash -c 'run_one "$@"' _ <"$runs"

# First frame whose decision differs: columns state (3), method (4) and keyframe (11) of frames.csv.
first_decision() {
  awk -F, 'NR == FNR { if (FNR > 1) ref[$1] = $3 "/" $4 "/kf" $11; next }
           FNR > 1 && ($1 in ref) && ref[$1] != $3 "/" $4 "/kf" $11 {
             print $1 ": " ref[$1] " -> " $3 "/" $4 "/kf" $11; found = 1; exit }
           END { if (!found) print "none" }' "$1" "$2"
}
# First frame (index in the reference run's trajectory) where the positions differ by more than
# $3 metres; poses are matched by timestamp.
first_apart() {
  awk -v limit="$3" '
    /^#/ { next }
    NR == FNR { ref[$1] = $2 " " $3 " " $4; order[++n] = $1; next }
    { run[$1] = $2 " " $3 " " $4 }
    END {
      for (i = 1; i <= n; i++) {
        t = order[i]; if (!(t in run)) continue
        split(ref[t], a, " "); split(run[t], b, " ")
        d = sqrt((a[1] - b[1]) ^ 2 + (a[2] - b[2]) ^ 2 + (a[3] - b[3]) ^ 2)
        if (d > limit) { print i - 1; exit }
      }
      print "never"
    }' "$1" "$2"
}

report=$out/divergence.md
{
  echo "# Where runs part: $(basename "$dataset"), brightness factors $brightness"
  echo
  echo "| method | ATE RMSE m per run | worst / best | runs vs the first: first differing decision (frame: before -> after) | first frame > 1 cm apart | > 5 cm apart |"
  echo "|---|---|---|---|---|---|"
  for method in $methods; do
    set -- $brightness
    reference=$out/runs/${method}_b$1
    ates=""; best=""; worst=""; decisions=""; apart1=""; apart5=""
    for b in $brightness; do
      dir=$out/runs/${method}_b$b
      ate=$(jq -r '.ate.translation_m.rmse // "nan"' "$dir/report.json")
      ates="$ates$(printf '%.4f' "$ate") "
      best=$(awk -v a="$ate" -v b="${best:-1e9}" 'BEGIN { print (a < b ? a : b) }')
      worst=$(awk -v a="$ate" -v b="${worst:-0}" 'BEGIN { print (a > b ? a : b) }')
      [ "$dir" = "$reference" ] && continue
      decisions="$decisions b$b $(first_decision "$reference/frames.csv" "$dir/frames.csv");"
      apart1="$apart1 b$b $(first_apart "$reference/trajectory.txt" "$dir/trajectory.txt" 0.01);"
      apart5="$apart5 b$b $(first_apart "$reference/trajectory.txt" "$dir/trajectory.txt" 0.05);"
    done
    ratio=$(awk -v w="$worst" -v b="$best" 'BEGIN { printf "%.2f", w / b }')
    echo "| $method | $ates| $ratio | $decisions | $apart1 | $apart5 |"
  done
} >"$report"
cat "$report"
echo "slam_divergence: wrote $report" >&2
