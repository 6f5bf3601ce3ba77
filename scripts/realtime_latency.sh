#!/usr/bin/env bash
# Checks the SLAM's latency in real time (docs/slam.md, "Latency in real time"): a sequence
# replayed at its recording's rate (`noctua slam --replay-rate 1.0`), frames that arrive while the
# SLAM is busy dropped as a camera's would be, for every method with and without the detector,
# from PNGs (the replay decodes each frame on the same cores) and preloaded (decoded before the
# clock starts, as a camera hands over frames). What a user waits for is a frame's latency, from
# its arrival to its pose; the target is a worst frame of at most TARGET_MS (60) ms.
# One real-time run depends on what else the machine does at that moment (its worst frame moves
# by 2x between two runs of the same build), so every combination runs ROUNDS times, the rounds
# interleaved, one run at a time: nothing else should run meanwhile.
# Writes OUT/runs.csv (one line per run, with the frame that was the worst), OUT/latency.md (per
# method, detector and frames: the median over the runs of their median, 95th percentile and
# worst frame, the worst frames' range, how many runs kept the worst frame within the target,
# frames dropped and lost, ATE mean (min–max)) and OUT/latency.png (every run's worst frame).
# Runs already in OUT are kept. About 10 s per run: 16 runs per round with the defaults.
# Usage: scripts/realtime_latency.sh [OUT (default realtime-latency)]
# Settings (environment): NOCTUA_DATASET (a TUM folder, default tum_fr1_rpy_200 of the shared
# data), NOCTUA_CONFIG (default config/tum_fr1.yaml), ROUNDS (3), METHODS ("orb clahe-orb paper
# noctua"), DETECTORS ("none yolov8n"), FRAMES ("png preloaded"), TARGET_MS (60), NOCTUA_BIN.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-realtime-latency}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
dataset=${NOCTUA_DATASET:-$shared/data/tum_fr1_rpy_200}
config=${NOCTUA_CONFIG:-$root/config/tum_fr1.yaml}
detector=$shared/models/yolov8n/yolov8n_head_f32.onnx
rounds=${ROUNDS:-3}
methods=${METHODS:-orb clahe-orb paper noctua}
detectors=${DETECTORS:-none yolov8n}
frames_modes=${FRAMES:-png preloaded}
target_ms=${TARGET_MS:-60}
for file in "$noctua" "$dataset" "$config"; do
  [ -e "$file" ] || { echo "realtime_latency: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
for mode in $detectors; do
  case $mode in
    none) ;;
    yolov8n) [ -e "$detector" ] || { echo "realtime_latency: $detector: not found" >&2; exit 1; } ;;
    *) echo "realtime_latency: unknown detector '$mode' (none, yolov8n)" >&2; exit 1 ;;
  esac
done
for mode in $frames_modes; do
  case $mode in png | preloaded) ;; *) echo "realtime_latency: unknown frames '$mode' (png, preloaded)" >&2; exit 1 ;; esac
done
[[ $rounds =~ ^[1-9][0-9]*$ ]] || { echo "realtime_latency: ROUNDS must be a positive integer" >&2; exit 1; }
command -v jq >/dev/null || { echo "realtime_latency: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out/runs"

runs=()
for round in $(seq 1 "$rounds"); do
  for frames in $frames_modes; do
    for method in $methods; do
      for mode in $detectors; do runs+=("$method $mode $frames $round"); done
    done
  done
done
done_runs=0
for run in "${runs[@]}"; do
  read -r method mode frames round <<<"$run"
  dir=$out/runs/${method}_${mode}_${frames}_$round
  done_runs=$((done_runs + 1))
  [ -e "$dir/report.json" ] && continue
  args=(slam --dataset "$dataset" --config "$config" --method "$method" --replay-rate 1.0
        --out "$dir" --force --progress-every 100000)
  [ "$mode" = yolov8n ] && args+=(--detector "$detector")
  [ "$frames" = preloaded ] && args+=(--replay-preload)
  echo "realtime_latency: run $done_runs of ${#runs[@]}: $method, detector $mode, $frames, round $round" >&2
  "$noctua" "${args[@]}" >/dev/null 2>"$dir.log" ||
    { echo "realtime_latency: $dir failed, see $dir.log" >&2; exit 1; }
done

csv=$out/runs.csv
echo "method,detector,frames,round,ate_rmse_m,latency_median_ms,latency_p95_ms,latency_max_ms,worst_frame,dropped_frames,lost_frames" >"$csv"
for run in "${runs[@]}"; do
  read -r method mode frames round <<<"$run"
  dir=$out/runs/${method}_${mode}_${frames}_$round
  # The frame whose latency was the largest (frames.csv names its columns in its header).
  worst=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "latency_ms") c = i; next }
                   c && $c != "" && (best == "" || $c + 0 > best) { best = $c + 0; frame = $1 }
                   END { print (frame == "" ? "none" : frame) }' "$dir/frames.csv")
  jq -r --arg m "$method" --arg d "$mode" --arg f "$frames" --arg r "$round" --arg w "$worst" \
    '[$m, $d, $f, $r, (.ate.translation_m.rmse // "nan"), .timing_ms.latency.median,
      .timing_ms.latency.p95, .timing_ms.latency.max, $w, .dropped_frames, .lost_frames] | @csv' \
    "$dir/report.json" | tr -d '"' >>"$csv"
done

{
  echo "| method | detector | frames | runs | latency ms: median / p95 (median of the runs) | worst frame ms: median (min–max) | runs with worst ≤ $target_ms ms | dropped / lost (all runs) | ATE m, mean (min–max) |"
  echo "|---|---|---|---|---|---|---|---|---|"
  awk -F, -v target="$target_ms" '
    function median(list,   values, n, i, j, t) {
      n = split(list, values, " ")
      for (i = 2; i <= n; i++) for (j = i; j > 1 && values[j - 1] + 0 > values[j] + 0; j--) {
        t = values[j]; values[j] = values[j - 1]; values[j - 1] = t
      }
      return n % 2 ? values[(n + 1) / 2] : (values[n / 2] + values[n / 2 + 1]) / 2
    }
    NR > 1 {
      key = $1 "|" $2 "|" $3; if (!(key in n)) order[++k] = key
      n[key]++; med[key] = med[key] " " $6; p95[key] = p95[key] " " $7; worst[key] = worst[key] " " $8
      if (!(key in lo) || $8 < lo[key]) lo[key] = $8
      if (!(key in hi) || $8 > hi[key]) hi[key] = $8
      if ($8 <= target) within[key]++
      dropped[key] += $10; lost[key] += $11; ate[key] += $5
      if (!(key in alo) || $5 < alo[key]) alo[key] = $5
      if (!(key in ahi) || $5 > ahi[key]) ahi[key] = $5
    }
    END {
      for (i = 1; i <= k; i++) {
        key = order[i]; split(key, part, "|")
        printf "| %s | %s | %s | %d | %.0f / %.0f | %.0f (%.0f–%.0f) | %d of %d | %d / %d | %.4f (%.4f–%.4f) |\n",
               part[1], part[2], part[3], n[key], median(med[key]), median(p95[key]),
               median(worst[key]), lo[key], hi[key], within[key], n[key], dropped[key], lost[key],
               ate[key] / n[key], alo[key], ahi[key]
      }
    }' "$csv"
} >"$out/latency.md"

# The plot: every run's worst frame, one column per method, detector and frames.
awk -F, 'NR > 1 { key = $1 " " $2 " " $3; if (!(key in x)) { x[key] = ++k; label[k] = key }
                 printf "%d %s \"%s\"\n", x[key], $8, key }' "$csv" >"$out/latency.dat"
if command -v gnuplot >/dev/null; then
  columns=$(awk 'END { print $1 }' "$out/latency.dat")
  gnuplot <<GNUPLOT
set terminal pngcairo size 1000,500 noenhanced
set output "$out/latency.png"
set title "Worst frame's latency per run, replayed at 30 Hz (target: $target_ms ms)"
set ylabel "worst frame latency (ms)"
set xrange [0.5:$columns + 0.5]
set yrange [0:*]
set grid ytics
set xtics rotate by -35
set key below
plot "$out/latency.dat" using 1:2:xtic(3) with points pt 7 ps 1.2 title "one run", \\
     $target_ms with lines lw 2 dt 2 title "target"
GNUPLOT
fi
cat "$out/latency.md"
echo "realtime_latency: wrote $out/latency.md, $csv and $out/latency.png" >&2
