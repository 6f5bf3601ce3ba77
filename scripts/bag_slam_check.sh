#!/usr/bin/env bash
# A bag written by another program (scripts/tum_to_bag.py, Debian's python3-rosbag) runs
# through `noctua slam --bag` (method paper): the first 60 frames of tum_fr1_rpy_200, every one tracked, ATE at
# most 0.03 m against the folder's ground truth. Exits 77 (skipped) without python3-rosbag.
#   scripts/bag_slam_check.sh NOCTUA_BINARY SHARED_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
noctua=$1
data=$2/data/tum_fr1_rpy_200
if ! /usr/bin/python3 -c 'import rosbag, sensor_msgs.msg' 2>/dev/null; then
  echo "bag_slam_check: skipped: needs python3-rosbag and python3-sensor-msgs"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 scripts/tum_to_bag.py "$data" "$work/fr1_60.bag" --frames 60
"$noctua" slam --bag "$work/fr1_60.bag" --groundtruth "$data/groundtruth.txt" \
  --config config/tum_fr1.yaml --method paper --out "$work/out" --progress-every 1000 >/dev/null
/usr/bin/python3 - "$work/out/report.json" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
frames, tracked = report["frames"], report["tracked_frames"]
ate = report["ate"]["translation_m"]["rmse"]
print(f"bag_slam_check: {frames} frames, {tracked} with a pose, {report['lost_frames']} lost, "
      f"{report['coasted_frames']} coasting, ATE RMSE {ate:.4f} m")
assert frames == 60, "expected 60 frames"
assert tracked == 60 and report["lost_frames"] == 0 and report["coasted_frames"] == 0, \
    "every frame must be tracked"
assert ate <= 0.03, "ATE above 0.03 m"
PY
