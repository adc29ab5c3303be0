"""The README's examples, run as written, on small generated inputs."""

import re
import shutil

import laspy
import numpy as np
import open3d as o3d

import bounded
from conftest import REPO, run_cli

README = REPO / "crates" / "bounded-py" / "README.md"


def example(needle):
    """The README's python block that mentions `needle` (exactly one must)."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    found = [b for b in blocks if needle in b]
    assert len(found) == 1, f"{len(found)} README examples mention {needle!r}"
    return found[0]


def test_every_example_is_tested():
    blocks = re.findall(r"```python\n", README.read_text())
    assert len(blocks) == 3, "a README example without a test below"


def run(code):
    namespace = {}
    exec(compile(code, str(README), "exec"), namespace)
    return namespace


def airborne_tile(path):
    """A LAS 1.2 tile (point format 3, 1 cm grid, UTM offsets): flat ground around a house
    with a gable roof, whose ridge is a crease and whose eaves are an edge of the data."""
    xs, ys = np.meshgrid(np.arange(0, 40, 0.5), np.arange(0, 40, 0.5), indexing="ij")
    x, y = xs.ravel(), ys.ravel()
    under_roof = (np.abs(x - 20) <= 6) & (np.abs(y - 20) <= 4)
    z = np.where(under_roof, 9.0 - 0.5 * np.abs(y - 20), 0.0)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.offsets = [600_000.0, 5_400_000.0, 0.0]
    header.scales = [0.01, 0.01, 0.01]
    las = laspy.LasData(header)
    las.x, las.y, las.z = x + 600_100.0, y + 5_400_200.0, z + 230.0
    las.intensity = np.arange(len(x), dtype=np.uint16)
    las.write(path)
    return len(x)


def test_laspy_example(bounded_bin, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    n = airborne_tile("tile.laz")
    ns = run(example("laspy"))
    result = ns["result"]
    labelled = laspy.read("tile_labelled.laz")
    assert len(labelled.points) == n
    codes = np.asarray(labelled.classification)
    np.testing.assert_array_equal(codes, np.array([1, 64, 65])[result.classes])
    np.testing.assert_array_equal(
        np.asarray(labelled.p_sharp), result.probabilities[:, bounded.SHARP]
    )
    np.testing.assert_array_equal(np.asarray(labelled.intensity), np.arange(n))
    # The roof ridge is found (and nothing else is sharp), and the CLI labels the same tile
    # the same way.
    xyz = np.column_stack([labelled.x, labelled.y, labelled.z]) - [600_100.0, 5_400_200.0, 230.0]
    near_ridge = (np.abs(xyz[:, 0] - 20) <= 6) & (np.abs(xyz[:, 1] - 20) < 1) & (xyz[:, 2] > 8)
    assert (codes == 64).sum() >= 10
    assert near_ridge[codes == 64].all()
    run_cli(bounded_bin, "detect", "tile.laz", "-o", "cli.laz")
    np.testing.assert_array_equal(np.asarray(laspy.read("cli.laz").classification), codes)


def test_open3d_example(box, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    bounded.write("scan.ply", box)
    ns = run(example("open3d"))
    coloured = o3d.io.read_point_cloud("scan_classes.ply")
    np.testing.assert_array_equal(np.asarray(coloured.points), box)
    expected = bounded.detect(box).classes
    np.testing.assert_array_equal(ns["result"].classes, expected)
    colours = np.asarray(coloured.colors)
    np.testing.assert_allclose(colours[expected == bounded.SHARP], [[1, 0, 0]] * (expected == 1).sum())
    np.testing.assert_allclose(colours[expected == bounded.BOUNDARY], [[0, 1, 0]] * (expected == 2).sum())
    assert (expected == bounded.SHARP).any() and (expected == bounded.BOUNDARY).any()


def test_scikit_learn_example(generated, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    shutil.copy(generated[0], "train.ply")
    shutil.copy(generated[1], "test.ply")
    ns = run(example("sklearn"))
    assert ns["X"].shape[1] == 4 * 12
    score = ns["forest"].score(ns["X_test"], ns["y_test"])
    assert f"accuracy on the test cloud: {score:.3f}" in capsys.readouterr().out
    # Better than calling every point non-edge, the most common class.
    majority = np.bincount(ns["y_test"]).max() / len(ns["y_test"])
    assert score > majority + 0.02, (score, majority)
