"""PCD outputs read back with pypcd4: f32 positions that PCL's PointXYZ tools load, and a
float32 class that `pcl_passthrough_filter` filters (it reads the filter field as FLOAT32)."""

import numpy as np
import plyfile
import pypcd4

from conftest import box_points, detect


def test_positions_and_class_are_float32(tmp_path):
    p = box_points(3000).astype(np.float32)
    src, out = tmp_path / "box.ply", tmp_path / "out.pcd"
    vertex = np.zeros(len(p), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vertex["x"], vertex["y"], vertex["z"] = p.T
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex")]).write(str(src))
    detect(src, out)
    pc = pypcd4.PointCloud.from_path(out)
    fields = dict(zip(pc.fields, pc.types))
    for name in ["x", "y", "z", "class"]:
        assert np.dtype(fields[name]) == np.float32, fields
    assert np.array_equal(pc.numpy(("x", "y", "z")), p)
    assert set(np.unique(pc.numpy(("class",)))) <= {0.0, 1.0, 2.0}


def test_decimal_positions_exact_in_float32_are_float32(tmp_path):
    # Multiples of 1/1024 below 2 are single floats exactly.
    p = np.round(box_points(3000) * 1024) / 1024
    src, out = tmp_path / "box.xyz", tmp_path / "out.pcd"
    np.savetxt(src, p, fmt="%.10f")
    detect(src, out)
    pc = pypcd4.PointCloud.from_path(out)
    assert np.dtype(dict(zip(pc.fields, pc.types))["x"]) == np.float32
    assert np.array_equal(pc.numpy(("x", "y", "z")).astype(np.float64), p)


def test_decimals_of_single_floats_are_float32(tmp_path):
    # A text cloud's 6-decimal coordinates: each the shortest decimal of a single float.
    p = box_points(3000)
    src, out = tmp_path / "box.xyz", tmp_path / "out.pcd"
    np.savetxt(src, p, fmt="%.6f")
    detect(src, out)
    pc = pypcd4.PointCloud.from_path(out)
    assert np.dtype(dict(zip(pc.fields, pc.types))["x"]) == np.float32
    xyz = pc.numpy(("x", "y", "z"))
    assert np.array_equal(xyz, np.round(p, 6).astype(np.float32))
    assert [f"{v:.6f}" for v in xyz[:100].ravel()] == [f"{v:.6f}" for v in p[:100].ravel()]


def test_positions_that_need_doubles_stay_doubles(tmp_path):
    p = box_points(3000) + [500_000.0, 5_400_000.0, 0.0]
    src, out = tmp_path / "utm.xyz", tmp_path / "out.pcd"
    np.savetxt(src, p, fmt="%.3f")
    detect(src, out)
    pc = pypcd4.PointCloud.from_path(out)
    fields = dict(zip(pc.fields, pc.types))
    assert np.dtype(fields["x"]) == np.float64
    assert np.array_equal(pc.numpy(("x", "y", "z")), np.round(p, 3))
