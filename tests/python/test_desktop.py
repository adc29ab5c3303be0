"""Outputs opened by the desktop tools' command lines, from Debian's packages (run.sh installs
them where apt-get can): CloudCompare 2.11 (under Xvfb) loads the results as scalar fields,
never as normals; PCL 1.13's passthrough filter selects sharp points by `class`, and its
PointXYZ tools load the positions."""

import shutil
import subprocess

import numpy as np
import pytest

from conftest import box_points, detect


def need(tool):
    if shutil.which(tool) is None:
        pytest.skip(f"{tool} is not installed (Debian: cloudcompare, pcl-tools, xvfb)")


def cloudcompare_columns(path):
    """The column names CloudCompare writes after loading `path` (its ASCII export)."""
    need("CloudCompare")
    need("xvfb-run")
    run = subprocess.run(
        ["xvfb-run", "-a", "CloudCompare", "-SILENT", "-O", str(path), "-C_EXPORT_FMT", "ASC",
         "-ADD_HEADER", "-EXT", "asc", "-NO_TIMESTAMP", "-SAVE_CLOUDS"],
        capture_output=True, text=True, timeout=300,
    )
    exported = path.with_suffix(".asc")
    assert exported.exists(), run.stdout + run.stderr
    header = exported.read_text().split("\n", 1)[0]
    assert header.startswith("//")
    return header[2:].split(" ")


@pytest.fixture
def box(tmp_path):
    src = tmp_path / "box.xyz"
    np.savetxt(src, box_points(3000), fmt="%.6f")
    return src


@pytest.mark.parametrize("ext", ["ply", "csv"])
def test_cloudcompare_names_the_scalar_fields(tmp_path, box, ext):
    out = tmp_path / f"out.{ext}"
    detect(box, out)
    columns = cloudcompare_columns(out)
    prefix = "" if ext == "ply" else "scalar_"
    for name in ["class", "p_nonedge", "p_sharp", "p_boundary"]:
        assert prefix + name in columns, columns
    assert "Nx" not in columns


def test_cloudcompare_takes_text_columns_as_scalar_fields(tmp_path, box):
    out = tmp_path / "out.txt"
    detect(box, out)
    columns = cloudcompare_columns(out)
    # From a space-separated header it takes the kinds, not the names.
    assert columns[:6] == ["X", "Y", "Z", "R", "G", "B"]
    assert len([c for c in columns if c.startswith("Scalar_field")]) == 4, columns
    assert "Nx" not in columns


def test_pcl_filters_on_class_and_loads_point_xyz(tmp_path, box):
    need("pcl_passthrough_filter")
    out, sharp = tmp_path / "out.pcd", tmp_path / "sharp.pcd"
    ply = tmp_path / "out.ply"
    detect(box, out)
    detect(box, ply, "--flavour", "plain")
    import plyfile

    classes = plyfile.PlyData.read(str(ply))["vertex"]["class"]
    run = subprocess.run(
        ["pcl_passthrough_filter", str(out), str(sharp), "-field", "class", "-min", "0.5",
         "-max", "1.5", "-keep", "0"],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    header = sharp.read_bytes().split(b"DATA", 1)[0].decode()
    points = int(header.split("POINTS ", 1)[1].split()[0])
    assert points == int((classes == 1).sum()) > 0
    # A PointXYZ tool: it fails with "Failed to find match for field 'x'" on double positions.
    sampled = tmp_path / "sampled.pcd"
    run = subprocess.run(
        ["pcl_uniform_sampling", str(out), str(sampled), "-radius", "0.05"],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0 and sampled.exists(), run.stdout + run.stderr
    assert "Failed to find match" not in run.stdout + run.stderr
