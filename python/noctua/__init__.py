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


def run_slam(sequence_dir, config, method="paper", detector=None, max_frames=0, out=None,
             brightness=1.0, sequential=False, force=False, video=None, map_ply=None,
             load_map=None, localize=False, save_map=None):
    """Runs the SLAM over a TUM / OpenLORIS sequence folder, as ``noctua slam`` does.

    Returns a dict: ``trajectory`` ((N, 8) TUM rows), ``report`` (report.json's content:
    frames, lost frames, timing, ATE/RPE with ground truth) and ``frames_csv`` (frames.csv's
    text). With ``out``, writes the same files as the command (trajectory.txt, frames.csv,
    report.json, report.md, ATE/RPE plots) into that folder. With ``video`` (.mp4 or .avi), writes
    the viewer's panel of every frame as a video (``video_frames`` in the result counts them);
    with ``map_ply``, the final map as a PLY (docs/viewer.md).

    ``load_map`` starts from a map saved with ``save_map`` (same method and camera) instead of
    a new one; with ``localize`` the run only localises in it and leaves it unchanged.
    ``save_map`` writes the map at the end of the run (``report["map"]`` says what was done).
    """
    return _noctua.run_slam(
        _os.fspath(sequence_dir), _os.fspath(config), method,
        None if detector is None else _os.fspath(detector), max_frames,
        None if out is None else _os.fspath(out), brightness, sequential, force,
        None if video is None else _os.fspath(video),
        None if map_ply is None else _os.fspath(map_ply),
        None if load_map is None else _os.fspath(load_map), localize,
        None if save_map is None else _os.fspath(save_map))
