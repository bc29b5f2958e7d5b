"""examples/python/map_tum.py on a 30-frame slice of TUM fr1_rpy written to a temporary folder."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO, TUM_SLICE

EXAMPLE = REPO / "examples" / "python" / "map_tum.py"


def write_slice(source, dest, frames):
    """The first `frames` colour images, the depth images up to just past them, the ground truth."""
    rgb = [line for line in (source / "rgb.txt").read_text().splitlines() if line and not line.startswith("#")]
    rgb = rgb[:frames]
    last_t = float(rgb[-1].split()[0]) + 0.05
    depth = [line for line in (source / "depth.txt").read_text().splitlines()
             if line and not line.startswith("#") and float(line.split()[0]) < last_t]
    dest.mkdir()
    (dest / "rgb.txt").write_text("# colour\n" + "\n".join(rgb) + "\n")
    (dest / "depth.txt").write_text("# depth\n" + "\n".join(depth) + "\n")
    (dest / "groundtruth.txt").write_text((source / "groundtruth.txt").read_text())
    for sub in ("rgb", "depth"):
        (dest / sub).mkdir()
    for line in rgb + depth:
        name = line.split()[1]
        os.symlink(source / name, dest / name)


def test_map_tum_example(tum_path, tum_mapped, tmp_path):
    pytest.importorskip("cv2")
    dataset = tmp_path / "rgbd_dataset_freiburg1_rpy"
    write_slice(tum_path, dataset, TUM_SLICE)
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, str(EXAMPLE), str(dataset), str(out), "--threads", "1"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "ATE RMSE" in run.stdout
    summary = json.loads((out / "map_tum.json").read_text())
    assert summary["frames"] == TUM_SLICE and summary["lost"] == 0
    assert summary["ate_rmse_m"] < 0.015  # as test_mapping.py: measured 0.0072 m
    assert summary["fps_online"] > 0 and 0 <= summary["binding_ms_per_frame"] < 20
    for name in ("trajectory.txt", "mesh.ply", "objects.json", "map.semap"):
        assert (out / name).exists(), name
    # OpenCV loading + the example's association give the frames semap's own TUM reader gives:
    # the same trajectory as the Mapper fed from semap.open_dataset().
    mapper, _ = tum_mapped
    ours = np.loadtxt(out / "trajectory.txt")
    reference = np.array([[t, *pose[:3, 3]] for t, pose in mapper.trajectory()])
    np.testing.assert_allclose(ours[:, :4], reference, atol=1e-9)


def test_map_tum_example_errors(tmp_path):
    run = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path / "missing"), str(tmp_path / "out")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 1 and "rgb.txt not found" in run.stderr and "Traceback" not in run.stderr
