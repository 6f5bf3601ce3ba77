#!/usr/bin/env bash
# Makes the real-crowd table of docs/dynamic.md: SLAM on bonn_crowd_120 (three people walking
# around a hand-held Xtion, config/bonn.yaml, errors against camera poses) for every SLAM method
# in four modes (none; model-free: slam --reject-moving-points; yolov8n: the detector's regions;
# both), each run three times (the frames scaled by 1, 0.98 and
# 0.96: one run scatters, docs/slam.md). Writes OUT/runs.csv (one line per run) and
# OUT/crowd.md (mean, min and max ATE RMSE, frames lost, frames/s per method and detector mode).
# Usage: scripts/crowd_table.sh [OUT (default crowd-table)]
# NOCTUA_JOBS runs that many SLAM runs at once (default 1: frames/s is measured too).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-crowd-table}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
jobs=${NOCTUA_JOBS:-1}
crowd=$shared/data/bonn_crowd_120
config=$root/config/bonn.yaml
detector=$shared/models/yolov8n/yolov8n_head_f32.onnx
methods=${NOCTUA_METHODS:-orb he-orb clahe-orb paper}
for file in "$noctua" "$crowd/rgb.txt" "$config" "$detector"; do
  [ -e "$file" ] || { echo "crowd_table: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "crowd_table: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out/runs"

runs=$out/runs.txt
: >"$runs"
for method in $methods; do
  for mode in none model-free yolov8n both; do
    for b in 1 0.98 0.96; do echo "$method $mode $b" >>"$runs"; done
  done
done

run_one() {
  local method=$1 mode=$2 b=$3
  local dir=$out/runs/${method}_${mode}_b$b
  [ -e "$dir/report.json" ] && return 0
  local args=(slam --dataset "$crowd" --config "$config" --method "$method" --brightness "$b"
              --out "$dir" --force --progress-every 1000 --deterministic)
  case $mode in yolov8n | both) args+=(--detector "$detector") ;; esac
  case $mode in model-free | both) args+=(--reject-moving-points) ;; esac
  echo "crowd_table: $method, detector $mode, brightness $b" >&2
  "$noctua" "${args[@]}" >/dev/null 2>"$dir.log" || { echo "crowd_table: $dir failed" >&2; return 1; }
}
export -f run_one
export out crowd config detector noctua
xargs -P "$jobs" -L 1 bash -c 'run_one "$@"' _ <"$runs"

csv=$out/runs.csv
echo "method,detector,brightness,ate_rmse_m,lost_frames,tracked_frames,frames_per_second" >"$csv"
while read -r method mode b; do
  report=$out/runs/${method}_${mode}_b$b/report.json
  jq -r --arg m "$method" --arg d "$mode" --arg b "$b" \
    '[$m, $d, $b, (.ate.translation_m.rmse // "nan"), .lost_frames, .tracked_frames,
      .frames_per_second] | @csv' "$report" | tr -d '"' >>"$csv"
done <"$runs"

{
  echo "| method | moving points | ATE RMSE m, mean (min–max) of 3 runs | frames lost (without a pose), per run | frames/s |"
  echo "|---|---|---|---|---|"
  awk -F, 'NR > 1 {
      key = $1 "|" $2; if (!(key in n)) order[++k] = key
      n[key]++; sum[key] += $4; fps[key] += $7
      if (!(key in lo) || $4 < lo[key]) lo[key] = $4
      if (!(key in hi) || $4 > hi[key]) hi[key] = $4
      lost[key] = lost[key] (lost[key] == "" ? "" : ", ") $5 " (" (120 - $6) ")"
    }
    END {
      for (i = 1; i <= k; i++) {
        key = order[i]; split(key, part, "|")
        printf "| %s | %s | %.4f (%.4f–%.4f) | %s | %.1f |\n", part[1], part[2],
               sum[key] / n[key], lo[key], hi[key], lost[key], fps[key] / n[key]
      }
    }' "$csv"
} >"$out/crowd.md"
# The plot: mean ATE per method and mode (log scale: they differ 20x).
awk -F, 'NR > 1 { key = $1; if (!(key in seen)) { seen[key] = 1; order[++k] = key }
                 sum[key, $2] += $4; n[key, $2]++ }
         END { for (i = 1; i <= k; i++) { m = order[i]
               printf "%s %.5f %.5f %.5f %.5f\n", m, sum[m, "none"] / n[m, "none"],
                      sum[m, "model-free"] / n[m, "model-free"], sum[m, "yolov8n"] / n[m, "yolov8n"],
                      sum[m, "both"] / n[m, "both"] } }' \
  "$csv" >"$out/crowd.dat"
if command -v gnuplot >/dev/null; then
  gnuplot <<GNUPLOT
set terminal pngcairo size 800,450 noenhanced
set output "$out/crowd.png"
set title "bonn_crowd_120: SLAM ATE RMSE, mean of 3 runs (log scale)"
set style data histograms
set style histogram clustered gap 1
set style fill solid 0.8 border -1
set logscale y
set yrange [0.005:1]
set ylabel "ATE RMSE (m)"
set grid ytics
plot "$out/crowd.dat" using 2:xtic(1) title "none", "" using 3 title "model-free", \\
     "" using 4 title "YOLOv8n, regions cut to depth", "" using 5 title "both"
GNUPLOT
fi
cat "$out/crowd.md"
echo "crowd_table: wrote $out/crowd.md, $out/runs.csv and $out/crowd.png" >&2
