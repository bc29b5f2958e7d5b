#!/usr/bin/env python3
"""Maps a TUM RGB-D sequence with semap from Python; the frames are read with OpenCV.

    PYTHONPATH=build/python python3 examples/python/map_tum.py ../shared/data/tum_fr1_rpy /tmp/out [--show]

DATASET is a TUM folder (rgb.txt, depth.txt, rgb/, depth/, optionally groundtruth.txt). The
program associates colour and depth by timestamp (as the benchmark's associate.py), feeds
every pair to semap.Mapper, prints the absolute trajectory error when ground truth exists,
writes what `semap run` writes (trajectory.txt, mesh.ply, objects.json, map.semap) into OUT
and, with --show, opens the mesh in Open3D.
"""
import argparse
import bisect
import json
import pathlib
import re
import sys
import time

import cv2
import numpy as np

import semap

# TUM RGB-D intrinsics per camera (https://cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats).
TUM_INTRINSICS = {1: (517.3, 516.5, 318.6, 255.3), 2: (520.9, 521.0, 325.1, 249.7), 3: (535.4, 539.2, 320.1, 247.6)}
# Their lens distortion (k1 k2 p1 p2 k3): the Mapper undistorts the frames it is given.
TUM_DISTORTION = {1: (0.2624, -0.9531, -0.0054, 0.0026, 1.1633), 2: (0.2312, -0.7849, -0.0033, -0.0001, 0.9172),
                  3: (0, 0, 0, 0, 0)}


def read_file_list(path):
    """[(timestamp, relative path)] of a TUM list file (rgb.txt, depth.txt); '#' lines are comments."""
    entries = []
    for line in pathlib.Path(path).read_text().splitlines():
        fields = line.split()
        if fields and not fields[0].startswith("#") and len(fields) >= 2:
            entries.append((float(fields[0]), fields[1]))
    return entries


def associate(rgb, depth, max_dt=0.02):
    """Greedy one-to-one matching of the closest timestamps (TUM associate.py), in rgb order."""
    depth = sorted(depth)
    depth_times = [t for t, _ in depth]
    candidates = []
    for i, (a, _) in enumerate(rgb):
        j = bisect.bisect_left(depth_times, a - max_dt)
        while j < len(depth) and depth_times[j] < a + max_dt:
            candidates.append((abs(a - depth_times[j]), i, j))
            j += 1
    candidates.sort()
    used_rgb, used_depth, pairs = set(), set(), []
    for _, i, j in candidates:
        if i not in used_rgb and j not in used_depth:
            used_rgb.add(i)
            used_depth.add(j)
            pairs.append((i, j))
    return [(rgb[i][0], rgb[i][1], depth[j][1]) for i, j in sorted(pairs)]


def camera_for(dataset, depth_scale=5000.0):
    """The TUM camera of the sequence's name (freiburg1/2/3, fr1/2/3); freiburg 1 otherwise."""
    match = re.search(r"(?:freiburg|fr)([123])", dataset.name)
    freiburg = int(match.group(1)) if match else 1
    fx, fy, cx, cy = TUM_INTRINSICS[freiburg]
    return semap.Camera(fx=fx, fy=fy, cx=cx, cy=cy, width=640, height=480, depth_scale=depth_scale,
                        distortion=TUM_DISTORTION[freiburg])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=pathlib.Path, help="TUM RGB-D folder")
    parser.add_argument("out", type=pathlib.Path, help="output folder")
    parser.add_argument("--config", help="semap YAML config (see `semap config --dump`)")
    parser.add_argument("--segmenter", help="yolo:MODEL.onnx | semantic:MODEL.onnx | none")
    parser.add_argument("--threads", type=int, default=None, help="pipeline.threads (1: deterministic)")
    parser.add_argument("--max-frames", type=int, default=0, help="map only the first N frames")
    parser.add_argument("--show", action="store_true", help="show the mesh with Open3D")
    args = parser.parse_args(argv)

    for name in ("rgb.txt", "depth.txt"):
        if not (args.dataset / name).is_file():
            sys.exit("map_tum: %s not found (DATASET must be a TUM RGB-D folder)" % (args.dataset / name))
    pairs = associate(read_file_list(args.dataset / "rgb.txt"), read_file_list(args.dataset / "depth.txt"))
    if args.max_frames:
        pairs = pairs[:args.max_frames]
    if not pairs:
        sys.exit("map_tum: no associated colour/depth pairs in %s" % args.dataset)
    if args.config and args.threads:
        parser.error("--threads goes into the YAML file when --config is given")
    config = args.config or ({"pipeline": {"threads": args.threads}} if args.threads else None)
    mapper = semap.Mapper(camera_for(args.dataset), config=config, segmenter=args.segmenter)

    read_s = add_s = binding_ms = 0.0
    lost = 0
    start = time.perf_counter()
    for timestamp, rgb_file, depth_file in pairs:
        t0 = time.perf_counter()
        bgr = cv2.imread(str(args.dataset / rgb_file), cv2.IMREAD_COLOR)
        depth = cv2.imread(str(args.dataset / depth_file), cv2.IMREAD_UNCHANGED)  # uint16, 1/5000 m
        if bgr is None or depth is None:
            sys.exit("map_tum: cannot read %s or %s" % (rgb_file, depth_file))
        t1 = time.perf_counter()
        rgb = bgr[:, :, ::-1]  # RGB view of OpenCV's BGR image (semap takes it without a copy)
        result = mapper.add_frame(rgb, depth, timestamp)
        add_s += time.perf_counter() - t1
        read_s += t1 - t0
        binding_ms += result.binding_ms
        lost += result.status == "lost"
    online_s = time.perf_counter() - start
    mapper.finish()
    mapper.save(args.out)
    total_s = time.perf_counter() - start

    n = len(pairs)
    mesh = mapper.mesh()
    summary = {
        "frames": n,
        "lost": lost,
        "fps_online": n / online_s,
        "fps_end_to_end": n / total_s,
        "read_ms_per_frame": 1000 * read_s / n,
        "add_frame_ms_per_frame": 1000 * add_s / n,
        "binding_ms_per_frame": binding_ms / n,
        "mesh_vertices": mesh.num_vertices,
        "objects": len(mapper.objects()),
    }
    ground_truth = args.dataset / "groundtruth.txt"
    if ground_truth.exists():
        summary["ate_rmse_m"] = semap.evaluate_ate(ground_truth, args.out / "trajectory.txt")["rmse_m"]
    print("map_tum: %d frames (%d lost), %.1f fps online, %.1f fps end to end, binding %.2f ms/frame" % (
        n, lost, summary["fps_online"], summary["fps_end_to_end"], summary["binding_ms_per_frame"]))
    if "ate_rmse_m" in summary:
        print("map_tum: ATE RMSE %.4f m" % summary["ate_rmse_m"])
    print("map_tum: %d mesh vertices, %d objects -> %s" % (mesh.num_vertices, summary["objects"], args.out))
    (args.out / "map_tum.json").write_text(json.dumps(summary, indent=2) + "\n")

    if args.show:
        import open3d as o3d  # noqa: E402  (optional: only for --show)
        o3d.visualization.draw_geometries([mesh.to_open3d()], window_name="semap: " + args.dataset.name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
