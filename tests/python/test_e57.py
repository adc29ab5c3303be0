"""E57 outputs read back with pye57: the default read_scan works, and the `bounded:*`
extension fields read through pye57's libE57Format binding."""

import numpy as np
import pye57

from conftest import box_points, detect


def test_read_scan_defaults_and_extension_fields(tmp_path):
    p = box_points(3000)
    src, out = tmp_path / "box.xyz", tmp_path / "out.e57"
    np.savetxt(src, p, fmt="%.6f")
    detect(src, out)
    e57 = pye57.E57(str(out))
    data = e57.read_scan(0)
    xyz = np.stack([data["cartesianX"], data["cartesianY"], data["cartesianZ"]], 1)
    assert np.allclose(xyz, p, atol=1e-6)
    # The extension fields, as README shows: a buffer per field on the scan's points.
    header = e57.get_header(0)
    n = header.point_count
    fields = {}
    buffers = pye57.libe57.VectorSourceDestBuffer()
    for name, dtype in [("bounded:class", np.uint8), ("bounded:p_sharp", np.float32)]:
        fields[name] = np.empty(n, dtype)
        buffers.append(pye57.libe57.SourceDestBuffer(e57.image_file, name, fields[name], n, True, True))
    header.points.reader(buffers).read()
    assert set(np.unique(fields["bounded:class"])) <= {0, 1, 2}
    assert (fields["bounded:class"] == 1).any()
    assert ((fields["bounded:p_sharp"] >= 0) & (fields["bounded:p_sharp"] <= 1)).all()
