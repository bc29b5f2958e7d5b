"""add_frame() inputs: every wrong dtype/shape/size is a ValueError naming the argument; every
accepted layout (RGB, BGR, reversed-channel views, strided, Fortran order, raw or metric depth)
gives the same map as the plain one."""
import gc

import numpy as np
import pytest

import semap
from conftest import synthetic_camera, synthetic_frame

H, W = 60, 80


@pytest.fixture
def mapper():
    return semap.Mapper(synthetic_camera(), config={"pipeline": {"threads": 1}})


@pytest.fixture
def frame():
    return synthetic_frame(synthetic_camera())


BAD_RGB = [
    (np.zeros((H, W), np.uint8), r"rgb: expected a uint8 array of shape \(60, 80, 3\) in RGB order.*"
                                 r"got uint8 array of shape \(60, 80\)"),
    (np.zeros((H, W, 3), np.float32), r"rgb: .*got float32 array of shape \(60, 80, 3\)"),
    (np.zeros((H + 1, W, 3), np.uint8), r"rgb: .*got uint8 array of shape \(61, 80, 3\)"),
    (np.zeros((W, H, 3), np.uint8), r"rgb: .*got uint8 array of shape \(80, 60, 3\)"),
    (np.zeros((H, W, 4), np.uint8), r"rgb: .*\(60, 80, 4\)"),
    ([[0, 0, 0]], r"rgb: .*got list"),
    (None, r"rgb: .*got NoneType"),
]


@pytest.mark.parametrize("rgb, message", BAD_RGB)
def test_bad_rgb(mapper, frame, rgb, message):
    with pytest.raises(ValueError, match=message):
        mapper.add_frame(rgb, frame[1], 0.0)


BAD_DEPTH = [
    (np.zeros((H, W), np.float64), r"depth: expected a uint16 \(raw units.*\) or float32 \(metres\) array of shape "
                                   r"\(60, 80\).*got float64 array of shape \(60, 80\)"),
    (np.zeros((H, W), np.int32), r"depth: .*got int32"),
    (np.zeros((H, W, 1), np.float32), r"depth: .*got float32 array of shape \(60, 80, 1\)"),
    (np.zeros((H, W + 2), np.uint16), r"depth: .*got uint16 array of shape \(60, 82\)"),
    (np.zeros((W * H,), np.float32), r"depth: .*shape \(4800,\)"),
    (None, r"depth: .*got NoneType"),
]


@pytest.mark.parametrize("depth, message", BAD_DEPTH)
def test_bad_depth(mapper, frame, depth, message):
    with pytest.raises(ValueError, match=message):
        mapper.add_frame(frame[0], depth, 0.0)


def test_bad_labels_instances_pose_timestamp(mapper, frame):
    rgb, depth = frame
    labels = np.zeros((H, W), np.uint8)
    cases = [
        (dict(labels=np.zeros((H, W), np.int64)), r"labels: expected None or a uint8 .* got int64"),
        (dict(labels=np.zeros((H // 2, W), np.uint8)), r"labels: .*shape \(30, 80\)"),
        (dict(labels=np.full((H, W), 250, np.uint8)), r"labels: class id 250 is not a project class"),
        (dict(labels=labels, instances=np.zeros((H, W), np.int32)), r"instances: expected None or a uint16"),
        (dict(instances=np.zeros((H, W), np.uint16)), r"instances: given without labels"),
        (dict(pose=np.eye(3)), r"pose: expected a rigid 4x4 transform.*got float64 array of shape \(3, 3\)"),
        (dict(pose=np.diag([2.0, 1, 1, 1])), r"pose: not a rigid transform"),
        (dict(pose=np.diag([-1.0, 1, 1, 1])), r"pose: not a rigid transform"),  # a reflection
        (dict(pose=np.full((4, 4), np.nan)), r"pose: NaN or Inf"),
        (dict(pose="identity"), r"pose: expected a rigid 4x4"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError, match=message):
            mapper.add_frame(rgb, depth, 0.0, **kwargs)
    with pytest.raises(ValueError, match="timestamp"):
        mapper.add_frame(rgb, depth, float("nan"))
    with pytest.raises(TypeError):
        mapper.add_frame(rgb, depth, "noon")
    # Nothing of the rejected calls reached the map.
    assert mapper.stats()["frames"] == 0
    mapper.add_frame(rgb, depth, 0.0)
    assert mapper.stats()["frames"] == 1


def test_wrong_size_for_a_camera_with_another_resolution(frame):
    cam = semap.Camera(fx=500, fy=500, cx=319.5, cy=239.5, width=640, height=480)
    with pytest.raises(ValueError, match=r"rgb: .*\(480, 640, 3\).*got uint8 array of shape \(60, 80, 3\)"):
        semap.Mapper(cam).add_frame(*frame, 0.0)


def map_layouts(camera, frames, make_args):
    """Poses and mesh of a run fed through make_args(rgb, depth) -> (rgb, depth, kwargs)."""
    mapper = semap.Mapper(camera, config={"pipeline": {"threads": 1}})
    results = []
    for i, (rgb, depth) in enumerate(frames):
        r, d, kwargs = make_args(rgb, depth)
        results.append(mapper.add_frame(r, d, 0.1 * i, **kwargs))
    mapper.finish()
    mesh = mapper.mesh()
    return results, mesh.vertices.copy(), mesh.colors.copy()


def test_every_accepted_layout_gives_the_same_map(tum, tum_frames):
    """Real frames (tracked, not lost): each layout must give bit-identical poses and mesh."""
    frames = [(f.rgb, f.depth) for f in tum_frames[:4]]
    results, ref_vertices, ref_colors = map_layouts(tum.camera, frames, lambda rgb, depth: (rgb, depth, {}))
    ref_poses = np.array([r.pose for r in results])
    assert [r.status for r in results].count("lost") == 0
    assert np.linalg.norm(ref_poses[-1][:3, 3]) > 0.005, "the camera moved"
    assert len(ref_vertices) > 1000 and ref_colors.std() > 10, "mesh with the images' colours"
    w = tum.camera.width
    layouts = {
        "bgr": lambda rgb, depth: (np.ascontiguousarray(rgb[..., ::-1]), depth, {"bgr": True}),
        "reversed view": lambda rgb, depth: (np.ascontiguousarray(rgb[..., ::-1])[..., ::-1], depth, {}),
        "reversed view, bgr": lambda rgb, depth: (rgb[..., ::-1], depth, {"bgr": True}),
        "strided rows": lambda rgb, depth: (np.pad(rgb, ((0, 0), (0, 5), (0, 0)))[:, :w],
                                            np.pad(depth, ((0, 0), (0, 3)))[:, :w], {}),
        "fortran order": lambda rgb, depth: (np.asfortranarray(rgb), np.asfortranarray(depth), {}),
        "raw depth": lambda rgb, depth: (rgb, np.round(depth * tum.camera.depth_scale).astype(np.uint16), {}),
    }
    for name, make_args in layouts.items():
        results, vertices, colors = map_layouts(tum.camera, frames, make_args)
        np.testing.assert_array_equal(np.array([r.pose for r in results]), ref_poses, err_msg=name)
        np.testing.assert_array_equal(vertices, ref_vertices, err_msg=name)
        np.testing.assert_array_equal(colors, ref_colors, err_msg=name)


def test_invalid_float_depth_is_treated_as_missing():
    cam = synthetic_camera()
    rgb, depth = synthetic_frame(cam)
    holes = depth.copy()
    holes[:, :20] = np.nan
    holes[:10] = -1.0
    holes[-5:] = np.inf
    zeros = depth.copy()
    zeros[:, :20] = 0
    zeros[:10] = 0
    zeros[-5:] = 0
    meshes = []
    for d in (holes, zeros):
        mapper = semap.Mapper(cam, config={"pipeline": {"threads": 1}})
        mapper.add_frame(rgb, d, 0.0)
        mapper.finish()
        meshes.append(mapper.mesh().vertices)
    np.testing.assert_array_equal(meshes[0], meshes[1])
    assert np.isnan(holes).any(), "the caller's array is not modified"


def test_arrays_outlive_the_caller_in_a_threaded_mapper():
    """The Mapper keeps references to the arrays (queues, keyframes): deleting them on the Python
    side right after add_frame must not free memory the worker threads still read."""
    cam = synthetic_camera()
    mapper = semap.Mapper(cam, config={"pipeline": {"threads": 4}})
    for i in range(12):
        rgb, depth = synthetic_frame(cam, shift_m=0.005 * i)
        pose = np.eye(4)
        pose[0, 3] = 0.005 * i
        mapper.add_frame(rgb[..., ::-1].copy()[..., ::-1], depth, 0.1 * i, pose=pose)
        del rgb, depth
        gc.collect()
    mapper.finish()
    assert mapper.mesh().num_vertices > 100
    assert mapper.stats()["frames_fused"] == 12
