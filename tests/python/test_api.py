"""semap.Camera, configuration (dict, YAML path, errors), class_names, module basics."""
import re

import numpy as np
import pytest

import semap
from conftest import synthetic_camera


def test_module_exposes_the_contract():
    for name in ("Camera", "Mapper", "open_dataset", "evaluate_ate", "class_names", "to_open3d", "Error"):
        assert hasattr(semap, name), name
    assert re.fullmatch(r"\d+\.\d+\.\d+", semap.__version__)
    assert issubclass(semap.Error, ValueError)


def test_camera_fields_and_validation():
    cam = semap.Camera(fx=535.4, fy=539.2, cx=320.1, cy=247.6, width=640, height=480, depth_scale=5000.0)
    assert (cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height, cam.depth_scale) == (
        535.4, 539.2, 320.1, 247.6, 640, 480, 5000.0)
    np.testing.assert_allclose(cam.K, [[535.4, 0, 320.1], [0, 539.2, 247.6], [0, 0, 1]])
    assert cam.color_size == (640, 480)
    assert "fx=535.4" in repr(cam)
    assert semap.Camera.tum(1).fx == pytest.approx(517.3)
    with pytest.raises(ValueError, match="cx"):  # principal point outside the image
        semap.Camera(fx=500, fy=500, cx=1e6, cy=240, width=640, height=480)
    with pytest.raises(ValueError, match="depth_scale|depth scale"):
        semap.Camera(fx=500, fy=500, cx=320, cy=240, width=640, height=480, depth_scale=0.0)


def test_class_names_and_palette():
    names = semap.class_names()
    assert names[0] == "unlabelled"
    assert "cup" in names and "chair" in names and names[38] == "other"  # ids kept when classes are added
    assert {"curtain", "picture", "rug", "mirror"} <= set(names)  # issue 38: appended after "other"
    assert len(set(names)) == len(names)
    colors = semap.class_colors()
    assert colors.shape == (len(names), 3) and colors.dtype == np.uint8


def test_config_dict_reaches_the_mapper():
    mapper = semap.Mapper(synthetic_camera(), config={"tsdf": {"voxel_size": 0.03}, "pipeline": {"threads": 1}})
    text = mapper.config_yaml()
    assert re.search(r"voxel_size: 0\.03\b", text)
    assert re.search(r"threads: 1\b", text)


def test_config_yaml_path(tmp_path):
    path = tmp_path / "my.yaml"
    path.write_text("tsdf:\n  voxel_size: 0.04\n")
    for config in (str(path), path):
        assert re.search(r"voxel_size: 0\.04\b", semap.Mapper(synthetic_camera(), config=config).config_yaml())


def test_defaults_are_the_clis_with_rgb_mesh_colours():
    python = semap.Mapper(synthetic_camera()).config_yaml().splitlines()
    cli = [line for line in semap.default_config().splitlines() if not line.startswith("# semap configuration")]
    assert python == cli
    assert any(re.match(r"\s*colour_layer: true\b", line) for line in python)
    assert any(re.match(r'\s*mesh_colour: "?rgb"?', line) for line in python)
    # The class palette on request.
    palette = semap.Mapper(synthetic_camera(), config={"tsdf": {"mesh_colour": "class"}})
    assert any(re.match(r'\s*mesh_colour: "?class"?', line) for line in palette.config_yaml().splitlines())


@pytest.mark.parametrize("config, message", [
    ({"tsdf": {"voxel_sise": 0.03}}, r"unknown config key 'tsdf\.voxel_sise'"),
    ({"tsdf": {"voxel_size": -1.0}}, r"config key 'tsdf\.voxel_size' must be"),
    ({"tsdf": {"voxel_size": "big"}}, r"config key 'tsdf\.voxel_size' must be a number"),
    ({"pipeline": {"threads": 2.5}}, r"config key 'pipeline\.threads' must be an integer"),
    ({"tsdf": 3}, r"'tsdf' must be a map"),
    ({"tsdf": {"voxel_size": float("nan")}}, r"finite"),
    ({"tsdf": {1: 2}}, r"keys must be strings"),
    ({"tsdf": {"voxel_size": object()}}, r"value of type"),
])
def test_config_errors_are_the_loaders(config, message):
    with pytest.raises(ValueError, match=message):
        semap.Mapper(synthetic_camera(), config=config)


def test_config_errors_of_files_and_types(tmp_path):
    with pytest.raises(semap.Error, match="missing.yaml"):
        semap.Mapper(synthetic_camera(), config=str(tmp_path / "missing.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("tsdf:\n  nonsense: 1\n")
    with pytest.raises(semap.Error, match=r"bad\.yaml.*unknown config key 'tsdf\.nonsense'"):
        semap.Mapper(synthetic_camera(), config=bad)
    with pytest.raises(ValueError, match="config: expected None, a dict"):
        semap.Mapper(synthetic_camera(), config=3)


def test_segmenter_spec_errors(tmp_path):
    with pytest.raises(semap.Error, match="no_such_model.onnx"):
        semap.Mapper(synthetic_camera(), segmenter="yolo:" + str(tmp_path / "no_such_model.onnx"))
    with pytest.raises(ValueError, match="segmenter: expected None or a spec"):
        semap.Mapper(synthetic_camera(), segmenter=42)
    assert semap.Mapper(synthetic_camera(), segmenter="none").stats()["segmenter"] == "none"
