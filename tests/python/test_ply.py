"""PLY outputs read back with plyfile, meshio, Open3D and pymeshlab: sized type names, and
property names for CloudCompare (default) and MeshLab."""

import re

import laspy
import meshio
import numpy as np
import open3d as o3d
import plyfile
import pymeshlab

from conftest import box_points, detect

# The sized names (int16 goes out as int32), and `double`: meshio's binary reader has neither
# `float64` nor any 16-bit signed type.
SIZED = {"int8", "uint8", "uint16", "int32", "uint32", "float32", "double"}


def las_input(path):
    """A LAS cloud: its intensity, point source ID and colours are 16-bit, its scan angle
    signed 16-bit."""
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.scales = [1e-4] * 3
    las = laspy.LasData(header)
    p = box_points(3000)
    las.x, las.y, las.z = p.T
    las.intensity = np.arange(len(p), dtype=np.uint16)
    las.scan_angle = (np.arange(len(p)) % 100 - 50).astype(np.int16)
    las.red = las.green = las.blue = np.full(len(p), 40000, dtype=np.uint16)
    las.write(str(path))


def ply_types(path):
    head = path.read_bytes().split(b"end_header")[0].decode()
    return re.findall(r"^property (\w+) (\w+)$", head, re.M)


def test_types_use_sized_names_that_open3d_and_meshio_read(tmp_path):
    src, out = tmp_path / "scan.las", tmp_path / "out.ply"
    las_input(src)
    detect(src, out)
    types = ply_types(out)
    assert {t for t, _ in types} <= SIZED, types
    mesh = meshio.read(out)
    assert len(mesh.points) == 3000
    assert np.array_equal(mesh.point_data["intensity"], np.arange(3000))
    assert np.array_equal(mesh.point_data["scan_angle"], np.arange(3000) % 100 - 50)
    cloud = o3d.t.io.read_point_cloud(str(out))
    assert cloud.point.positions.shape[0] == 3000
    assert np.array_equal(cloud.point["intensity"].numpy().ravel(), np.arange(3000))
    assert set(cloud.point["scalar_class"].numpy().ravel()) <= {0, 1, 2}


def test_default_names_are_cloudcompare_scalar_fields(tmp_path):
    p = box_points(3000).astype(np.float32)
    src, out = tmp_path / "box.ply", tmp_path / "out.ply"
    vertex = np.zeros(len(p), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vertex["x"], vertex["y"], vertex["z"] = p.T
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex")]).write(str(src))
    detect(src, out)
    v = plyfile.PlyData.read(str(out))["vertex"].data
    names = v.dtype.names
    for name in ["scalar_class", "scalar_p_nonedge", "scalar_p_sharp", "scalar_p_boundary"]:
        assert name in names, names
    assert np.array_equal(np.stack([v["x"], v["y"], v["z"]], 1), p)
    p_sum = v["scalar_p_nonedge"] + v["scalar_p_sharp"] + v["scalar_p_boundary"]
    assert np.allclose(p_sum, 1.0, atol=1e-5)
    # A colourless input gets class colours, which Open3D's legacy reader shows.
    legacy = o3d.io.read_point_cloud(str(out))
    assert legacy.has_colors() and len(legacy.points) == 3000
    sharp = v["scalar_class"] == 1
    assert sharp.any() and np.all(v["red"][sharp] == 255)


def test_meshlab_flavour_loads_as_vertex_quality(tmp_path):
    p = box_points(3000).astype(np.float32)
    src, out = tmp_path / "box.ply", tmp_path / "out.ply"
    vertex = np.zeros(len(p), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vertex["x"], vertex["y"], vertex["z"] = p.T
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex")]).write(str(src))
    detect(src, out, "--flavour", "meshlab")
    v = plyfile.PlyData.read(str(out))["vertex"].data
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(out))
    mesh = ms.current_mesh()
    assert mesh.has_vertex_scalar()
    assert np.array_equal(mesh.vertex_scalar_array().astype(np.float32), v["p_sharp"])
