"""Issue 44, class 5: config values that contain themselves or nest absurdly deep raise
ValueError (not a crash of the interpreter); C++ errors reach Python as semap.Error/ValueError,
never as a raw RuntimeError or yaml-cpp text."""
import subprocess
import sys
import textwrap

import pytest

import semap
from conftest import synthetic_camera


def _self_containing_dict():
    d = {"tsdf": {}}
    d["tsdf"]["voxel_size"] = d
    return d


def _self_containing_list():
    items = []
    items.append(items)
    return {"tsdf": {"voxel_size": items}}


def _deep(depth):
    value = 0.05
    for _ in range(depth):
        value = {"x": value}
    return {"tsdf": value}


def _deep_list(depth):
    value = [0.05]
    for _ in range(depth):
        value = [value]
    return {"tsdf": {"voxel_size": value}}


@pytest.mark.parametrize("make", [_self_containing_dict, _self_containing_list,
                                  lambda: _deep(200_000), lambda: _deep_list(200_000)])
def test_recursive_or_deep_config_raises_value_error(make):
    with pytest.raises(ValueError, match="nested more than"):
        semap.Mapper(synthetic_camera(), config=make())
    with pytest.raises(ValueError, match="nested more than"):
        semap.run("/nonexistent-dataset", "/nonexistent-out", config=make())


def test_moderate_nesting_reaches_the_loader_not_the_depth_limit():
    # 10 levels is within the bound: the loader's own message about the unknown key comes back.
    with pytest.raises(ValueError, match="unknown config key"):
        semap.Mapper(synthetic_camera(), config=_deep(10))


def test_interpreter_survives_a_self_containing_config():
    # In a child interpreter, so that a regression shows as a failed test, not a crashed run.
    code = textwrap.dedent("""
        import semap, numpy as np
        d = {}
        d["tsdf"] = d
        try:
            semap.Mapper(semap.Camera(fx=100.0, fy=100.0, cx=39.5, cy=29.5, width=80, height=60), config=d)
        except ValueError as e:
            print("ValueError:", e)
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "ValueError:" in r.stdout


def test_malformed_yaml_file_is_a_semap_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("tsdf: [1, 2\n  voxel_size: {\n")
    with pytest.raises(semap.Error) as info:
        semap.Mapper(synthetic_camera(), config=bad)
    assert type(info.value) is not RuntimeError
    assert "bad.yaml" in str(info.value)


class _BadIndex:
    def __index__(self):
        raise RuntimeError("no index")


class _BadFloat:
    def __float__(self):
        raise RuntimeError("no float")


@pytest.mark.parametrize("value", [_BadIndex(), _BadFloat()])
def test_values_whose_conversion_raises_are_value_errors(value):
    with pytest.raises(ValueError, match="does not convert") as info:
        semap.Mapper(synthetic_camera(), config={"tsdf": {"voxel_size": value}})
    assert "<NULL>" not in str(info.value)
