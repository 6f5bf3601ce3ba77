#!/usr/bin/env bash
# Makes the SLAM table of docs/slam.md: `noctua slam` on tum_fr1_rpy_200 at normal light, 30 %
# and 15 % (`noctua simulate --level`), and with the real walking person at 0.5 m, for orb,
# clahe-orb, paper and paper with the YOLOv8n detector. One folder per run under OUT, and
# OUT/slam_table.md with tracked and lost frames, keyframes, ATE, RPE and frames/s.
# Usage: scripts/slam_tables.sh [OUT (default slam-tables)] [extra `noctua slam` options...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-slam-tables}
shift || true
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
fr1=$shared/data/tum_fr1_rpy_200
cutout=$shared/data/tum_fr3_walking_rpy_rgb16/rgb/1341846648.438342.png
seg=$shared/models/yolov8n-seg/yolov8n-seg_head_f32.onnx
detector=$shared/models/yolov8n/yolov8n_head_f32.onnx
config=$root/config/tum_fr1.yaml
for file in "$noctua" "$fr1/associations.txt" "$cutout" "$seg" "$detector"; do
  [ -e "$file" ] || { echo "slam_tables: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
command -v jq >/dev/null || { echo "slam_tables: needs jq (apt-get install jq)" >&2; exit 1; }
mkdir -p "$out"
table="$out/slam_table.md"
{
  echo "| method | light | tracked / frames | lost (frames) | keyframes | ATE RMSE m | ATE median m | RPE m/s | RPE °/s | frames/s |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} >"$table"
for light in normal 30 15 person; do
  case $light in
    normal) sequence=$fr1 ;;
    person)
      sequence=$out/sequences/person
      [ -e "$sequence/associations.txt" ] || "$noctua" simulate --dataset "$fr1" --camera "$config" \
        --person-cutout "$cutout" --seg-model "$seg" --person-distance 0.5 --out "$sequence" --force >&2 ;;
    *)
      sequence=$out/sequences/level$light
      [ -e "$sequence/associations.txt" ] || "$noctua" simulate --dataset "$fr1" --camera "$config" \
        --level "$light" --out "$sequence" --force >&2 ;;
  esac
  for method in orb clahe-orb paper paper+yolov8n; do
    run=$out/$light/$method
    args=(--dataset "$sequence" --config "$config" --out "$run" --force --progress-every 50
          --deterministic)
    if [ "$method" = paper+yolov8n ]; then
      args+=(--method paper --detector "$detector")
    else
      args+=(--method "$method")
    fi
    echo "slam_tables: $light, $method" >&2
    "$noctua" slam "${args[@]}" "$@" >/dev/null
    label=$light
    [ "$light" = normal ] || [ "$light" = person ] || label="$light %"
    [ "$light" = person ] && label="normal + person"
    jq -r --arg method "$method" --arg light "$label" '
      def ranges: reduce .[] as $i ([]; if length > 0 and .[-1][1] == $i - 1
        then .[-1][1] = $i else . + [[$i, $i]] end)
        | map(if .[0] == .[1] then "\(.[0])" else "\(.[0])–\(.[1])" end) | join(", ");
      "| \($method) | \($light) | \(.tracked_frames) / \(.frames) | \(.lost_frames)" +
      (if .lost_frames > 0 then " (\(.lost_frame_indices | ranges))" else "" end) +
      " | \(.keyframes) | \(.ate.translation_m.rmse * 10000 | round / 10000)" +
      " | \(.ate.translation_m.median * 10000 | round / 10000)" +
      " | \(.rpe.translation_m.rmse // "n/a" | if type == "number" then (. * 1000 | round / 1000) else . end)" +
      " | \(.rpe.rotation_deg.rmse // "n/a" | if type == "number" then (. * 100 | round / 100) else . end)" +
      " | \(.frames_per_second * 10 | round / 10) |"' "$run/report.json" >>"$table"
  done
done
echo "slam_tables: wrote $table" >&2
