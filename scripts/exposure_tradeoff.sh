#!/usr/bin/env bash
# The trade a dark scene forces on a camera (docs/slam.md, "The longest exposure"): a longer
# exposure collects more light, so less noise, and smears every corner further along the motion.
# For each sensor model, the scene is lit so that the model's own longest exposure gives LEVEL %
# mean grey (as in scripts/lowlight_sweep.sh); the same scene is then taken with the longest
# exposure cut to each FRACTION of it (never below the model's normal-light exposure). A frame
# exposed for t instead of T collects t / T of the electrons, so its mean grey is about LEVEL x
# (t / T)^(1 / gamma) by the model's response curve (noise and clipping at black left out: the
# level asked of `simulate`, which measures what it makes). Each case is `noctua simulate
# --max-exposure-ms` of tum_fr1_rpy_200, seeds 1..N, run through `noctua slam --deterministic`.
# Writes OUT/runs_METHOD.csv, OUT/tradeoff_METHOD.md (ATE mean (min-max), its ratio to the
# method at normal light and frames without a pose, per model and exposure) and
# OUT/tradeoff_METHOD.png (mean ATE against exposure, one line per model, and 1.2 x normal light).
# Usage: scripts/exposure_tradeoff.sh [OUT (default exposure-tradeoff)]
# NOCTUA_SENSORS (default every camera model), NOCTUA_FRACTIONS (default "1 0.5 0.3"),
# NOCTUA_LEVEL (15), NOCTUA_SEEDS ("1 2 3"), NOCTUA_FRAMES (100), NOCTUA_METHOD (noctua),
# NOCTUA_JOBS (2). Runs of another method into the same OUT reuse its simulated sequences.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-exposure-tradeoff}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
dataset=$shared/data/tum_fr1_rpy_200
config=$root/config/tum_fr1.yaml
fractions=${NOCTUA_FRACTIONS:-1 0.5 0.3}
level=${NOCTUA_LEVEL:-15}
seeds=${NOCTUA_SEEDS:-1 2 3}
frames=${NOCTUA_FRAMES:-100}
method=${NOCTUA_METHOD:-noctua}
jobs=${NOCTUA_JOBS:-2}
for file in "$noctua" "$dataset/associations.txt" "$config"; do
  [ -e "$file" ] || { echo "exposure_tradeoff: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "exposure_tradeoff: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out/seq" "$out/slam"

# name gamma normal_ms max_ms of every camera model, from the one table of models.
models=$out/models.txt
"$noctua" simulate --list-sensors | awk -F'|' 'NR > 2 {
    gsub(/ /, "", $2); split($11, ms, "/"); gsub(/ /, "", ms[1]); gsub(/ /, "", ms[2])
    if ($2 != "noiseless") print $2, $5 + 0, ms[1], ms[2] }' >"$models"
sensors=${NOCTUA_SENSORS:-$(cut -d' ' -f1 "$models" | tr '\n' ' ')}

# One line per case: sensor exposure_ms level seed.
cases=$out/cases.txt
: >"$cases"
for sensor in $sensors; do
  read -r _ gamma normal_ms max_ms < <(awk -v s="$sensor" '$1 == s' "$models") ||
    { echo "exposure_tradeoff: unknown sensor model '$sensor'" >&2; exit 1; }
  for fraction in $fractions; do
    read -r exposure case_level < <(awk -v f="$fraction" -v n="$normal_ms" -v m="$max_ms" \
      -v g="$gamma" -v l="$level" 'BEGIN { t = f * m; if (t < n) t = n
        printf "%.1f %.2f\n", t, l * (t / m) ^ (1 / g) }')
    for seed in $seeds; do echo "$sensor $exposure $case_level $seed" >>"$cases"; done
  done
done

run_one() {
  local sensor=$1 exposure=$2 case_level=$3 seed=$4 name=${1}_${2}ms_s$4
  local seq=$out/seq/$name run=$out/slam/${name}_$method
  if [ ! -e "$seq/simulation.json" ]; then
    echo "exposure_tradeoff: simulate $sensor ${exposure} ms (${case_level} %) seed $seed" >&2
    "$noctua" simulate --dataset "$dataset" --camera "$config" --sensor "$sensor" \
      --level "$case_level" --max-exposure-ms "$exposure" --seed "$seed" --max-frames "$frames" \
      --out "$seq" --force >/dev/null 2>"$seq.log" ||
      { echo "exposure_tradeoff: $seq failed" >&2; return 1; }
  fi
  [ -e "$run/report.json" ] && return 0
  "$noctua" slam --dataset "$seq" --config "$config" --method "$method" --max-frames "$frames" \
    --out "$run" --force --progress-every 100000 --deterministic >/dev/null 2>"$run.log" ||
    { echo "exposure_tradeoff: $run failed" >&2; return 1; }
}
# The reference: the same method on the recorded frames (normal light), scaled by 1, 0.98 and
# 0.96 as in scripts/lowlight_sweep.sh, since a SLAM run on the same frames repeats itself.
normal_one() {
  local run=$out/slam/normal_${1}_$method
  [ -e "$run/report.json" ] && return 0
  "$noctua" slam --dataset "$dataset" --brightness "$1" --config "$config" --method "$method" \
    --max-frames "$frames" --out "$run" --force --progress-every 100000 --deterministic \
    >/dev/null 2>"$run.log" || { echo "exposure_tradeoff: $run failed" >&2; return 1; }
}
export -f run_one normal_one
export out dataset config noctua frames method
xargs -P "$jobs" -L 1 bash -c 'run_one "$@"' _ <"$cases"
printf '%s\n' 1 0.98 0.96 | xargs -P "$jobs" -L 1 bash -c 'normal_one "$@"' _
normal=$(for scale in 1 0.98 0.96; do jq '.ate.translation_m.rmse' "$out/slam/normal_${scale}_$method/report.json"; done |
  awk '{ s += $1 } END { printf "%.5f", s / NR }')

csv=$out/runs_$method.csv
# Frames without a pose include those before the map starts (the report's lost_frames does not).
echo "sensor,exposure_ms,level,seed,method,ate_rmse_m,frames_without_pose" >"$csv"
while read -r sensor exposure case_level seed; do
  jq -r --arg s "$sensor" --arg e "$exposure" --arg l "$case_level" --arg k "$seed" \
    --arg m "$method" '[$s, $e, $l, $k, $m, (.ate.translation_m.rmse // "nan"), .frames - .tracked_frames] |
      @csv' "$out/slam/${sensor}_${exposure}ms_s${seed}_$method/report.json" | tr -d '"' >>"$csv"
done <"$cases"

{
  echo "Normal light (the recorded frames scaled by 1, 0.98, 0.96): $method ATE RMSE $normal m."
  echo
  echo "| model | longest exposure ms | mean grey | $method ATE RMSE m, mean (min–max) | mean / normal light | frames without a pose (per run) |"
  echo "|---|---:|---:|---|---:|---|"
  # A run that never started its map has no ATE: the mean is over the runs that have one.
  awk -F, -v normal="$normal" 'NR > 1 {
      key = $1 "|" $2 "|" $3; if (!(key in n)) order[++k] = key
      n[key]++; lost[key] = lost[key] (lost[key] == "" ? "" : "/") $7
      if ($6 == "nan") next
      valid[key]++; sum[key] += $6
      if (!(key in lo) || $6 < lo[key]) lo[key] = $6
      if (!(key in hi) || $6 > hi[key]) hi[key] = $6
    }
    END {
      for (i = 1; i <= k; i++) {
        split(order[i], part, "|"); key = order[i]
        if (valid[key] == 0) { ate = "no run has a pose"; ratio = "–" }
        else {
          ate = sprintf("%.4f (%.4f–%.4f)", sum[key] / valid[key], lo[key], hi[key])
          if (valid[key] < n[key]) ate = ate sprintf(", %d of %d runs", valid[key], n[key])
          ratio = sprintf("%.2f", sum[key] / valid[key] / normal)
        }
        printf "| %s | %s | %s %% | %s | %s | %s |\n", part[1], part[2], part[3], ate, ratio,
               lost[key]
      }
    }' "$csv"
} >"$out/tradeoff_$method.md"

if command -v gnuplot >/dev/null; then
  for sensor in $sensors; do
    awk -F, -v s="$sensor" 'NR > 1 && $1 == s && $6 != "nan" { sum[$2] += $6; n[$2]++ }
      END { for (e in sum) printf "%s %.5f\n", e, sum[e] / n[e] }' "$csv" | sort -n \
      >"$out/tradeoff_${method}_$sensor.dat"
  done
  {
    echo "set terminal pngcairo size 640,420 noenhanced"
    echo "set output '$out/tradeoff_$method.png'"
    echo "set title 'tum_fr1_rpy_200, $level % at each model''s longest exposure: $method'"
    echo "set xlabel 'longest exposure (ms)'; set ylabel 'ATE RMSE (m), mean over seeds'; set grid"
    plot="plot $normal * 1.2 with lines dashtype 2 title '1.2 x normal light',"
    for sensor in $sensors; do
      plot+=" '$out/tradeoff_${method}_$sensor.dat' using 1:2 with linespoints title '$sensor',"
    done
    echo "${plot%,}"
  } | gnuplot
fi
cat "$out/tradeoff_$method.md"
echo "exposure_tradeoff: wrote $out/tradeoff_$method.md, $csv and $out/tradeoff_$method.png" >&2
