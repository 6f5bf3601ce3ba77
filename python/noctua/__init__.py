"""noctua: feature points for visual SLAM that survive low light and moving people.

Images are numpy arrays as cv2 gives them (uint8 BGR or grey; depth uint16 raw or float32
metres). Keypoints are numpy structured arrays of ``keypoint_dtype``: fields x, y, size, angle,
response (float32) and octave (int32), one row per descriptor row. Errors raise ``noctua.Error``
(a RuntimeError) with the C++ library's message.
"""

import os as _os

from ._noctua import (  # noqa: F401  (the public API)
    Detector,
    Error,
    Extractor,
    FrameSource,
    LowLightSimulator,
    SensorModel,
    Slam,
    __version__,
    ate,
    brightness_for_mean_ratio,
    darken,
    coco_class_names,
    edge_methods,
    edges,
    keypoint_dtype,
    method_names,
    motion_level,
    read_trajectory,
    rpe,
    sensor_model,
    sensor_models,
    write_trajectory,
)
from . import _noctua

Error.__module__ = __name__  # tracebacks say noctua.Error, the name users catch


def extract(image, method="paper", config=None, mask=None, detector=None):
    """(keypoints, descriptors) of one image with one method.

    image: uint8 BGR or grey array (cv2.imread) or an image path; mask: optional array of the
    image's size, no point where it is non-zero; config: settings file; detector: ONNX model for
    the dynamic regions. To run many images, create an ``Extractor`` once instead.
    """
    return Extractor(method, config, detector).extract(image, mask)


def to_cv_keypoints(keypoints):
    """The keypoint array as a list of cv2.KeyPoint (e.g. for cv2.drawKeypoints)."""
    import cv2

    return [
        cv2.KeyPoint(float(k["x"]), float(k["y"]), float(k["size"]), float(k["angle"]),
                     float(k["response"]), int(k["octave"]))
        for k in keypoints
    ]


def config_dir():
    """The folder of the camera presets (tum_fr1.yaml, ...): $NOCTUA_CONFIG_DIR, the installed
    share/noctua/config, or the source tree's config/ for a build."""
    prefix = _os.path.join(_os.path.dirname(_os.path.abspath(__file__)), *[".."] * 4)
    return _noctua.config_dir([_os.path.join(prefix, "share", "noctua", "config")])


def config_path(name):
    """A camera preset by file name, e.g. config_path("tum_fr1.yaml")."""
    return _os.path.join(config_dir(), name)


TUM_RGB_TOPIC = "/camera/rgb/image_color"
TUM_DEPTH_TOPIC = "/camera/depth/image"


def _path(value):
    return None if value is None else _os.fspath(value)


def run_slam(sequence_dir=None, config=None, method="paper", detector=None, max_frames=0,
             out=None, brightness=1.0, sequential=False, force=False, video=None, map_ply=None,
             load_map=None, localize=False, save_map=None, bag=None, rgb_topic=TUM_RGB_TOPIC,
             depth_topic=TUM_DEPTH_TOPIC, groundtruth=None, reject_moving_points=False,
             vocabulary=None, sensor="noiseless", seed=1, deterministic=False):
    """Runs the SLAM over a TUM / OpenLORIS sequence folder or a ROS1 bag, as ``noctua slam``
    does (``--dataset`` or ``--bag``).

    Give ``sequence_dir`` or ``bag`` (a ROS1 bag of sensor_msgs/Image colour and depth on
    ``rgb_topic`` and ``depth_topic``, TUM's names by default; ``groundtruth``: its TUM-format
    ground truth for ATE/RPE), and ``config``, the camera preset.

    Returns a dict: ``trajectory`` ((N, 8) TUM rows), ``report`` (report.json's content:
    frames, lost frames, timing, ATE/RPE with ground truth) and ``frames_csv`` (frames.csv's
    text). With ``out``, writes the same files as the command (trajectory.txt, frames.csv,
    report.json, report.md, ATE/RPE plots) into that folder. With ``video`` (.mp4 or .avi), writes
    the viewer's panel of every frame as a video (``video_frames`` in the result counts them);
    with ``map_ply``, the final map as a PLY (docs/viewer.md).

    ``load_map`` starts from a map saved with ``save_map`` (same method and camera) instead of
    a new one; with ``localize`` the run only localises in it and leaves it unchanged.
    ``save_map`` writes the map at the end of the run (``report["map"]`` says what was done).

    ``reject_moving_points`` turns on the model-free rejection of moving points (``slam
    --reject-moving-points``). ``vocabulary`` is the place-recognition vocabulary (``slam
    --vocabulary``): ``"default"``, ``"none"`` or a file; None keeps the settings file's
    (``report["map"]["vocabulary"]`` names the one used). ``brightness``, ``sensor`` and ``seed``
    darken every frame by a camera model of ``sensor_models()``, as ``slam --brightness --sensor
    --seed`` do. ``deterministic`` runs the local bundle adjustment in line and maps each
    keyframe in the frame that makes it (``slam --deterministic``): the same result every run,
    slower keyframes.
    """
    if config is None:
        raise Error("run_slam needs config (a camera preset, e.g. config_path('tum_fr1.yaml'))")
    return _noctua.run_slam(
        _path(sequence_dir), _path(bag), rgb_topic, depth_topic, _path(groundtruth),
        _os.fspath(config), method, _path(detector), max_frames, _path(out), brightness,
        sequential, force, _path(video), _path(map_ply), _path(load_map), localize,
        _path(save_map), reject_moving_points, "" if vocabulary is None else _os.fspath(vocabulary),
        sensor, seed, deterministic)


def open_frames(dataset=None, bag=None, rgb_topic=TUM_RGB_TOPIC, depth_topic=TUM_DEPTH_TOPIC,
                groundtruth=None, max_frames=0, depth_factor=5000.0):
    """The frames of a sequence folder or a ROS1 bag, in time order, as ``noctua slam`` and
    ``noctua extract`` read them (``--dataset`` or ``--bag``).

    Returns a ``FrameSource``, an iterator of dicts: ``index``, ``timestamp`` (s), ``image``
    (uint8 BGR), ``depth`` (float32 metres, 0 = none) and ``ground_truth`` (4x4
    T_world_camera at the timestamp, or None). A bag's colour and depth are on ``rgb_topic`` and
    ``depth_topic`` (TUM's names by default); ``groundtruth`` is its TUM-format ground truth (a
    folder has its own). ``max_frames``: the first frames only (0: all); ``depth_factor``: a
    folder's 16-bit depth per metre. A bag without those topics raises ``noctua.Error`` naming
    the file, the topic and the bag's image topics. For example::

        extractor = noctua.Extractor("paper")
        for frame in noctua.open_frames(bag="fr1.bag"):
            keypoints, descriptors = extractor.extract(frame["image"])
    """
    return _noctua.open_frames(_path(dataset), _path(bag), rgb_topic, depth_topic,
                               _path(groundtruth), max_frames, depth_factor)


def write_bag(sequence_dir, path, max_frames=0, depth_factor=5000.0, rgb_topic=TUM_RGB_TOPIC,
              depth_topic=TUM_DEPTH_TOPIC, rgb_encoding="rgb8", depth_encoding="32FC1"):
    """Writes a TUM / OpenLORIS sequence folder as a ROS1 bag in TUM's layout (colour
    ``rgb8``/``bgr8``, depth ``32FC1`` metres or ``16UC1`` millimetres), stamped with the images'
    times; ``max_frames``: the first frames only (0: all)."""
    _noctua.write_bag(_os.fspath(sequence_dir), _os.fspath(path), max_frames, depth_factor,
                      rgb_topic, depth_topic, rgb_encoding, depth_encoding)


def match_warped_pair(photo, method="noctua", config=None, rotation_deg=8.0, scale=0.9, ratio=0.8,
                      correct_px=3.0, fresh_noise_multiple=1.0, seed=1):
    """Matching on a single photo, where there is no second view (``bench/dark_photos``): the
    photo (uint8 BGR / grey array or a path) against a copy warped by a known similarity
    (``rotation_deg``, ``scale``), each copy with fresh Gaussian noise of
    ``fresh_noise_multiple`` times the photo's own estimated noise (its real noise would otherwise
    repeat like texture). Ratio-test matches (``ratio``) are correct when the warp maps their
    point within ``correct_px`` of the partner. ``config``: a settings file for the extractor
    (None: defaults). Returns a dict: ``keypoints``, ``matches``, ``correct``, ``noise_sigma``,
    and, whatever the descriptors say, ``comparable`` (the photo's points the warp keeps inside
    the copy) and ``repeated`` (of those, the ones the copy detected within ``correct_px``).
    """
    return _noctua.match_warped_pair(photo, method, _path(config), rotation_deg, scale, ratio,
                                     correct_px, fresh_noise_multiple, seed)


def evaluate_features(dataset=None, bag=None, camera=None, groundtruth=None,
                      methods=("orb", "paper"), gap=20, pair_step=1, max_frames=0, ratio=0.8,
                      config=None, out=None, force=False, rgb_topic=TUM_RGB_TOPIC,
                      depth_topic=TUM_DEPTH_TOPIC):
    """The feature evaluation of ``noctua eval`` (docs/evaluation.md) on a sequence folder or a
    ROS1 bag: points per frame and matches of frame i against i + ``gap`` judged correct from
    depth and the ground-truth poses.

    A folder brings its ground truth and, unless ``camera`` (a preset) is given, its
    camera.yaml; a bag needs ``groundtruth`` (TUM format) and ``camera``. ``max_frames`` counts
    the frames with ground truth (0: all). With ``out``, writes the command's report there.
    Returns a dict: ``dataset``, ``taus``, ``default_tau``, ``markdown`` (the summary table) and
    ``methods``: per method name, ``counts`` (frame, timestamp, count, extract_ms) and ``pairs``
    (frame_i, frame_j, matches, no_depth, on_dynamic, correct per tau, comparable, repeated
    per tau: frame i's points that frame j sees and, of those, the ones it detected again).
    """
    if camera is None and dataset is not None:
        camera = _os.path.join(_os.fspath(dataset), "camera.yaml")
    if camera is None:
        raise Error("evaluate_features with a bag needs camera (a preset, e.g. "
                    "config_path('tum_fr1.yaml'))")
    return _noctua.evaluate_features(
        _path(dataset), _path(bag), rgb_topic, depth_topic, _path(groundtruth), _path(camera),
        list(methods), gap, pair_step, max_frames, ratio, _path(config), _path(out), force)
