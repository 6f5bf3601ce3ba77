#!/usr/bin/env bash
# Makes the low-light table of docs/slam.md from repeated runs. One run of this SLAM moves by
# ±30 % when a frame changes by a few grey levels (docs/slam.md, "Spread"), so a single run per
# light cannot tell a method's degradation from chance. Here every light is run five times:
# normal light with the frames scaled by 0.96, 0.97, 0.98, 0.99 and 1 (`noctua slam --brightness`),
# 30 % and 15 % with five noise seeds each (`noctua simulate --level L --seed 1..5`). Methods: orb,
# clahe-orb, paper (config/tum_fr1.yaml, edge fill on) and paper-strict (the same with
# `extractor: edge_fill: false`, the paper's filter as published).
# Writes OUT/runs.csv (one line per run) and OUT/spread.md (mean, min and max ATE RMSE per method
# and light, the ratio of the low-light mean to the normal-light mean, frames lost after the map
# was started and frames without a pose at all, over the five runs). Runs already in OUT are kept.
# About 10 min on 2 cores.
# Usage: scripts/slam_spread.sh [OUT (default slam-spread)]
# NOCTUA_JOBS runs that many SLAM runs at once (default 2).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-slam-spread}
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
jobs=${NOCTUA_JOBS:-2}
fr1=$shared/data/tum_fr1_rpy_200
config=$root/config/tum_fr1.yaml
for file in "$noctua" "$fr1/associations.txt" "$config"; do
  [ -e "$file" ] || { echo "slam_spread: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "slam_spread: needs jq (apt-get install jq)" >&2; exit 1; }
grep -q '^  edge_fill: true' "$config" ||
  { echo "slam_spread: $config: expected 'edge_fill: true' in its extractor section" >&2; exit 1; }
mkdir -p "$out/sequences" "$out/runs"
strict_config=$out/tum_fr1_strict.yaml
sed 's/^  edge_fill: true/  edge_fill: false/' "$config" >"$strict_config"

seeds="1 2 3 4 5"
brightness="0.96 0.97 0.98 0.99 1"
for level in 30 15; do
  for seed in $seeds; do
    sequence=$out/sequences/level${level}_seed$seed
    [ -e "$sequence/associations.txt" ] && continue
    echo "slam_spread: simulating ${level} % light, seed $seed" >&2
    "$noctua" simulate --dataset "$fr1" --camera "$config" --level "$level" --seed "$seed" \
      --out "$sequence" --force >/dev/null
  done
done

# One line per run: method light variant sequence config extra-option.
runs=$out/runs.txt
: >"$runs"
for method in orb clahe-orb paper paper-strict; do
  method_config=$config
  [ "$method" = paper-strict ] && method_config=$strict_config
  for b in $brightness; do
    echo "$method normal b$b $fr1 $method_config --brightness=$b" >>"$runs"
  done
  for level in 30 15; do
    for seed in $seeds; do
      echo "$method $level seed$seed $out/sequences/level${level}_seed$seed $method_config" \
        "--brightness=1" >>"$runs"
    done
  done
done
total=$(wc -l <"$runs")
echo "slam_spread: $total SLAM runs, $jobs at a time" >&2
export noctua out
# shellcheck disable=SC2016
xargs -P "$jobs" -L 1 bash -c '
  method=$0 light=$1 variant=$2 sequence=$3 config=$4 option=$5
  run=$out/runs/${method}_${light}_$variant
  [ -e "$run/report.json" ] && exit 0
  name=$method; [ "$method" = paper-strict ] && name=paper
  "$noctua" slam --dataset "$sequence" --config "$config" --method "$name" "$option" \
    --out "$run" --force --progress-every 1000 --deterministic >/dev/null 2>"$run.log" ||
    { echo "slam_spread: $run failed, see $run.log" >&2; exit 255; }
  echo "slam_spread: done $method, $light, $variant" >&2' <"$runs"

csv=$out/runs.csv
echo "method,light,variant,ate_rmse_m,lost_frames,tracked_frames,frames" >"$csv"
while read -r method light variant _; do
  jq -r --arg m "$method" --arg l "$light" --arg v "$variant" \
    '"\($m),\($l),\($v),\(.ate.translation_m.rmse),\(.lost_frames),\(.tracked_frames),\(.frames)"' \
    "$out/runs/${method}_${light}_$variant/report.json" >>"$csv"
done <"$runs"

awk -F, '
  NR == 1 { next }
  {
    key = $1 SUBSEP $2
    if (!(key in n)) { n[key] = 0; lo[key] = $4; hi[key] = $4 }
    n[key]++; sum[key] += $4; lost[key] += $5; untracked[key] += $7 - $6
    if ($4 < lo[key]) lo[key] = $4
    if ($4 > hi[key]) hi[key] = $4
  }
  END {
    print "| method | normal: mean (min–max) | 30 %: mean (min–max) | 30 % / normal | lost / untracked at 30 % | 15 %: mean (min–max) | 15 % / normal | lost / untracked at 15 % |"
    print "|---|---|---|---|---|---|---|---|"
    split("orb clahe-orb paper paper-strict", methods, " ")
    for (i = 1; i <= 4; i++) {
      m = methods[i]; base = sum[m SUBSEP "normal"] / n[m SUBSEP "normal"]
      line = sprintf("| %s | %.4f (%.4f–%.4f)", m, base, lo[m SUBSEP "normal"], hi[m SUBSEP "normal"])
      for (j = 0; j < 2; j++) {
        l = j == 0 ? "30" : "15"; k = m SUBSEP l; mean = sum[k] / n[k]
        line = line sprintf(" | %.4f (%.4f–%.4f) | %.2f× | %d / %d", mean, lo[k], hi[k], mean / base,
                            lost[k], untracked[k])
      }
      print line " |"
    }
  }' "$csv" >"$out/spread.md"
echo "slam_spread: wrote $out/spread.md and $csv" >&2
