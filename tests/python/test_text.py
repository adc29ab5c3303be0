"""Text outputs read back with numpy: CloudCompare's header rules take columns whose name
holds SCALAR as scalar fields (the probabilities otherwise look like normals to it), and
it reads names only from a header line that starts with `//`, in CSV too."""

import numpy as np

from conftest import box_points, detect


def test_header_names_the_results_as_scalar_fields(tmp_path):
    p = box_points(3000)
    src = tmp_path / "box.xyz"
    np.savetxt(src, p, fmt="%.6f")
    for ext, sep, prefix in [("txt", " ", "//"), ("csv", ",", "//")]:
        out = tmp_path / f"out.{ext}"
        detect(src, out)
        header = out.read_text().split("\n", 1)[0]
        assert header.startswith(prefix)
        names = header[len(prefix):].split(sep)
        assert names[:3] == ["x", "y", "z"]
        ours = [n for n in names[3:] if n not in ("red", "green", "blue")]
        assert ours == ["scalar_class", "scalar_p_nonedge", "scalar_p_sharp", "scalar_p_boundary"]
        table = np.loadtxt(out, delimiter=None if sep == " " else ",", skiprows=1)
        assert np.allclose(table[:, :3], p, atol=1e-6)
        column = dict(zip(names, table.T))
        assert set(np.unique(column["scalar_class"])) <= {0, 1, 2}
