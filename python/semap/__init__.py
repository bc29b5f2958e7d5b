"""semap: RGB-D semantic mapping with numpy in and out.

    import semap
    cam = semap.Camera(fx=535.4, fy=539.2, cx=320.1, cy=247.6, width=640, height=480, depth_scale=5000.0)
    mapper = semap.Mapper(cam)                      # config=dict|path, segmenter="yolo:model.onnx"
    r = mapper.add_frame(rgb, depth, timestamp)     # rgb uint8 HxWx3 RGB; depth uint16 raw or float32 m
    mapper.finish()
    mesh = mapper.mesh()                            # .vertices .triangles .colors .labels .instances

The compiled core is semap._semap (C++, pybind11); this file adds the pure-Python parts:
Open3D conversion and readable reprs. Errors from the core (bad files, config keys, cameras)
are semap.Error, a ValueError; wrong arrays are ValueErrors naming the argument.
"""

import numpy as _np

from ._semap import (  # noqa: F401  (the public API)
    Camera,
    Dataset,
    DatasetFrame,
    Error,
    FrameResult,
    Mapper,
    Mesh,
    Object,
    __version__,
    class_colors,
    class_names,
    default_config,
    evaluate_ate,
    evaluate_rpe,
    load_scene_graph,
    merge_maps,
    open_dataset,
    run,
)

__all__ = [
    "Camera", "Dataset", "DatasetFrame", "Error", "FrameResult", "Mapper", "Mesh", "Object",
    "class_colors", "class_names", "default_config", "evaluate_ate", "evaluate_rpe", "load_scene_graph", "merge_maps",
    "open_dataset", "run", "to_open3d",
]

_COLOR_MODES = ("rgb", "class", "instance")


def _vertex_colors(mesh, colors):
    """(N, 3) float64 in [0, 1] for to_open3d, or None."""
    if colors not in _COLOR_MODES:
        raise ValueError("colors: expected one of %s, got %r" % (", ".join(_COLOR_MODES), colors))
    if colors == "rgb":
        rgb = mesh.colors
    elif colors == "class":
        rgb = None if mesh.labels is None else class_colors()[mesh.labels]
    else:
        ids = mesh.instances
        # A fixed pseudo-random colour per object id; grey for "no object" (0).
        rgb = None
        if ids is not None:
            rgb = _np.stack([(ids * 97) % 200 + 55, (ids * 57) % 200 + 55, (ids * 31) % 200 + 55], axis=1)
            rgb[ids == 0] = 128
    return None if rgb is None else _np.asarray(rgb, dtype=_np.float64) / 255.0


def to_open3d(mesh, colors="rgb"):
    """The mesh as an open3d.geometry.TriangleMesh (needs Open3D's Python package).

    colors: "rgb" (the surfaces' colours), "class" (the class palette, semap.class_colors())
    or "instance" (one colour per object).
    """
    try:
        import open3d as o3d
    except ImportError as e:
        raise ImportError(
            "semap.to_open3d needs Open3D's Python package: apt install python3-open3d "
            "(Debian/Ubuntu) or pip install open3d") from e
    vertex_colors = _vertex_colors(mesh, colors)
    out = o3d.geometry.TriangleMesh()
    out.vertices = o3d.utility.Vector3dVector(_np.asarray(mesh.vertices, dtype=_np.float64))
    out.triangles = o3d.utility.Vector3iVector(_np.asarray(mesh.triangles, dtype=_np.int32))
    if vertex_colors is not None:
        out.vertex_colors = o3d.utility.Vector3dVector(vertex_colors)
    if mesh.normals is not None:
        out.vertex_normals = o3d.utility.Vector3dVector(_np.asarray(mesh.normals, dtype=_np.float64))
    elif len(mesh.triangles):
        out.compute_vertex_normals()
    return out


Mesh.to_open3d = to_open3d


def _xyz(v):
    return "[%.3f, %.3f, %.3f]" % tuple(v)


def _camera_repr(c):
    return "semap.Camera(fx=%g, fy=%g, cx=%g, cy=%g, width=%d, height=%d, depth_scale=%g)" % (
        c.fx, c.fy, c.cx, c.cy, c.width, c.height, c.depth_scale)


def _result_repr(r):
    return "<semap.FrameResult frame %d t=%.3f %s at %s>" % (
        r.frame_index, r.timestamp, r.status, _xyz(r.pose[:3, 3]))


def _mesh_repr(m):
    parts = [name for name in ("colors", "labels", "instances") if getattr(m, name) is not None]
    return "<semap.Mesh %d vertices, %d triangles%s>" % (
        m.num_vertices, m.num_triangles, (", " + ", ".join(parts)) if parts else "")


def _object_repr(o):
    return "<semap.Object %d %r, %d points at %s, extent %s>" % (
        o.id, o.class_name, o.point_count, _xyz(o.centroid), _xyz(o.extent))


def _dataset_repr(d):
    return "<semap.Dataset %s, %d frames, %r>" % (d.format, len(d), str(d.root))


def _frame_repr(f):
    h, w = f.depth.shape
    return "<semap.DatasetFrame %d t=%.6f %dx%d%s>" % (
        f.index, f.timestamp, w, h, "" if f.gt_pose is None else " with gt_pose")


def _mapper_repr(m):
    s = m.stats()
    return "<semap.Mapper %d frames, %d keyframes%s>" % (
        s["frames"], s["keyframes"], ", finished" if s["finished"] else "")


Camera.__repr__ = _camera_repr
FrameResult.__repr__ = _result_repr
Mesh.__repr__ = _mesh_repr
Object.__repr__ = _object_repr
Dataset.__repr__ = _dataset_repr
DatasetFrame.__repr__ = _frame_repr
Mapper.__repr__ = _mapper_repr
