"""bounded.read / bounded.write: round trips through every format, and clear errors."""

import warnings

import numpy as np
import pytest

import bounded

FORMATS = ["ply", "pcd", "xyz", "txt", "csv", "las", "laz", "e57"]


def fields_of(n):
    rng = np.random.default_rng(3)
    return {
        "intensity": rng.integers(0, 65536, n).astype(np.uint16),
        "score": rng.random(n).astype(np.float32),
        "label": rng.integers(-5, 5, n).astype(np.int32),
        "flag": rng.random(n) > 0.5,
    }


@pytest.mark.parametrize("ext", FORMATS)
def test_doubles_and_fields_round_trip(box, tmp_path, ext):
    xyz = box + [500_000.0, 4_000_000.0, 100.0]
    fields = fields_of(len(xyz))
    path = tmp_path / f"cloud.{ext}"
    bounded.write(path, xyz, **fields)
    back, back_fields = bounded.read(path)
    assert back.dtype == np.float64 and back.shape == xyz.shape
    if ext in ("las", "laz"):
        # LAS stores integers on a grid finer than float32 resolves over the cloud.
        np.testing.assert_allclose(back, xyz, rtol=0, atol=1e-3)
    else:
        np.testing.assert_array_equal(back, xyz)
    for name, values in fields.items():
        assert name in back_fields, (name, list(back_fields))
        # Text and E57 may read a field back as another type, never as another value.
        back_values = back_fields[name].astype(values.dtype)
        np.testing.assert_array_equal(back_values, values, err_msg=name)
    if ext in ("ply", "pcd"):
        assert list(back_fields) == list(fields)
        for name in ("intensity", "score", "label"):
            assert back_fields[name].dtype == fields[name].dtype, name
        assert back_fields["flag"].dtype == np.uint8
    # And the detection is the same on the cloud read back (float64 again).
    if ext not in ("las", "laz"):
        np.testing.assert_array_equal(bounded.detect(back).classes, bounded.detect(xyz).classes)


@pytest.mark.parametrize("ext", ["ply", "pcd", "e57"])
def test_floats_stay_floats(box, tmp_path, ext):
    xyz = box.astype(np.float32) - 1.5
    path = tmp_path / f"cloud.{ext}"
    bounded.write(path, xyz)
    back, fields = bounded.read(path)
    assert back.dtype == np.float32
    np.testing.assert_array_equal(back, xyz)


def test_las_fields_keep_their_las_meaning(box, tmp_path):
    n = len(box)
    path = tmp_path / "cloud.las"
    classification = np.full(n, 6, np.uint8)
    bounded.write(path, box, classification=classification, return_number=np.ones(n, np.uint8))
    _, fields = bounded.read(path)
    np.testing.assert_array_equal(fields["classification"], classification)
    assert fields["classification"].dtype == np.uint8


def test_read_keeps_the_file_order_and_types(tmp_path):
    path = tmp_path / "small.ply"
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
        "property double z\nproperty ushort intensity\nproperty char tag\nend_header\n"
        "0.5 1.5 2.5 7 -1\n1 2 3 65535 2\n500000.25 0 0 0 127\n"
    )
    xyz, fields = bounded.read(path)
    np.testing.assert_array_equal(xyz, [[0.5, 1.5, 2.5], [1, 2, 3], [500000.25, 0, 0]])
    assert list(fields) == ["intensity", "tag"]
    assert fields["intensity"].dtype == np.uint16 and fields["tag"].dtype == np.int8
    np.testing.assert_array_equal(fields["intensity"], [7, 65535, 0])
    np.testing.assert_array_equal(fields["tag"], [-1, 2, 127])


def test_non_finite_points_are_refused_or_left_out_with_a_warning(tmp_path):
    path = tmp_path / "holes.xyz"
    path.write_text("0 0 0 1\nnan nan nan 2\n1 0 0 3\n0 inf 0 4\n")
    with pytest.raises(ValueError) as raised:
        bounded.read(path)
    message = str(raised.value)
    assert f"{path}: point 1 has a non-finite coordinate" in message
    assert "drop_non_finite=True leaves such points out" in message
    with pytest.warns(UserWarning, match=r"left out 2 points with a NaN or infinite"):
        xyz, fields = bounded.read(path, drop_non_finite=True)
    np.testing.assert_array_equal(xyz, [[0, 0, 0], [1, 0, 0]])
    np.testing.assert_array_equal(fields["column_4"], [1, 3])
    clean = tmp_path / "clean.xyz"
    clean.write_text("0 0 0\n1 0 0\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning when nothing is left out
        assert len(bounded.read(clean, drop_non_finite=True)[0]) == 2


def test_unreadable_files_name_the_file(tmp_path):
    missing = tmp_path / "missing.ply"
    with pytest.raises(FileNotFoundError, match=f"{missing}: No such file"):
        bounded.read(missing)
    with pytest.raises(ValueError, match="unknown point-cloud format"):
        bounded.read(tmp_path / "cloud.obj")
    broken = tmp_path / "broken.ply"
    broken.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
                       b"property float x\nproperty float y\nproperty float z\nend_header\n\0\0")
    with pytest.raises(ValueError) as raised:
        bounded.read(broken)
    assert str(raised.value).startswith(f"{broken}: ")
    directory = tmp_path / "directory.ply"
    directory.mkdir()
    with pytest.raises(IsADirectoryError, match=f"{directory}"):
        bounded.read(directory)


@pytest.mark.parametrize(
    "fields, error, message",
    [
        ({"short": np.zeros(2, np.uint8)}, ValueError, "property 'short' has 2 values for 3 points"),
        ({"big": np.zeros(3, np.int64)}, TypeError, "field 'big' has dtype int64"),
        ({"rgb": np.zeros((3, 3), np.uint8)}, ValueError, "field 'rgb' must be a 1-D array"),
        ({"x": np.zeros(3)}, ValueError, "the property name 'x' appears twice"),
        ({"a b": np.zeros(3)}, ValueError, "is empty or has a space or comma"),
    ],
)
def test_bad_fields_are_refused_and_leave_no_file(tmp_path, fields, error, message):
    path = tmp_path / "out.ply"
    with pytest.raises(error) as raised:
        bounded.write(path, np.zeros((3, 3)), **fields)
    assert message in str(raised.value)
    assert list(tmp_path.iterdir()) == []


def test_write_errors(tmp_path):
    xyz = np.zeros((3, 3))
    with pytest.raises(ValueError, match="unknown point-cloud format"):
        bounded.write(tmp_path / "out.obj", xyz)
    with pytest.raises(FileNotFoundError):
        bounded.write(tmp_path / "no" / "such" / "out.ply", xyz)
    with pytest.raises(TypeError, match="got dtype int64"):
        bounded.write(tmp_path / "out.ply", np.zeros((3, 3), np.int64))
    nan = xyz.copy()
    nan[1, 2] = np.nan
    with pytest.raises(ValueError, match="point 1 has a non-finite coordinate"):
        bounded.write(tmp_path / "out.ply", nan)
    assert list(tmp_path.iterdir()) == []
    # Fields may be named like the positional parameters.
    bounded.write(tmp_path / "out.ply", xyz, path=np.ones(3, np.uint8), xyz=np.ones(3, np.uint8))
    assert list(bounded.read(tmp_path / "out.ply")[1]) == ["path", "xyz"]


def test_detect_on_what_read_gives_equals_the_cli(bounded_bin, generated, tmp_path):
    """Written by the CLI, read back: the annotation columns are the detection's."""
    from conftest import cli_detect

    classes, probabilities = cli_detect(bounded_bin, generated[1], tmp_path / "out.pcd")
    result = bounded.detect(bounded.read(generated[1])[0])
    np.testing.assert_array_equal(result.classes, classes)
    np.testing.assert_allclose(result.probabilities, probabilities, rtol=0, atol=1e-6)
