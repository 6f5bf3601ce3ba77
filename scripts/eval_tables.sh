#!/usr/bin/env bash
# Makes the evaluation tables of docs/evaluation.md: tum_fr1_rpy_200 at normal light, 30% and 15%,
# each without and with a real walking person (cut out of the fr3 walking frames by YOLOv8n-seg,
# 0.5 m from the camera), evaluated with every baseline and `paper` (with the YOLOv8n detector).
# Writes one folder per case under OUT and OUT/tables.md with all summary tables.
# Usage: scripts/eval_tables.sh [OUT (default eval-tables)] [extra `noctua eval` options...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-eval-tables}
shift || true
shared=${NOCTUA_SHARED_DIR:-$root/../shared}
noctua=${NOCTUA_BIN:-$root/build/noctua}
fr1=$shared/data/tum_fr1_rpy_200
cutout=$shared/data/tum_fr3_walking_rpy_rgb16/rgb/1341846648.438342.png
seg=$shared/models/yolov8n-seg/yolov8n-seg_head_f32.onnx
detector=$shared/models/yolov8n/yolov8n_head_f32.onnx
methods=${NOCTUA_EVAL_METHODS:-fast,orb,he-orb,clahe-orb,sift,surf,paper}
for file in "$noctua" "$fr1/associations.txt" "$cutout" "$seg" "$detector"; do
  [ -e "$file" ] || { echo "eval_tables: $file: not found (run scripts/setup.sh first)" >&2; exit 1; }
done
mkdir -p "$out"
tables="$out/tables.md"
echo "# noctua eval on tum_fr1_rpy_200 (methods $methods; paper with YOLOv8n)" >"$tables"
for level in 100 30 15; do
  for person in no yes; do
    name="level${level}_person-${person}"
    sequence="$out/$name/sequence"
    args=(--dataset "$fr1" --camera "$root/config/tum_fr1.yaml" --level "$level"
          --out "$sequence" --force)
    [ "$person" = yes ] && args+=(--person-cutout "$cutout" --seg-model "$seg" --person-distance 0.5)
    echo "eval_tables: $name: simulating" >&2
    "$noctua" simulate "${args[@]}" >&2
    echo "eval_tables: $name: evaluating $methods" >&2
    "$noctua" eval --dataset "$sequence" --methods "$methods" --detector "$detector" \
      --out "$out/$name/report" --force "$@" >&2
    {
      echo
      echo "## ${level}% light, $([ "$person" = yes ] && echo "with" || echo "without") the walking person"
      echo
      cat "$out/$name/report/summary.md"
    } >>"$tables"
  done
done
echo "eval_tables: wrote $tables" >&2
