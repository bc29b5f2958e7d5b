"""mapper.objects() with the caller's own segmentation (labels=, instances=) and poses
(pose=): YCB-Video 0000, 10 frames, ground-truth label images and camera poses."""
import io
import json

import numpy as np
import pytest
from PIL import Image

import semap
from conftest import require_data

# Measured: each object's centroid lies 1.3-2.3 cm from its YCB model origin (the visible
# surface only), the nearest other object 8.4 cm or more.
CENTROID_LIMIT_M = 0.04
# YCB ids in this video -> project classes (io/dataset.hpp ycb_to_project_class).
EXPECTED = {"009_gelatin_box": "box", "025_mug": "cup", "061_foam_brick": "box"}


@pytest.fixture(scope="module")
def ycb():
    return semap.open_dataset(require_data("ycb_video_0000"))


@pytest.fixture(scope="module")
def ycb_mapped(ycb):
    mapper = semap.Mapper(ycb.camera, config={"pipeline": {"threads": 1}})
    for i in range(len(ycb)):
        f = ycb[i]
        r = mapper.add_frame(f.rgb, f.depth, f.timestamp, labels=f.labels, instances=f.instances, pose=f.gt_pose)
        assert r.segmented
    mapper.finish()
    return mapper


def ground_truth_objects(ycb):
    """name -> world position of the object's model origin in the first frame."""
    T_world_camera = ycb[0].gt_pose
    out = {}
    for line in (ycb.root / "derived" / "object_poses.txt").read_text().splitlines():
        fields = line.split()
        if fields and fields[0] == "000001":
            t_camera = np.array([float(fields[i]) for i in (6, 10, 14)] + [1.0])
            out[fields[2]] = (T_world_camera @ t_camera)[:3]
    return out


def test_objects_match_the_ground_truth(ycb, ycb_mapped):
    objects = ycb_mapped.objects()
    gt = ground_truth_objects(ycb)
    assert len(gt) == 3 and len(objects) == 3
    matched = set()
    for o in objects:
        name = min(gt, key=lambda n: np.linalg.norm(o.centroid - gt[n]))
        assert np.linalg.norm(o.centroid - gt[name]) < CENTROID_LIMIT_M, (o, name)
        assert o.class_name == EXPECTED[name]
        matched.add(name)
    assert matched == set(gt)


def test_object_fields(ycb_mapped):
    names = semap.class_names()
    for o in ycb_mapped.objects():
        assert o.id > 0 and names[o.class_id] == o.class_name
        assert o.centroid.shape == (3,) and o.extent.shape == (3,) and o.box_rotation.shape == (3, 3)
        assert o.points.shape == (o.point_count, 3) and o.point_count > 50 and o.points.dtype == np.float32
        np.testing.assert_allclose(o.points.mean(axis=0), o.centroid, atol=0.03)
        assert (o.aabb_min <= o.centroid).all() and (o.centroid <= o.aabb_max).all()
        assert ((o.extent > 0.02) & (o.extent < 0.3)).all()  # table-top objects
        assert o.class_distribution[o.class_name] == max(o.class_distribution.values())
        assert set(o.class_distribution) <= set(names)
        entry = json.loads(o.to_json())
        assert entry["id"] == o.id
        assert repr(o).startswith("<semap.Object %d %r" % (o.id, o.class_name))


def test_mesh_carries_the_labels_and_object_ids(ycb_mapped):
    mesh = ycb_mapped.mesh()
    names = semap.class_names()
    labelled = {names[c] for c in np.unique(mesh.labels)}
    assert {"box", "cup"} <= labelled
    ids = set(np.unique(mesh.instances)) - {0}
    assert ids == {o.id for o in ycb_mapped.objects()}


def decoded_view(o):
    """The object's best view (Object.view_jpeg) decoded with Pillow, as an RGB numpy array."""
    image = Image.open(io.BytesIO(o.view_jpeg))
    assert image.format == "JPEG"
    return np.asarray(image.convert("RGB"))


def test_object_view_is_a_small_jpeg_of_the_object(ycb_mapped):
    """Issue 43: each object's best camera view as JPEG bytes; its centre shows the object's own
    colours (nearer to its voxels' mean colour than to any other object's)."""
    objects = ycb_mapped.objects()
    mean_colour = {o.id: o.colors.reshape(-1, 3).astype(float).mean(axis=0) for o in objects}
    for o in objects:
        assert isinstance(o.view_jpeg, bytes) and len(o.view_jpeg) > 0, o
        view = decoded_view(o)
        assert max(view.shape[:2]) <= 96 and min(view.shape[:2]) >= 8, view.shape
        h, w = view.shape[:2]
        centre = view[h // 3: 2 * h // 3, w // 3: 2 * w // 3].reshape(-1, 3).astype(float).mean(axis=0)
        distances = {i: np.linalg.norm(centre - c) for i, c in mean_colour.items()}
        assert min(distances, key=distances.get) == o.id, (o, distances)


def test_object_views_survive_save_and_load(ycb_mapped, tmp_path):
    """The views are kept in map.semap: a loaded map's objects carry the same bytes."""
    ycb_mapped.save(tmp_path / "out")
    loaded = semap.Mapper.load(tmp_path / "out" / "map.semap")
    before = {o.id: o.view_jpeg for o in ycb_mapped.objects()}
    after = {o.id: o.view_jpeg for o in loaded.objects()}
    assert after == before and all(before.values())
