"""semap.open_dataset(): the CLI's readers; frames as numpy views, in the orders and units the
Mapper takes; compared with what OpenCV reads from the same files."""
import cv2
import numpy as np
import pytest

import semap


def test_tum_dataset(tum, tum_path):
    assert len(tum) == 200 and tum.format == "tum" and tum.has_ground_truth
    cam = tum.camera
    assert (cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height, cam.depth_scale) == (
        517.3, 516.5, 318.6, 255.3, 640, 480, 5000.0)
    assert len(tum.timestamps) == 200 and tum.timestamps == sorted(tum.timestamps)
    gt = tum.ground_truth()
    assert len(gt) > 150 and gt[0][1].shape == (4, 4)
    assert "200 frames" in repr(tum)


# TUM's published freiburg1 lens (k1 k2 p1 p2 k3): the reader undistorts, reporting the pinhole camera.
FR1_DISTORTION = np.array([0.2624, -0.9531, -0.0054, 0.0026, 1.1633])


def undistorted(image, camera, interpolation):
    maps = cv2.initUndistortRectifyMap(camera.K, FR1_DISTORTION, None, camera.K, (640, 480), cv2.CV_16SC2)
    border = cv2.BORDER_CONSTANT if interpolation == cv2.INTER_NEAREST else cv2.BORDER_REPLICATE
    return cv2.remap(image, *maps, interpolation, borderMode=border, borderValue=0)


def test_frames_are_what_opencv_reads(tum):
    f = tum[3]
    assert f.index == 3 and f.timestamp == tum.timestamps[3]
    assert f.rgb.shape == (480, 640, 3) and f.rgb.dtype == np.uint8
    assert f.depth.shape == (480, 640) and f.depth.dtype == np.float32
    assert tum.camera.distortion == (0, 0, 0, 0, 0)
    bgr = undistorted(cv2.imread(f.rgb_path, cv2.IMREAD_COLOR), tum.camera, cv2.INTER_LINEAR)
    np.testing.assert_array_equal(f.bgr, bgr)
    np.testing.assert_array_equal(f.rgb, bgr[..., ::-1])  # RGB order
    raw = cv2.imread(f.depth_path, cv2.IMREAD_UNCHANGED)
    assert raw.dtype == np.uint16
    expected = np.where((raw == 0) | (raw == 65535), 0, raw * np.float32(1 / 5000.0)).astype(np.float32)
    expected = undistorted(expected, tum.camera, cv2.INTER_NEAREST)
    np.testing.assert_array_equal(f.depth, expected)
    assert f.labels is None and f.instances is None
    pose = f.gt_pose
    assert pose.shape == (4, 4)
    np.testing.assert_allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-6)


def test_indexing(tum):
    assert tum[-1].index == len(tum) - 1
    with pytest.raises(IndexError):
        tum[len(tum)]
    with pytest.raises(IndexError):
        tum[-len(tum) - 1]
    first = [f.index for _, f in zip(range(3), tum)]  # iteration
    assert first == [0, 1, 2]


def test_views_keep_the_frame_alive(tum):
    depth = tum[5].depth  # the frame object is gone; the array still reads its memory
    rgb = tum[5].rgb
    assert depth.base is not None and np.count_nonzero(depth) > 100000
    assert rgb.mean() > 10


def test_missing_dataset_is_an_error(tmp_path):
    with pytest.raises(semap.Error, match="nowhere"):
        semap.open_dataset(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(semap.Error):
        semap.open_dataset(tmp_path / "empty")
