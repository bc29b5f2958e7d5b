"""semap.to_open3d / Mesh.to_open3d, and the ImportError when Open3D is missing."""
import sys

import numpy as np
import pytest

import semap


@pytest.fixture(scope="module")
def mesh(tum, tum_frames):
    mapper = semap.Mapper(tum.camera, config={"pipeline": {"threads": 1}})
    for f in tum_frames[:3]:
        mapper.add_frame(f.rgb, f.depth, f.timestamp)
    mapper.finish()
    return mapper.mesh()


def test_clear_import_error_without_open3d(mesh, monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)  # makes `import open3d` fail
    with pytest.raises(ImportError, match="python3-open3d"):
        semap.to_open3d(mesh)
    with pytest.raises(ImportError, match="needs Open3D"):
        mesh.to_open3d()


def test_to_open3d(mesh):
    o3d = pytest.importorskip("open3d")
    out = mesh.to_open3d()
    assert isinstance(out, o3d.geometry.TriangleMesh)
    np.testing.assert_allclose(np.asarray(out.vertices), mesh.vertices, rtol=1e-6)
    np.testing.assert_array_equal(np.asarray(out.triangles), mesh.triangles)
    np.testing.assert_allclose(np.asarray(out.vertex_colors) * 255, mesh.colors, atol=1e-3)
    assert out.has_vertex_normals()
    by_class = semap.to_open3d(mesh, colors="class")
    np.testing.assert_allclose(np.asarray(by_class.vertex_colors) * 255, semap.class_colors()[mesh.labels], atol=1e-3)
    assert len(semap.to_open3d(mesh, colors="instance").vertex_colors) == mesh.num_vertices
    with pytest.raises(ValueError, match="colors: expected one of rgb, class, instance"):
        semap.to_open3d(mesh, colors="pink")
