import numpy as np
import pytest

import noctua


def test_a_missing_file_names_it():
    with pytest.raises(noctua.Error, match="no_such_frame.png"):
        noctua.extract("/nonexistent/no_such_frame.png")


def test_none_from_cv2_imread_is_explained():
    with pytest.raises(noctua.Error, match="image is None"):
        noctua.extract(None)


def test_a_corrupt_file_names_it(tmp_path):
    corrupt = tmp_path / "corrupt.png"
    corrupt.write_bytes(b"\x89PNG\r\n\x1a\n this is not a png")
    with pytest.raises(noctua.Error, match="corrupt.png"):
        noctua.extract(corrupt)


def test_wrong_arrays_are_refused_with_the_reason():
    with pytest.raises(noctua.Error, match="uint8"):
        noctua.extract(np.zeros((48, 64), np.float64))
    with pytest.raises(noctua.Error, match="shape"):
        noctua.extract(np.zeros((4, 48, 64, 3), np.uint8))
    with pytest.raises(noctua.Error, match="empty"):
        noctua.extract(np.zeros((0, 0), np.uint8))
    with pytest.raises(noctua.Error, match="mask is 10x10"):
        noctua.extract(np.zeros((48, 64), np.uint8), mask=np.ones((10, 10), np.uint8))


def test_an_unknown_method_lists_the_known_ones():
    with pytest.raises(noctua.Error, match="paper"):
        noctua.Extractor("no-such-method")


def test_errors_are_runtime_errors():
    assert issubclass(noctua.Error, RuntimeError)
