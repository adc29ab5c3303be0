""".npy inputs written by NumPy: float32 / float64, C or Fortran order, extra columns kept."""

import numpy as np
import plyfile

from conftest import box_points, detect


def test_npy_inputs_in_every_layout(tmp_path):
    p = box_points(3000)
    extra = np.arange(len(p), dtype=np.float64)[:, None]
    for dtype in [np.float32, np.float64]:
        for order in ["C", "F"]:
            a = np.asarray(np.hstack([p, extra]), dtype=dtype, order=order)
            src, out = tmp_path / f"a_{order}.npy", tmp_path / f"a_{order}.ply"
            np.save(src, a)
            detect(src, out)
            v = plyfile.PlyData.read(str(out))["vertex"].data
            xyz = np.stack([v["x"], v["y"], v["z"]], 1)
            assert np.array_equal(xyz, a[:, :3]), (dtype, order)
            assert np.array_equal(v["column_4"], a[:, 3])


def test_other_arrays_are_refused_clearly(tmp_path):
    import subprocess
    from conftest import bounded_bin

    for name, array, message in [
        ("int.npy", np.zeros((10, 3), np.int32), "dtype '<i4'"),
        ("flat.npy", np.zeros(30), "shape (30,)"),
        ("big.npy", np.zeros((10, 3), ">f8"), "big-endian"),
    ]:
        np.save(tmp_path / name, array)
        run = subprocess.run(
            [str(bounded_bin()), "detect", str(tmp_path / name), "-o", str(tmp_path / "o.ply")],
            capture_output=True, text=True,
        )
        assert run.returncode != 0 and message in run.stderr, run.stderr
