"""Fleet mapping on Dask (issue 23): a real dask-scheduler and two dask-worker processes on
127.0.0.1, three overlapping recordings of a shared sequence mapped in parallel and merged into
one world frame, checked with ONE alignment of all three trajectories against the ground truth;
then the same with one worker killed mid-task: the same result."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

import semap
from conftest import BUILD, require_data

SPLITS = [(0, 199), (150, 349), (300, 499)]  # redkitchen: each overlaps the next by 50 frames


def write_slice(ds, first, last, out):
    """A TUM-layout folder of links to frames first..last (with their ground truth)."""
    (out / "rgb").mkdir(parents=True)
    (out / "depth").mkdir()
    rgb, depth, gt = ["# timestamp filename"], ["# timestamp filename"], ["# timestamp tx ty tz qx qy qz qw"]
    for i in range(first, last + 1):
        f = ds[i]
        rgb_name = "rgb/%06d%s" % (i, pathlib.Path(f.rgb_path).suffix)
        depth_name = "depth/%06d.png" % i
        os.symlink(pathlib.Path(f.rgb_path).resolve(), out / rgb_name)
        os.symlink(pathlib.Path(f.depth_path).resolve(), out / depth_name)
        rgb.append("%.6f %s" % (f.timestamp, rgb_name))
        depth.append("%.6f %s" % (f.timestamp, depth_name))
        gt.append(tum_line(f.timestamp, f.gt_pose))
    for name, lines in (("rgb.txt", rgb), ("depth.txt", depth), ("groundtruth.txt", gt)):
        (out / name).write_text("\n".join(lines) + "\n")
    c = ds.camera
    (out / "dataset.yaml").write_text(
        "format: tum\ncamera:\n  fx: %r\n  fy: %r\n  cx: %r\n  cy: %r\n  width: %d\n  height: %d\n  depth_scale: %r\n"
        % (c.fx, c.fy, c.cx, c.cy, c.width, c.height, c.depth_scale))


def tum_line(t, pose):
    import numpy as np
    R, p = pose[:3, :3], pose[:3, 3]
    # rotation matrix -> quaternion (x y z w), numerically safe branch
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f" % (t, p[0], p[1], p[2], x, y, z, w)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    kitchen = require_data("7scenes_redkitchen")
    ds = semap.open_dataset(kitchen)
    root = tmp_path_factory.mktemp("fleet_data")
    dirs = []
    for k, (first, last) in enumerate(SPLITS):
        d = root / ("rec%d" % (k + 1))
        write_slice(ds, first, last, d)
        dirs.append(d)
    gt = root / "groundtruth.txt"
    gt.write_text("\n".join(tum_line(ds[i].timestamp, ds[i].gt_pose) for i in range(SPLITS[-1][1] + 1)) + "\n")
    config = root / "fleet.yaml"
    config.write_text("pipeline:\n  threads: 1\n")  # deterministic: a rerun gives the same bytes
    return dirs, gt, config


def env():
    e = dict(os.environ)
    e["PYTHONPATH"] = str(BUILD / "python") + os.pathsep + e.get("PYTHONPATH", "")
    return e


class DaskCluster:
    """dask-scheduler + two dask-worker processes (no nanny: a killed worker stays dead)."""

    def __init__(self, folder):
        self.file = folder / "scheduler.json"
        self.log = open(folder / "dask.log", "w")
        self.scheduler = subprocess.Popen(
            ["dask-scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
             str(self.file)], stdout=self.log, stderr=subprocess.STDOUT, env=env())
        deadline = time.monotonic() + 60
        while not self.file.exists():
            assert time.monotonic() < deadline, "dask-scheduler did not start"
            time.sleep(0.2)
        time.sleep(0.5)  # the file is written before it is complete on some versions
        self.address = json.loads(self.file.read_text())["address"]
        self.workers = [subprocess.Popen(
            ["dask-worker", "--scheduler-file", str(self.file), "--nthreads", "1", "--no-nanny", "--no-dashboard",
             "--host", "127.0.0.1", "--name", "w%d" % k], stdout=self.log, stderr=subprocess.STDOUT, env=env())
            for k in range(2)]

    def close(self):
        for p in self.workers + [self.scheduler]:
            if p.poll() is None:
                p.terminate()
        for p in self.workers + [self.scheduler]:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
        self.log.close()


def run_fleet(recordings, out, address, kill_worker=None):
    dirs, _, config = recordings
    cmd = [sys.executable, "-m", "semap.fleet", *map(str, dirs), "--out", str(out), "--scheduler", address,
           "--config", str(config), "--segmenter", "none"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env(), text=True)
    killed = False
    if kill_worker is not None:
        # Mid-task: once a recording's run has opened its staging folder and before it finished.
        deadline = time.monotonic() + 300
        while not killed and time.monotonic() < deadline and proc.poll() is None:
            staging = list(out.glob("rec*/.semap-staging-*"))
            if staging:
                time.sleep(2.0)
                kill_worker.send_signal(signal.SIGKILL)
                kill_worker.wait()  # reaped, as a worker's parent would: its PID is then free
                killed = True
            time.sleep(0.2)
    output, _ = proc.communicate(timeout=560)
    return proc.returncode, output, killed


def read_positions(path):
    """timestamp (6 decimals) -> position of a TUM trajectory file."""
    out = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if line and not line.startswith("#"):
            v = line.split()
            out.setdefault("%.6f" % float(v[0]), []).append([float(x) for x in v[1:4]])
    return out


def joint_ate(recordings, merged):
    """All three trajectories of the merged map (the overlaps twice: each recording's own
    estimate), in its world frame, against the ground truth with ONE rigid alignment (TUM ATE)."""
    import numpy as np
    _, gt_path, _ = recordings
    gt = read_positions(gt_path)
    est, ref = [], []
    for k in range(len(SPLITS)):
        for t, positions in read_positions(merged / ("rec%d.trajectory.txt" % (k + 1))).items():
            for p in positions:
                est.append(p)
                ref.append(gt[t][0])
    est, ref = np.array(est), np.array(ref)
    mu_e, mu_r = est.mean(0), ref.mean(0)
    U, _, Vt = np.linalg.svd((ref - mu_r).T @ (est - mu_e))
    D = np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    aligned = (R @ (est - mu_e).T).T + mu_r
    return float(np.sqrt(np.mean(np.sum((aligned - ref) ** 2, axis=1))))


def test_fleet_maps_three_recordings_on_two_workers_and_survives_a_killed_worker(recordings, tmp_path):
    cluster = DaskCluster(tmp_path)
    try:
        t0 = time.monotonic()
        code, output, _ = run_fleet(recordings, tmp_path / "out1", cluster.address)
        wall = time.monotonic() - t0
        assert code == 0, output
        merged = tmp_path / "out1" / "merged"
        ate = joint_ate(recordings, merged)
        print(output)
        print("[fleet] 3 recordings on 2 workers: %.1f s, joint ATE %.2f cm" % (wall, 100 * ate))
        assert ate <= 0.05
        assert json.loads((merged / "fleet.json").read_text())["recordings"] == ["rec1", "rec2", "rec3"]
        assert (tmp_path / "out1" / "rec2" / "map.semap").exists(), "each recording keeps its own output folder"

        code2, output2, killed = run_fleet(recordings, tmp_path / "out2", cluster.address, kill_worker=cluster.workers[0])
        assert killed, output2
        assert code2 == 0, output2
        for k in range(len(SPLITS)):
            name = "rec%d.trajectory.txt" % (k + 1)
            assert (merged / name).read_bytes() == (tmp_path / "out2" / "merged" / name).read_bytes(), \
                "a task rerun after its worker died gives the same map"
        assert not list((tmp_path / "out2").glob("rec*/.semap-staging-*")), "no half-written folder is left"
        print("[fleet] one worker killed mid-task: finished on the other with identical trajectories")
    finally:
        cluster.close()


def test_a_failing_recording_is_reported_and_the_others_still_merge(recordings, tmp_path):
    dirs, _, config = recordings
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "dataset.yaml").write_text("format: tum\ncamera: {fx: 1}\n")  # incomplete camera: a semap error
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "semap.fleet", str(dirs[0]), str(broken), str(dirs[1]), "--out", str(out),
           "--config", str(config), "--segmenter", "none", "--workers", "2", "--retries", "0"]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env(), text=True, timeout=560)
    assert proc.returncode == 0, proc.stdout
    assert "broken failed: Error: %s" % broken in proc.stdout, proc.stdout
    report = json.loads((out / "fleet.json").read_text())
    assert report["components"][0] == ["rec1", "rec2"], report
    assert (out / "merged" / "rec2.trajectory.txt").exists()
