"""Shared fixtures of the semap Python tests (issue 15).

Real data comes from SEMAP_DATA_DIR (default ../shared/data beside the repository, or
SEMAP_SHARED_DIR/data as ctest passes it); tests whose data is absent are skipped, or fail
under CI=true (as the C++ tests do: tests/test_support.hpp, issue 21).
"""
import os
import pathlib

import numpy as np
import pytest

import semap

REPO = pathlib.Path(os.environ.get("SEMAP_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BUILD = pathlib.Path(os.environ.get("SEMAP_BINARY_DIR", REPO / "build"))

# The TUM slice most tests map: enough motion for a meaningful ATE, fast on 2 cores.
TUM_SLICE = 30


def data_dir():
    if os.environ.get("SEMAP_DATA_DIR"):
        return pathlib.Path(os.environ["SEMAP_DATA_DIR"])
    if os.environ.get("SEMAP_SHARED_DIR"):
        return pathlib.Path(os.environ["SEMAP_SHARED_DIR"]) / "data"
    return REPO.parent / "shared" / "data"


def require_data(name):
    path = data_dir() / name
    if not path.exists():
        skip_or_fail("shared data missing: %s (set SEMAP_DATA_DIR)" % path)
    return path


def skip_or_fail(message):
    """Skips the calling test, or fails it under CI=true (a missing prerequisite is a CI error)."""
    if os.environ.get("CI") == "true":
        pytest.fail(message + " (CI=true: this must not be missing)")
    pytest.skip(message)


def synthetic_camera():
    return semap.Camera(fx=100.0, fy=100.0, cx=39.5, cy=29.5, width=80, height=60, depth_scale=1000.0)


def synthetic_frame(camera, shift_m=0.0):
    """A box corner seen from 1-2 m (enough structure to track), as numpy arrays."""
    h, w = camera.height, camera.width
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    depth = 1.5 + 0.3 * np.sin((u + 100 * shift_m) / 9.0) * np.cos(v / 7.0)
    depth = depth.astype(np.float32)
    rgb = np.zeros((h, w, 3), np.uint8)
    rgb[..., 0] = (u * 3).astype(np.uint8)
    rgb[..., 1] = (v * 4).astype(np.uint8)
    rgb[..., 2] = 128
    return rgb, depth


@pytest.fixture(scope="session")
def tum_path():
    return require_data("tum_fr1_rpy")


@pytest.fixture(scope="session")
def tum(tum_path):
    return semap.open_dataset(tum_path)


@pytest.fixture(scope="session")
def tum_frames(tum):
    return [tum[i] for i in range(TUM_SLICE)]


def map_frames(frames, camera, config=None, **add_kwargs):
    """Maps dataset frames with the numpy API; returns (mapper, results)."""
    mapper = semap.Mapper(camera, config=config)
    results = [mapper.add_frame(f.rgb, f.depth, f.timestamp, **add_kwargs) for f in frames]
    mapper.finish()
    return mapper, results


@pytest.fixture(scope="session")
def tum_mapped(tum, tum_frames):
    """The TUM slice mapped deterministically (pipeline.threads = 1)."""
    return map_frames(tum_frames, tum.camera, config={"pipeline": {"threads": 1}})
