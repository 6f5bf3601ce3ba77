#!/usr/bin/env bash
# The low-light sweep of docs/evaluation.md and docs/slam.md: every method x every sensor model x
# light level x noise seed on tum_fr1_rpy_200 (config/tum_fr1.yaml). Each dark case is a sequence
# made by `noctua simulate --sensor MODEL --level L --seed K` (noise, fixed pattern, the model's
# longer exposure blurred along the ground-truth motion); each is run through `noctua slam` (ATE
# RMSE, frames without a pose) and `noctua eval` (correct matches per pair: frame i vs i+5, every
# 5th pair, tau 10 px; repeatability: the share of points found again within 3 px). 100 % is the recorded frames, the same for every model: its runs are the
# frames scaled by 1, 0.98 and 0.96 (`--brightness`, the noiseless model), since a SLAM run on the
# same frames repeats itself and one run scatters (docs/slam.md).
# Writes OUT/runs.csv (one line per SLAM run), OUT/sweep.md (mean, min-max over seeds), and
# OUT/sweep.png (mean ATE against light level, one panel per model).
# Usage: scripts/lowlight_sweep.sh [OUT (default lowlight-sweep)]
# QUICK=1: 60 frames, orb and paper, models kinect and webcam, levels 100 and 15, two seeds
# (a few minutes). NOCTUA_METHODS, NOCTUA_SENSORS, NOCTUA_LEVELS, NOCTUA_SEEDS, NOCTUA_FRAMES
# (0: all) override either mode; NOCTUA_JOBS runs that many commands at once (default 2).
# NOCTUA_SCENE=crowd sweeps bonn_crowd_120 instead (real people walking around a hand-held Xtion,
# config/bonn.yaml), its SLAM runs with YOLOv8n's dynamic regions: the held-out check of the
# same methods and models where people cover the view. NOCTUA_REJECT_MOVING=1 adds the model-free
# test of moving points to every SLAM run (`slam --reject-moving-points`; with the crowd's
# detector: "both", docs/slam.md).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-lowlight-sweep}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
jobs=${NOCTUA_JOBS:-2}
scene=${NOCTUA_SCENE:-fr1}
detector=""
reject_moving=${NOCTUA_REJECT_MOVING:-0}
# Runs are reused when OUT is run again: each mode keeps its own, so switching never mixes them.
slam_runs=$out/slam
[ "$reject_moving" != 1 ] || slam_runs=$out/slam-reject-moving
case $scene in
  fr1) dataset=$shared/data/tum_fr1_rpy_200 config=$root/config/tum_fr1.yaml ;;
  crowd)
    dataset=$shared/data/bonn_crowd_120 config=$root/config/bonn.yaml
    detector=$shared/models/yolov8n/yolov8n_head_f32.onnx
    ;;
  *) echo "lowlight_sweep: NOCTUA_SCENE must be fr1 or crowd, not '$scene'" >&2; exit 1 ;;
esac
if [ "${QUICK:-0}" = 1 ]; then
  d_methods="orb paper" d_sensors="kinect webcam" d_levels="100 15" d_seeds="1 2" d_frames=60
else
  d_methods="orb clahe-orb paper he-orb" d_sensors="" d_levels="100 30 15 8" d_seeds="1 2 3"
  d_frames=0
fi
methods=${NOCTUA_METHODS:-$d_methods}
levels=${NOCTUA_LEVELS:-$d_levels}
seeds=${NOCTUA_SEEDS:-$d_seeds}
frames=${NOCTUA_FRAMES:-$d_frames}
for file in "$noctua" "$dataset/rgb.txt" "$config" ${detector:+"$detector"}; do
  [ -e "$file" ] || { echo "lowlight_sweep: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "lowlight_sweep: needs jq (apt-get install jq)" >&2; exit 1; }
# Every camera model of the table (the noiseless reference is no camera).
all_sensors=$("$noctua" simulate --list-sensors | awk -F'|' 'NR > 2 { gsub(/ /, "", $2); if ($2 != "noiseless") print $2 }')
sensors=${NOCTUA_SENSORS:-${d_sensors:-$all_sensors}}
# shellcheck disable=SC2086 # split on purpose
set -- $seeds
[ $# -le 3 ] || { echo "lowlight_sweep: at most 3 seeds (100 % has three scalings)" >&2; exit 1; }
mkdir -p "$out/seq" "$slam_runs" "$out/eval"

# One line per case: sensor level seed (100 %: sensor "-", the seed picks the scaling).
cases=$out/cases.txt
: >"$cases"
for level in $levels; do
  for seed in $seeds; do
    if [ "$level" = 100 ]; then echo "- 100 $seed" >>"$cases"; continue; fi
    for sensor in $sensors; do echo "$sensor $level $seed" >>"$cases"; done
  done
done

simulate_one() {
  local sensor=$1 level=$2 seed=$3 dir=$out/seq/${1}_${2}_s$3
  [ "$level" = 100 ] || [ -e "$dir/simulation.json" ] && return 0
  echo "lowlight_sweep: simulate $sensor $level% seed $seed" >&2
  "$noctua" simulate --dataset "$dataset" --camera "$config" --sensor "$sensor" --level "$level" \
    --seed "$seed" --max-frames "$frames" --out "$dir" --force >/dev/null 2>"$dir.log" ||
    { echo "lowlight_sweep: $dir failed" >&2; return 1; }
}

slam_one() {
  local sensor=$1 level=$2 seed=$3 method=$4
  local dir=$slam_runs/${sensor}_${level}_s${seed}_$method args
  [ -e "$dir/report.json" ] && return 0
  if [ "$level" = 100 ]; then
    local scale=(1 0.98 0.96)
    args=(--dataset "$dataset" --brightness "${scale[$((seed - 1))]}")
  else
    args=(--dataset "$out/seq/${sensor}_${level}_s$seed")
  fi
  echo "lowlight_sweep: slam $method $sensor $level% seed $seed" >&2
  [ -z "$detector" ] || args+=(--detector "$detector")
  [ "$reject_moving" != 1 ] || args+=(--reject-moving-points)
  "$noctua" slam "${args[@]}" --config "$config" --method "$method" --max-frames "$frames" \
    --out "$dir" --force --progress-every 100000 --deterministic >/dev/null 2>"$dir.log" ||
    { echo "lowlight_sweep: $dir failed" >&2; return 1; }
}

eval_one() {
  local sensor=$1 level=$2 seed=$3 dir=$out/eval/${1}_${2}_s$3 data
  # Reused only when it holds every method asked for now: an OUT run again with more methods
  # evaluates its cases again instead of reporting the new methods as matching nothing.
  [ -e "$dir/summary.json" ] && jq -e --arg m "$methods" \
    '($m | split(" ") | map(select(. != ""))) - [.methods[].method] | length == 0' \
    "$dir/summary.json" >/dev/null && return 0
  # The recorded frames are the same for every seed: evaluate them once.
  [ "$level" = 100 ] && [ "$seed" != "$first_seed" ] && return 0
  data=$out/seq/${sensor}_${level}_s$seed
  [ "$level" = 100 ] && data=$dataset
  echo "lowlight_sweep: eval $sensor $level% seed $seed" >&2
  "$noctua" eval --dataset "$data" --camera "$config" --methods "${methods// /,}" --gap 5 \
    --pair-step 5 --max-frames "$frames" --out "$dir" --force >/dev/null 2>"$dir.log" ||
    { echo "lowlight_sweep: $dir failed" >&2; return 1; }
}
export -f simulate_one slam_one eval_one
export out slam_runs dataset config detector reject_moving noctua frames methods
export first_seed=$1
xargs -P "$jobs" -L 1 bash -c 'simulate_one "$@"' _ <"$cases"
while read -r sensor level seed; do
  for method in $methods; do echo "$sensor $level $seed $method"; done
done <"$cases" | xargs -P "$jobs" -L 1 bash -c 'slam_one "$@"' _
xargs -P "$jobs" -L 1 bash -c 'eval_one "$@"' _ <"$cases"

csv=$out/runs.csv
# Frames without a pose: the frames before the map starts count too (a method that never starts
# one has none with a pose), where the report's lost_frames counts only those after it.
echo "sensor,level,seed,method,ate_rmse_m,frames_without_pose,frames,correct_matches_per_pair,repeatability_3px" >"$csv"
while read -r sensor level seed; do
  summary=$out/eval/${sensor}_${level}_s$seed/summary.json
  [ "$level" = 100 ] && summary=$out/eval/-_100_s$first_seed/summary.json
  for method in $methods; do
    correct=$(jq -r --arg m "$method" '(.taus | index(10)) as $i |
      .methods[] | select(.method == $m) | .mean_correct[$i]' "$summary")
    repeated=$(jq -r --arg m "$method" '(.taus | index(3)) as $i |
      .methods[] | select(.method == $m) | .repeatability[$i]' "$summary")
    if [ -z "$correct" ] || [ -z "$repeated" ]; then
      echo "lowlight_sweep: $summary: no $method in it" >&2
      exit 1
    fi
    jq -r --arg s "$sensor" --arg l "$level" --arg k "$seed" --arg m "$method" --arg c "$correct" \
      --arg r "$repeated" \
      '[$s, $l, $k, $m, (.ate.translation_m.rmse // "nan"), .frames - .tracked_frames, .frames, $c,
        $r] | @csv' \
      "$slam_runs/${sensor}_${level}_s${seed}_$method/report.json" | tr -d '"' >>"$csv"
  done
done <"$cases"

# Mean, min and max over seeds per (model, level, method); 100 % is listed once, as model "-".
{
  moving=()
  [ -z "$detector" ] || moving+=("YOLOv8n's regions")
  [ "$reject_moving" != 1 ] || moving+=("the model-free test")
  [ ${#moving[@]} -gt 0 ] || moving=(none)
  joined=$(IFS='|' && echo "${moving[*]}")
  echo "$(basename "$dataset"), moving points: ${joined//|/ and }."
  echo
  echo "| model | light | method | ATE RMSE m, mean (min–max) | frames without a pose (per run) | correct matches per pair (τ 10 px) | repeatability (3 px) |"
  echo "|---|---:|---|---|---|---:|---:|"
  awk -F, 'NR > 1 {
      key = $1 "|" $2 "|" $4; if (!(key in n)) order[++k] = key
      n[key]++; sum[key] += $5; corr[key] += $8; rep[key] += $9
      if (!(key in lo) || $5 < lo[key]) lo[key] = $5
      if (!(key in hi) || $5 > hi[key]) hi[key] = $5
      lost[key] = lost[key] (lost[key] == "" ? "" : "/") $6
    }
    END {
      for (i = 1; i <= k; i++) {
        key = order[i]; split(key, part, "|")
        printf "| %s | %s %% | %s | %.4f (%.4f–%.4f) | %s | %.0f | %.3f |\n", part[1], part[2],
               part[3], sum[key] / n[key], lo[key], hi[key], lost[key], corr[key] / n[key],
               rep[key] / n[key]
      }
    }' "$csv"
} >"$out/sweep.md"

# The plot: mean ATE against light level per method, one panel per model (100 % shared).
for sensor in $sensors; do
  awk -F, -v s="$sensor" 'NR > 1 && ($1 == s || $1 == "-") { key = $4 " " $2; sum[key] += $5; n[key]++ }
    END { for (key in sum) { split(key, p, " "); printf "%s %s %.5f\n", p[1], p[2], sum[key] / n[key] } }' \
    "$csv" | sort -k1,1 -k2,2n >"$out/sweep_$sensor.dat"
done
if command -v gnuplot >/dev/null; then
  # shellcheck disable=SC2086 # split on purpose
  set -- $sensors
  {
    echo "set terminal pngcairo size $((420 * $#)),400 noenhanced"
    echo "set output '$out/sweep.png'"
    echo "set multiplot layout 1,$# title '$(basename "$dataset")${detector:+ (YOLOv8n)}: SLAM ATE RMSE (mean over seeds) against light'"
    echo "set logscale x; set xrange [6:120]; set xtics (8, 15, 30, 100); set grid"
    echo "set xlabel 'mean grey, % of recorded'; set ylabel 'ATE RMSE (m)'; set key top right"
    for sensor in $sensors; do
      echo "set title '$sensor'"
      plot="plot"
      for method in $methods; do
        plot+=" '$out/sweep_$sensor.dat' using 2:(strcol(1) eq '$method' ? \$3 : 1/0) with linespoints title '$method',"
      done
      echo "${plot%,}"
    done
    echo "unset multiplot"
  } | gnuplot
fi
cat "$out/sweep.md"
echo "lowlight_sweep: wrote $out/sweep.md, $out/runs.csv and $out/sweep.png" >&2
