import cv2
import numpy as np
import pytest

import noctua


def test_edge_maps_of_every_method(first_frame):
    image = cv2.imread(str(first_frame))
    for method in noctua.edge_methods():
        edges = noctua.edges(image, method=method)
        assert edges.shape == image.shape[:2] and edges.dtype == np.uint8
        fraction = np.count_nonzero(edges) / edges.size
        assert 0.005 < fraction < 0.5, (method, fraction)
    with pytest.raises(noctua.Error, match="pc-fast"):
        noctua.edges(image, method="no-such-edges")


def test_detector_finds_people_and_masks_them(shared_dir):
    model = shared_dir / "models" / "yolov8n" / "yolov8n_head_f32.onnx"
    image = cv2.imread(str(shared_dir / "models" / "images" / "zidane.jpg"))
    detector = noctua.Detector(model, input_size=(640, 384))
    detections = detector.detect(image)
    people = [d for d in detections if d["class_name"] == "person"]
    assert len(people) >= 2
    assert people[0]["motion_level"] == "high"
    mask = detector.dynamic_mask(image)
    assert mask.shape == image.shape[:2] and mask.dtype == np.uint8
    x, y, w, h = (int(v) for v in people[0]["box"])
    assert mask[y + h // 2, x + w // 2] == 255
    with pytest.raises(noctua.Error, match="missing.onnx"):
        noctua.Detector(shared_dir / "missing.onnx")


def test_low_light_sensor_model(first_frame):
    image = cv2.imread(str(first_frame))
    model = noctua.SensorModel()
    brightness = noctua.brightness_for_mean_ratio(image, 0.15, model)
    assert 0.0 < brightness < 0.15
    simulator = noctua.LowLightSimulator(model, brightness)
    dark = simulator.apply(image, seed=3)
    assert dark.shape == image.shape and dark.dtype == np.uint8
    assert abs(dark.mean() / image.mean() - 0.15) < 0.03
    assert np.array_equal(dark, simulator.apply(image, seed=3))
    mean, variance = simulator.expected_output(128)
    assert 0.0 < mean < 128.0 and variance > 0.0
    with pytest.raises(noctua.Error):
        noctua.SensorModel(gamma=-1.0)


def test_named_sensor_models_darken_to_the_level(first_frame):
    image = cv2.imread(str(first_frame))
    names = noctua.sensor_models()
    assert "kinect" in names and len(names) >= 4
    for name in names:
        assert noctua.sensor_model(name).name == name
        dark = noctua.darken(image, 0.15, sensor=name, seed=2)
        assert dark.shape == image.shape and dark.dtype == np.uint8
        assert abs(dark.mean() / image.mean() - 0.15) < 0.03, name
    with pytest.raises(noctua.Error, match="no-such-sensor"):
        noctua.sensor_model("no-such-sensor")


def test_ate_and_rpe_on_arrays_and_files(tum_sequence, tmp_path):
    truth = noctua.read_trajectory(tum_sequence / "groundtruth.txt")
    assert truth.shape[1] == 8
    shifted = truth.copy()
    shifted[:, 1:4] += [1.0, -2.0, 0.5]  # a rigid offset: aligned away
    result = noctua.ate(shifted, truth)
    assert result["rmse"] < 1e-6 and result["count"] == len(truth)
    path = tmp_path / "estimate.txt"
    noctua.write_trajectory(path, shifted)
    assert noctua.ate(path, tum_sequence / "groundtruth.txt")["rmse"] < 1e-6
    rpe = noctua.rpe(truth, truth)
    assert rpe["translation_m"]["rmse"] < 1e-9
    with pytest.raises(noctua.Error, match="at least 3 estimated poses"):
        noctua.ate(shifted[:2], truth)


def test_config_presets_are_found():
    assert noctua.config_path("tum_fr1.yaml").endswith("tum_fr1.yaml")
    assert __import__("os").path.exists(noctua.config_path("tum_fr1.yaml"))
