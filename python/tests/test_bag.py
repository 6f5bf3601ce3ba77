"""ROS1 bags from Python: written from the real folder, read back frame for frame, extracted and
run through the SLAM as the folder is."""
import cv2
import numpy as np
import pytest

import noctua

FRAMES = 30


@pytest.fixture(scope="module")
def bag(tum_sequence, tmp_path_factory):
    path = tmp_path_factory.mktemp("bag") / "fr1.bag"
    noctua.write_bag(tum_sequence, path, max_frames=FRAMES)
    return path


def test_a_bag_gives_the_folders_frames(bag, tum_sequence):
    from_bag = list(noctua.open_frames(bag=bag))
    source = noctua.open_frames(dataset=tum_sequence, max_frames=FRAMES)
    assert len(source) == FRAMES
    from_folder = list(source)
    assert len(from_bag) == FRAMES
    for a, b in zip(from_bag, from_folder):
        assert a["index"] == b["index"]
        assert a["timestamp"] == pytest.approx(b["timestamp"], abs=1e-6)
        assert a["image"].dtype == np.uint8 and a["image"].shape == (480, 640, 3)
        assert np.array_equal(a["image"], b["image"])
        assert a["depth"].dtype == np.float32
        assert np.array_equal(a["depth"], b["depth"])
        assert a["ground_truth"] is None  # no groundtruth file given
        assert b["ground_truth"].shape == (4, 4)  # the folder has its own
    # The image is the PNG as cv2 reads it: a bag frame extracts exactly as the file.
    first = sorted((tum_sequence / "rgb").glob("*.png"))[0]
    assert np.array_equal(from_bag[0]["image"], cv2.imread(str(first)))


def test_extraction_on_bag_frames_equals_extraction_on_the_files(bag, tum_sequence):
    extractor = noctua.Extractor("paper")
    files = sorted((tum_sequence / "rgb").glob("*.png"))
    for frame in noctua.open_frames(bag=bag, max_frames=3):
        keypoints, descriptors = extractor.extract(frame["image"])
        assert len(keypoints) > 500
        ref_keypoints, ref_descriptors = extractor.extract(files[frame["index"]])
        assert np.array_equal(keypoints, ref_keypoints)
        assert np.array_equal(descriptors, ref_descriptors)


def test_ground_truth_of_a_bag_is_interpolated_at_each_frame(bag, tum_sequence):
    with_truth = noctua.open_frames(bag=bag, groundtruth=tum_sequence / "groundtruth.txt")
    folder = noctua.open_frames(dataset=tum_sequence, max_frames=FRAMES)
    assert len(with_truth.ground_truth()) > 1000  # the TUM file's rows, (N, 8)
    for a, b in zip(with_truth, folder):
        assert np.allclose(a["ground_truth"], b["ground_truth"], atol=1e-6)


def test_run_slam_on_a_bag_tracks_and_scores_against_its_ground_truth(bag, tum_sequence,
                                                                       tum_config, tmp_path):
    result = noctua.run_slam(bag=bag, config=tum_config, method="orb", out=tmp_path / "slam",
                             groundtruth=tum_sequence / "groundtruth.txt")
    report = result["report"]
    assert report["frames"] == FRAMES
    assert report["bag"] == str(bag)
    assert len(result["trajectory"]) == report["tracked_frames"] >= 25
    assert report["ate"]["translation_m"]["rmse"] < 0.1
    assert (tmp_path / "slam" / "trajectory.txt").exists()


def test_a_bag_without_the_topic_names_the_file_and_topic(bag, tum_config):
    with pytest.raises(noctua.Error, match=r"fr1\.bag.*/kinect/rgb"):
        noctua.open_frames(bag=bag, rgb_topic="/kinect/rgb")
    with pytest.raises(noctua.Error, match=r"fr1\.bag.*/kinect/depth"):
        noctua.run_slam(bag=bag, config=tum_config, depth_topic="/kinect/depth")
    with pytest.raises(noctua.Error, match="exactly one source"):
        noctua.open_frames()
    with pytest.raises(noctua.Error, match="config"):
        noctua.run_slam(bag=bag)


def test_evaluate_features_on_a_bag_scores_every_pair_as_on_the_folder(bag, tum_sequence,
                                                                        tmp_path):
    camera = noctua.config_path("tum_fr1.yaml")
    common = dict(camera=camera, methods=["orb"], gap=5, max_frames=20)
    folder = noctua.evaluate_features(dataset=tum_sequence, **common)
    from_bag = noctua.evaluate_features(bag=bag, groundtruth=tum_sequence / "groundtruth.txt",
                                        out=tmp_path / "eval", **common)
    assert from_bag["dataset"] == "fr1.bag"
    a, b = folder["methods"]["orb"], from_bag["methods"]["orb"]
    assert [c["count"] for c in b["counts"]] == [c["count"] for c in a["counts"]]
    assert len(b["pairs"]) == 15
    assert b["pairs"] == a["pairs"]
    assert sum(p["matches"] for p in a["pairs"]) > 15 * 50
    # Every pair says how many of frame i's corners frame j found again, more at a wider tau.
    assert all(p["repeated"] == sorted(p["repeated"]) and p["repeated"][-1] <= p["comparable"]
               for p in a["pairs"])
    assert sum(p["repeated"][0] for p in a["pairs"]) > 0
    assert (tmp_path / "eval" / "pairs.csv").exists()
    with pytest.raises(noctua.Error, match=r"fr1\.bag.*--groundtruth"):
        noctua.evaluate_features(bag=bag, **common)
