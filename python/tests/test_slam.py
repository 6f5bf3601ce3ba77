import cv2
import numpy as np
import pytest

import noctua


def frames(sequence, count):
    """(timestamp, rgb path, depth path) of the first frames, paired as associate.py does."""
    def listing(name):
        rows = []
        for line in (sequence / f"{name}.txt").read_text().splitlines():
            if line and not line.startswith("#"):
                t, path = line.split()[:2]
                rows.append((float(t), sequence / path))
        return rows

    depths = listing("depth")
    pairs = []
    for t, rgb in listing("rgb")[:count]:
        dt, depth = min(depths, key=lambda d: abs(d[0] - t))
        if abs(dt - t) < 0.02:
            pairs.append((t, rgb, depth))
    return pairs


def test_frame_by_frame_slam_follows_the_ground_truth(tum_sequence, tum_config):
    slam = noctua.Slam(tum_config, method="paper")
    poses = []
    for t, rgb, depth in frames(tum_sequence, 30):
        pose = slam.track(cv2.imread(str(rgb)), cv2.imread(str(depth), cv2.IMREAD_UNCHANGED), t)
        if pose is not None:
            assert pose.shape == (4, 4)
            poses.append(pose)
    assert len(poses) >= 25
    assert slam.last_result["state"] in ("ok", "coasting")
    assert slam.keyframes >= 1
    trajectory = slam.trajectory()
    assert len(trajectory) == len(poses)
    result = noctua.ate(trajectory, tum_sequence / "groundtruth.txt")
    assert result["rmse"] < 0.1, result["rmse"]


def test_whole_sequence_run_writes_the_report(tum_sequence, tum_config, tmp_path):
    out = tmp_path / "slam"
    result = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=30, out=out)
    report = result["report"]
    assert report["frames"] == 30
    assert len(result["trajectory"]) == report["tracked_frames"] >= 25
    assert report["ate"]["translation_m"]["rmse"] < 0.1
    assert (out / "trajectory.txt").exists() and (out / "report.json").exists()
    assert result["frames_csv"].startswith("frame,timestamp,state")


def test_run_writes_the_viewer_video_and_the_map(tum_sequence, tum_config, tmp_path):
    video, ply = tmp_path / "run.avi", tmp_path / "map.ply"
    result = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=12, video=video,
                             map_ply=ply)
    assert result["video_frames"] == 12
    capture = cv2.VideoCapture(str(video))
    count = 0
    while capture.read()[0]:
        count += 1
    assert count == 12
    header = ply.read_text().split("end_header")[0]
    report = result["report"]
    assert f"element vertex {report['map_points'] + report['keyframes']}" in header
    with pytest.raises(noctua.Error, match="unknown extension"):
        noctua.run_slam(tum_sequence, tum_config, method="orb", video=tmp_path / "run.mkv")


def test_run_options_reach_the_slam(tum_sequence, tum_config, tmp_path):
    default = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=8)["report"]
    assert default["map"]["vocabulary"] != "none"
    assert not default["reject_moving_points"] and default["sensor"] == "noiseless"
    assert not default["deterministic"]  # the bundle adjustment on its own thread
    dark = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=8,
                           vocabulary="none", reject_moving_points=True, brightness=0.3,
                           sensor="webcam", seed=2)
    report = dark["report"]
    assert report["map"]["vocabulary"] == "none"
    assert report["reject_moving_points"]
    assert (report["sensor"], report["seed"], report["brightness"]) == ("webcam", 2, 0.3)
    # Deterministic: the bundle adjustment in line, the same trajectory run after run.
    runs = [noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=40,
                            deterministic=True) for _ in range(2)]
    assert runs[0]["report"]["deterministic"]
    assert runs[0]["trajectory"].shape[0] == 40
    assert (runs[0]["trajectory"] == runs[1]["trajectory"]).all()
    with pytest.raises(noctua.Error, match="missing.vocab"):
        noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=8,
                        vocabulary=tmp_path / "missing.vocab")
    with pytest.raises(noctua.Error, match="no-such-camera"):
        noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=8,
                        sensor="no-such-camera")


def test_saved_map_is_reused_for_localisation(tum_sequence, tum_config, tmp_path):
    saved = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=20,
                            save_map=tmp_path / "fr1.map")
    assert saved["report"]["map"]["saved"]
    localised = noctua.run_slam(tum_sequence, tum_config, method="orb", max_frames=20,
                                load_map=tmp_path / "fr1.map", localize=True)
    assert localised["report"]["map"]["localised_frames"] == 20
    assert localised["report"]["keyframes"] == saved["report"]["keyframes"]
    with pytest.raises(noctua.Error, match="fr1.map"):
        noctua.run_slam(tum_sequence, tum_config, method="paper", max_frames=20,
                        load_map=tmp_path / "fr1.map", localize=True)


def test_bad_slam_input_is_explained(tum_config, tmp_path):
    with pytest.raises(noctua.Error, match="no_such_settings.yaml"):
        noctua.Slam(tmp_path / "no_such_settings.yaml")
    slam = noctua.Slam(tum_config, method="orb")
    with pytest.raises(noctua.Error, match="depth"):
        slam.track(np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640), np.uint8), 0.0)
