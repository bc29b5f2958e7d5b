"""`cmake --install` puts an importable semap package under the prefix (component python)."""
import os
import pathlib
import subprocess
import sys
import textwrap

import pytest

from conftest import BUILD, skip_or_fail

SCRIPT = textwrap.dedent("""
    import numpy as np, semap
    print(semap.__file__)
    cam = semap.Camera(fx=100, fy=100, cx=39.5, cy=29.5, width=80, height=60, depth_scale=1000.0)
    mapper = semap.Mapper(cam, config={"pipeline": {"threads": 1}})
    depth = np.full((60, 80), 1.2, np.float32)
    r = mapper.add_frame(np.full((60, 80, 3), 200, np.uint8), depth, 0.0)
    mapper.finish()
    mesh = mapper.mesh()
    assert r.status == "keyframe" and mesh.num_vertices > 100, mesh
    assert abs(float(np.median(mesh.vertices[:, 2])) - 1.2) < 0.05
    print("ok", mesh.num_vertices)
""")


def test_install_and_import_from_the_prefix(tmp_path):
    cmake = os.environ.get("CMAKE_COMMAND", "cmake")
    if not (BUILD / "cmake_install.cmake").exists():
        skip_or_fail("no configured build folder at %s" % BUILD)
    prefix = tmp_path / "prefix"
    subprocess.run([cmake, "--install", str(BUILD), "--prefix", str(prefix), "--component", "python"], check=True,
                   capture_output=True)
    packages = sorted(prefix.glob("lib/python3*/*-packages/semap"))
    assert len(packages) == 1, list(prefix.rglob("*"))
    package = packages[0]
    assert (package / "__init__.py").exists() and list(package.glob("_semap*.so"))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(package.parent)
    run = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=300)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert pathlib.Path(lines[0]).resolve().is_relative_to(prefix.resolve())
    assert lines[1].startswith("ok")
