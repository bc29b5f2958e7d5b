"""Issue 39: the occupancy grid opens with yaml + OpenCV or Pillow exactly as ROS map_server reads it
(origin in metres, occupied = black), the distance field with numpy, and the scene graph through
semap.load_scene_graph. One `semap run` of a small synthetic world (ground-truth labels)."""
import subprocess

import numpy as np
import pytest

import semap
from conftest import BUILD, skip_or_fail


def _imports():
    try:
        import cv2
        import yaml
    except ImportError as e:  # python3-yaml / python3-opencv (scripts/install-deps.sh)
        skip_or_fail("missing Python package: %s" % e)
    return yaml, cv2


@pytest.fixture(scope="module")
def run_out(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("navigation")
    subprocess.run([str(BUILD / "semap"), "synth", "--out", str(tmp / "data"), "--frames", "40", "--objects", "6",
                    "--width", "160", "--height", "120", "--seed", "5"], check=True, capture_output=True)
    report = semap.run(tmp / "data", tmp / "out", segmenter="groundtruth", evaluate=False,
                       config={"tsdf": {"voxel_size": 0.04}})
    return tmp / "out", report


def first_ground_truth_pose(path):
    """The first pose of a TUM ground-truth file (tx ty tz qx qy qz qw) as a 4x4 matrix."""
    row = next(line for line in path.read_text().splitlines() if not line.startswith("#")).split()
    t = np.array([float(v) for v in row[1:4]])
    x, y, z, w = (float(v) for v in row[4:8])
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = t
    return T


def map_server_load(yaml_path, yaml, cv2):
    """What map_server does (trinary mode): p = (255 - v) / 255 for negate 0; occupied above
    occupied_thresh, free below free_thresh, else unknown. Returns (states, meta), states with
    row 0 at the origin (lowest y): 100 occupied, 0 free, -1 unknown."""
    meta = yaml.safe_load(yaml_path.read_text())
    image = cv2.imread(str(yaml_path.parent / meta["image"]), cv2.IMREAD_UNCHANGED)
    assert image.dtype == np.uint8 and image.ndim == 2
    p = (255.0 - image) / 255.0
    if meta["negate"]:
        p = 1.0 - p
    states = np.full(image.shape, -1, np.int8)
    states[p > meta["occupied_thresh"]] = 100
    states[p < meta["free_thresh"]] = 0
    return states[::-1], meta


def test_grid_loads_like_map_server(run_out):
    yaml, cv2 = _imports()
    out, report = run_out
    states, meta = map_server_load(out / "map.yaml", yaml, cv2)
    assert len(meta["origin"]) == 3 and meta["resolution"] == pytest.approx(report["navigation"]["resolution_m"])
    cell_m2 = meta["resolution"] ** 2
    assert (states == 0).sum() * cell_m2 == pytest.approx(report["navigation"]["free_m2"])
    assert (states == 100).sum() * cell_m2 == pytest.approx(report["navigation"]["occupied_m2"])
    assert (states == 0).sum() > 100 and (states == 100).sum() > 20
    # The synthetic room's floor spans x, y in [0, 6] x [0, 5] of the scene frame S (scene.json).
    # The run's world W is its first camera's frame (trajectory.txt starts at the identity), so
    # S from W is the first ground-truth pose; free cells go G -> W -> S.
    T_W_G = np.array(meta["T_W_G"]).reshape(4, 4)
    T_S_W = first_ground_truth_pose(out.parent / "data" / "groundtruth.txt")
    iy, ix = np.nonzero(states == 0)
    xy_G = np.stack([meta["origin"][0] + (ix + 0.5) * meta["resolution"],
                     meta["origin"][1] + (iy + 0.5) * meta["resolution"], np.zeros(ix.size), np.ones(ix.size)])
    xy_S = (T_S_W @ T_W_G @ xy_G)[:3]
    inside = (xy_S[0] > -0.1) & (xy_S[0] < 6.1) & (xy_S[1] > -0.1) & (xy_S[1] < 5.1)
    assert inside.mean() > 0.99
    labels = cv2.cvtColor(cv2.imread(str(out / meta["labels_image"]), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    assert labels.shape == states.shape + (3,)
    palette = {tuple(e["rgb"]) for e in meta["label_palette"]}
    seen = {tuple(c) for c in labels.reshape(-1, 3)[::7]} - {(0, 0, 0)}
    assert seen and seen <= palette


def test_grid_loads_with_pillow_like_map_server(run_out):
    """map_server reads the image with SDL_image; Pillow (python3-pil) is the usual Python
    stand-in: an 8-bit grey image whose map_server states equal those read through OpenCV, with
    the yaml's origin in metres (the lower-left cell's corner) and occupied = black (0)."""
    yaml, cv2 = _imports()
    try:
        from PIL import Image
    except ImportError as e:
        skip_or_fail("missing Python package: %s" % e)
    out, _ = run_out
    meta = yaml.safe_load((out / "map.yaml").read_text())
    image = Image.open(out / meta["image"])
    assert image.mode == "L" and image.format == "PPM"
    pixels = np.asarray(image)
    p = (255.0 - pixels) / 255.0  # negate 0
    states = np.full(pixels.shape, -1, np.int8)
    states[p > meta["occupied_thresh"]] = 100
    states[p < meta["free_thresh"]] = 0
    expected, _ = map_server_load(out / "map.yaml", yaml, cv2)
    assert np.array_equal(states[::-1], expected)
    assert set(np.unique(pixels)) <= {0, 205, 254} and (pixels == 0).any()
    assert all(isinstance(v, (int, float)) for v in meta["origin"]) and meta["origin"][2] == 0.0


def test_distance_field_and_scene_graph(run_out):
    yaml, cv2 = _imports()
    out, _ = run_out
    states, meta = map_server_load(out / "map.yaml", yaml, cv2)
    esdf_meta = yaml.safe_load((out / "esdf.yaml").read_text())
    assert esdf_meta["origin"] == meta["origin"] and esdf_meta["resolution"] == meta["resolution"]
    esdf = np.load(out / esdf_meta["image"])[::-1]
    assert esdf.dtype == np.float32 and esdf.shape == states.shape
    assert np.all(esdf[states == 100] == 0) and np.all(esdf[states == 0] >= meta["resolution"] * 0.99)
    graph = semap.load_scene_graph(out)
    assert graph["frame"] == "gravity" and graph["objects"]
    on = [e for e in graph["edges"] if e["relation"] == "on"]
    assert on and all("gap_m" in e["evidence"] for e in on)
    # Structural nodes and places: the floor, the synthetic room's walls, one place (one room).
    kinds = [s["kind"] for s in graph["surfaces"]]
    assert kinds.count("floor") == 1 and kinds.count("wall") >= 1
    assert all("evidence" in s for s in graph["surfaces"])
    assert len(graph["places"]) == 1
    assert not [e for e in graph["edges"] if e["target"].startswith(("wall", "ceiling"))]
    assert {"scene_graph.json", "map.pgm", "map.yaml", "esdf.npy", "map_labels.png"} <= set(
        p.name for p in out.iterdir())
    with pytest.raises(semap.Error):
        semap.load_scene_graph(out / "map.yaml")
