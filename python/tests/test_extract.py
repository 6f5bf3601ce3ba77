import os
import subprocess

import cv2
import numpy as np
import pytest

import noctua


def reference_extraction(image_path, method, tmp_path):
    """Keypoints (N x 6) and descriptors of the C++ extractor on the same file."""
    out = tmp_path / f"{method}.yml"
    subprocess.run([os.environ["NOCTUA_REFERENCE_EXTRACT"], str(image_path), method, str(out)],
                   check=True)
    storage = cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ)
    keypoints = storage.getNode("keypoints").mat()
    descriptors = storage.getNode("descriptors").mat()
    storage.release()
    return keypoints, descriptors


def test_paper_on_a_real_frame_equals_the_cpp_extractor(first_frame, tmp_path):
    keypoints, descriptors = noctua.extract(cv2.imread(str(first_frame)), method="paper")
    assert len(keypoints) >= 500
    assert descriptors.shape == (len(keypoints), 32)
    assert descriptors.dtype == np.uint8
    assert keypoints.dtype == noctua.keypoint_dtype
    ref_keypoints, ref_descriptors = reference_extraction(first_frame, "paper", tmp_path)
    assert np.array_equal(descriptors, ref_descriptors)
    ours = np.stack([keypoints[f].astype(np.float32)
                     for f in ("x", "y", "size", "angle", "response", "octave")], axis=1)
    assert np.array_equal(ours, ref_keypoints)


@pytest.mark.parametrize("method", noctua.method_names())
def test_every_method_runs_on_colour_and_grey(method, first_frame):
    bgr = cv2.imread(str(first_frame))
    for image in (bgr, cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)):
        keypoints, descriptors = noctua.extract(image, method=method)
        assert len(keypoints) > 100
        assert descriptors.shape[0] == len(keypoints)
        if method in ("sift", "surf"):
            assert descriptors.dtype == np.float32
        else:
            assert descriptors.dtype == np.uint8 and descriptors.shape[1] == 32


def test_mask_removes_points_and_extractor_is_reusable(first_frame):
    image = cv2.imread(str(first_frame))
    mask = np.zeros(image.shape[:2], np.uint8)
    mask[:, : image.shape[1] // 2] = 255
    extractor = noctua.Extractor("orb")
    keypoints, _ = extractor.extract(image, mask=mask)
    assert len(keypoints) > 0
    assert (keypoints["x"] >= image.shape[1] // 2 - 1).all()
    assert extractor.last_stats["counts"]["final"] == len(keypoints)
    again, _ = extractor.extract(str(first_frame), mask=mask)  # a path works too
    assert np.array_equal(again, keypoints)
    assert len(noctua.to_cv_keypoints(keypoints[:5])) == 5


def test_settings_file_is_read(first_frame, tum_config):
    keypoints, _ = noctua.extract(cv2.imread(str(first_frame)), method="orb", config=tum_config)
    assert len(keypoints) > 500


def test_warped_pair_on_a_real_dark_photo(shared_dir):
    photo = shared_dir / "data" / "lowlight" / "lol_low20" / "low" / "2.png"
    noctua_pair = noctua.match_warped_pair(photo, method="noctua")
    orb_pair = noctua.match_warped_pair(cv2.imread(str(photo)), method="orb")
    assert noctua_pair["noise_sigma"] == orb_pair["noise_sigma"] > 0
    assert 0 < noctua_pair["correct"] <= noctua_pair["matches"] <= noctua_pair["keypoints"]
    assert noctua_pair["correct"] > orb_pair["correct"]
    assert noctua_pair["correct"] <= noctua_pair["repeated"] <= noctua_pair["comparable"]
    with pytest.raises(noctua.Error, match="scale"):
        noctua.match_warped_pair(photo, scale=0)
