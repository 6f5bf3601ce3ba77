import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def shared_dir():
    """The real data; missing data fails the tests, never skips them."""
    path = pathlib.Path(os.environ.get("NOCTUA_SHARED_DIR")
                        or os.environ.get("NOCTUA_TEST_SHARED_DIR") or REPO.parent / "shared")
    assert (path / "data").is_dir(), f"{path}/data is missing: the tests need the real data"
    return path


@pytest.fixture(scope="session")
def tum_sequence(shared_dir):
    path = shared_dir / "data" / "tum_fr1_rpy_200"
    assert (path / "rgb").is_dir(), f"{path} is missing"
    return path


@pytest.fixture(scope="session")
def first_frame(tum_sequence):
    return sorted((tum_sequence / "rgb").glob("*.png"))[0]


@pytest.fixture(scope="session")
def tum_config():
    return REPO / "config" / "tum_fr1.yaml"
