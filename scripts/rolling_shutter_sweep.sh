#!/usr/bin/env bash
# How long does this camera take to read its rows? A rolling-shutter camera sees each row at its
# own time, and SLAM corrects for it with the settings file's Camera.rolling_shutter_s
# (docs/slam.md, "Rolling shutter"). This measures it on a recording, without ground truth: for
# each candidate readout time it runs `noctua slam --deterministic` on the sequence at a few
# brightness scales (one run says little: docs/slam.md, "Spread") and reports how well the tracked
# poses fit their matches: the mean over tracked frames of frames.csv's residual_px (the median
# reprojection error, in pixels of each keypoint's level). The shear of a readout time the
# correction gets wrong is an error no pose can absorb, so the camera's own readout leaves the
# least; where the recording has ground truth the table gives the ATE too, to check that it
# agrees.
# Usage: scripts/rolling_shutter_sweep.sh DATASET CONFIG [OUT (default rolling_shutter)]
# READOUTS (seconds, default "0 0.01 0.015 0.02 0.025 0.03 0.035"), SCALES (default "1 0.98
# 0.96"), NOCTUA_METHOD (default orb), NOCTUA_JOBS (default 2), EXTRA_ARGS (more `noctua slam`
# flags, e.g. "--detector model.onnx") override. Writes OUT/sweep.csv (one line per run) and
# OUT/sweep.md (per readout: mean residual, mean inliers, mean ATE, runs), and prints the best.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 2 ] || { echo "usage: $0 DATASET CONFIG [OUT]" >&2; exit 2; }
dataset=$1
config=$2
out=${3:-rolling_shutter}
noctua=${NOCTUA_BIN:-$root/build/noctua}
jobs=${NOCTUA_JOBS:-2}
method=${NOCTUA_METHOD:-orb}
readouts=${READOUTS:-0 0.01 0.015 0.02 0.025 0.03 0.035}
scales=${SCALES:-1 0.98 0.96}
for file in "$noctua" "$dataset" "$config"; do
  [ -e "$file" ] || { echo "rolling_shutter_sweep: $file: not found" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "rolling_shutter_sweep: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out/configs" "$out/runs"

# One settings file per readout: the given one with Camera.rolling_shutter_s set (a relative
# Vocabulary.file made absolute, since it is relative to the settings file).
config_dir=$(cd "$(dirname "$config")" && pwd)
for r in $readouts; do
  grep -v '^Camera\.rolling_shutter_s:' "$config" |
    sed -E "/^Vocabulary\.file:[[:space:]]*\"?(none|default)?\"?[[:space:]]*\$/!s|^(Vocabulary\.file:[[:space:]]*\"?)([^/\"[:space:]][^\"]*)|\1$config_dir/\2|" \
      >"$out/configs/r$r.yaml"
  echo "Camera.rolling_shutter_s: $r" >>"$out/configs/r$r.yaml"
done

runs=$out/runs.txt
: >"$runs"
for r in $readouts; do for b in $scales; do echo "$r $b" >>"$runs"; done; done
echo "rolling_shutter_sweep: $(wc -l <"$runs") SLAM runs of $method, $jobs at a time" >&2
export noctua out dataset method EXTRA_ARGS
# shellcheck disable=SC2016
xargs -P "$jobs" -L 1 bash -c '
  r=$0 b=$1
  run=$out/runs/r${r}_b$b
  # shellcheck disable=SC2086
  "$noctua" slam --dataset "$dataset" --config "$out/configs/r$r.yaml" \
    --method "$method" --brightness "$b" ${EXTRA_ARGS:-} --out "$run" --force \
    --progress-every 1000 --deterministic >/dev/null 2>"$run.log" ||
    { echo "rolling_shutter_sweep: $run failed, see $run.log" >&2; exit 255; }
  echo "rolling_shutter_sweep: done readout $r s, brightness $b" >&2' <"$runs"

csv=$out/sweep.csv
echo "readout_s,brightness,mean_residual_px,mean_inliers,ate_rmse_m,lost_frames" >"$csv"
while read -r r b; do
  run=$out/runs/r${r}_b$b
  # Means over the tracked frames, the columns found by name.
  fit=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    $col["state"] == "ok" && $col["residual_px"] != "" {
      residual += $col["residual_px"]; inliers += $col["inliers"]; n++ }
    END { if (n) printf "%.4f,%.1f", residual / n, inliers / n; else printf "," }' "$run/frames.csv")
  jq -r --arg r "$r" --arg b "$b" --arg fit "$fit" \
    '"\($r),\($b),\($fit),\(.ate.translation_m.rmse // ""),\(.lost_frames)"' "$run/report.json" >>"$csv"
done <"$runs"

awk -F, '
  NR == 1 { next }
  {
    if (!($1 in n)) order[++count] = $1
    n[$1]++; residual[$1] += $3; inliers[$1] += $4; lost[$1] += $6
    if ($5 != "") { ate[$1] += $5; with_ate[$1]++ }
  }
  END {
    print "| readout s | mean residual px | mean inliers per tracked frame | mean ATE m | frames lost | runs |"
    print "|---:|---:|---:|---:|---:|---:|"
    best = order[1]
    for (i = 1; i <= count; i++) {
      r = order[i]
      printf "| %s | %.4f | %.1f | %s | %d | %d |\n", r, residual[r] / n[r], inliers[r] / n[r],
             with_ate[r] ? sprintf("%.4f", ate[r] / with_ate[r]) : "-", lost[r], n[r]
      if (residual[r] / n[r] < residual[best] / n[best]) best = r
    }
    printf "\nLeast residual: Camera.rolling_shutter_s: %s\n", best
  }' "$csv" >"$out/sweep.md"
cat "$out/sweep.md"
echo "rolling_shutter_sweep: wrote $out/sweep.md and $csv" >&2
