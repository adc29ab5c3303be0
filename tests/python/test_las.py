"""LAS / LAZ outputs read back with laspy (and lazrs): the user's records and fields survive,
the header follows LAS 1.4, and `detect` runs on its own output."""

import struct

import laspy
import numpy as np
import pytest

from conftest import box_points, detect

# EPSG:32632 (WGS 84 / UTM zone 32N), abridged WKT: the records are compared byte for byte.
WKT = (
    'PROJCS["WGS 84 / UTM zone 32N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",'
    '6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],'
    'PROJECTION["Transverse_Mercator"],PARAMETER["central_meridian",9],'
    'PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],UNIT["metre",1],'
    'AUTHORITY["EPSG","32632"]]'
)


def survey(path, compressed=False):
    """A georeferenced LAS 1.4 survey of a box at UTM coordinates on a mm grid: WKT CRS,
    a custom VLR and EVLR, ground / building classes, scan colours and a scaled Extra Bytes
    field "Deviation"."""
    p = box_points(3000) + [500_000.0, 5_400_000.0, 100.0]
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.scales = [0.001] * 3
    header.offsets = [500_000.0, 5_400_000.0, 0.0]
    header.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr(WKT))
    header.vlrs.append(laspy.VLR("MyCompany", 42, "custom", b"\x00\x01\x02custom record"))
    header.add_extra_dim(
        laspy.ExtraBytesParams(
            name="Deviation", type=np.uint8, description="distance to design",
            scales=[0.01], offsets=[0.0], no_data=[255],
        )
    )
    las = laspy.LasData(header)
    las.x, las.y, las.z = p.T
    n = len(p)
    las.classification = np.where(p[:, 2] < 100.01, 2, 6).astype(np.uint8)
    las.red = (np.arange(n) * 7 % 65536).astype(np.uint16)
    las.green = (np.arange(n) * 11 % 65536).astype(np.uint16)
    las.blue = (np.arange(n) * 13 % 65536).astype(np.uint16)
    las.Deviation = np.round((np.arange(n) % 200) * 0.01, 2)
    las.evlrs = laspy.vlrs.vlrlist.VLRList([laspy.VLR("MyCompany", 43, "custom evlr", b"evlr payload" * 10)])
    las.write(str(path))
    return laspy.read(str(path))


def payload(vlr):
    """A VLR's data as in the file: laspy parses known records (the WKT CRS) into objects."""
    if hasattr(vlr, "record_data_bytes"):
        return bytes(vlr.record_data_bytes())
    return bytes(vlr.record_data)


def records(vlrs):
    return {(v.user_id, v.record_id): v for v in vlrs}


@pytest.fixture(params=["las", "laz"])
def ext(request):
    return request.param


def test_records_crs_and_fields_survive(tmp_path, ext):
    src = tmp_path / f"survey.{ext}"
    before = survey(src)
    out = tmp_path / f"out.{ext}"
    detect(src, out)
    after = laspy.read(str(out))
    assert after.header.global_encoding.wkt
    vlrs, old = records(after.header.vlrs), records(before.header.vlrs)
    for key in [("LASF_Projection", 2112), ("MyCompany", 42)]:
        assert payload(vlrs[key]) == payload(old[key]), key
    assert after.header.parse_crs() is not None
    assert [bytes(e.record_data) for e in after.evlrs] == [b"evlr payload" * 10]
    # The ground and building classes and the scan colours stay; the class is an extra dim.
    assert np.array_equal(after.classification, before.classification)
    for c in ["red", "green", "blue"]:
        assert np.array_equal(after[c], before[c]), c
    assert set(np.unique(after["class"])) <= {0, 1, 2}
    # The scaled field keeps its scale, offset, no-data and description.
    assert np.allclose(after.Deviation, before.Deviation)
    info = {d.name: d for d in after.point_format.extra_dimensions}["Deviation"]
    assert info.scales[0] == 0.01 and info.offsets[0] == 0.0
    assert info.description == "distance to design"
    assert np.array_equal(after.points.array["Deviation"], before.points.array["Deviation"])
    assert np.array_equal(after.x, before.x) and np.array_equal(after.z, before.z)


def test_header_follows_las_1_4(tmp_path, ext):
    src = tmp_path / f"survey.{ext}"
    survey(src)
    out = tmp_path / f"out.{ext}"
    detect(src, out)
    head = out.read_bytes()[:375]
    legacy_count, = struct.unpack_from("<I", head, 107)
    legacy_by_return = struct.unpack_from("<5I", head, 111)
    assert legacy_count == 0 and legacy_by_return == (0,) * 5
    after = laspy.read(str(out))
    assert after.header.point_count == 3000
    assert after.header.creation_date is not None and after.header.creation_date.year >= 2024
    assert after.header.system_identifier == "MODIFICATION"
    assert after.header.generating_software.startswith("BoundED-rs")


def test_detect_runs_on_its_own_output(tmp_path, ext):
    src = tmp_path / f"survey.{ext}"
    survey(src)
    once, twice = tmp_path / f"once.{ext}", tmp_path / f"twice.{ext}"
    detect(src, once)
    detect(once, twice)
    a, b = laspy.read(str(once)), laspy.read(str(twice))
    names = list(b.point_format.dimension_names)
    assert len(names) == len(set(names)) and names == list(a.point_format.dimension_names)
    assert np.array_equal(a["class"], b["class"])
    assert np.array_equal(a.classification, b.classification)


def test_class_codes_in_classification_keep_the_input_classes(tmp_path):
    # A PLY-like cloud without classes written by laspy: the class goes to Classification.
    p = box_points(3000)
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = [1e-4] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = p.T
    src, out = tmp_path / "plain.las", tmp_path / "out.las"
    las.write(str(src))
    detect(src, out)
    after = laspy.read(str(out))
    assert set(np.unique(after.classification)) <= {1, 64, 65}
    assert "class" not in after.point_format.dimension_names
    assert 64 in after.classification
