"""bounded.features: the documented layout, the Rust library's values, groups and errors."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import bounded
from conftest import REPO

NAMES = [
    "sigma_u1", "sigma_u2", "sigma_u3", "sigma_l1", "sigma_l2", "sigma_l3",
    "d_perp", "d_par", "s_perp", "s_par", "c_perp", "c_par",
]  # fmt: skip


def plane(n=20):
    """An n x n grid on the plane z = 5, at UTM-like x."""
    i = np.arange(n * n)
    return np.column_stack([1000.0 + i % n, 2000.0 + i // n, np.full(n * n, 5.0)])


def test_layout_is_points_by_scales_by_features(box):
    f = bounded.features(box)
    assert f.dtype == np.float32
    assert f.shape == (len(box), 4, 12)
    assert f.flags.c_contiguous
    assert bounded.feature_names() == NAMES
    assert np.isfinite(f).all()


def test_values_on_a_plane_are_the_hand_computed_ones():
    xyz = plane()
    f = bounded.features(xyz, scales=(32, 16))
    names = bounded.feature_names()
    inside = [(x, y) for x in range(7, 13) for y in range(7, 13)]
    rows = [y * 20 + x for x, y in inside]
    # A plane has no extent along its normal: the smallest eigenvalue of each half, and the
    # offsets across the plane (d, s and c along the normal), are zero at every scale.
    for name in ("sigma_u3", "sigma_l3", "d_perp", "s_perp", "c_perp"):
        values = f[rows, :, names.index(name)]
        np.testing.assert_allclose(values, 0.0, atol=1e-5, err_msg=name)
    # ...while the in-plane spreads are not.
    assert (f[rows, :, names.index("sigma_u1")] > 0.01).all()


def test_scales_are_largest_first_and_each_scale_its_own():
    xyz = plane()
    both = bounded.features(xyz, scales=(64, 16))
    small = bounded.features(xyz, scales=(16,))
    # The c features compare a scale with the largest neighbourhood, so only the others are
    # a scale's own: computed alone they are the same numbers.
    np.testing.assert_array_equal(both[:, 1, :10], small[:, 0, :10])
    assert not np.array_equal(both[:, 0, :10], small[:, 0, :10])


def test_groups_select_columns_in_the_fixed_order(box):
    full = bounded.features(box, scales=(32, 16))
    names = bounded.feature_names()
    cases = [
        (["s"], ["s_perp", "s_par"]),
        (["d", "sigma_u"], ["sigma_u1", "sigma_u2", "sigma_u3", "d_perp", "d_par"]),
        (["c", "s", "d", "sigma_l", "sigma_u"], NAMES),
    ]
    for groups, expected in cases:
        assert bounded.feature_names(groups) == expected
        some = bounded.features(box, scales=(32, 16), groups=groups)
        np.testing.assert_array_equal(some, full[:, :, [names.index(n) for n in expected]])
    with_sigma = bounded.features(box, scales=(32,), groups=["sigma", "s"])
    assert with_sigma.shape == (len(box), 1, 5)
    assert bounded.feature_names(["sigma", "s"]) == [
        "sigma_1", "sigma_2", "sigma_3", "s_perp", "s_par",
    ]  # fmt: skip


def test_features_equal_the_rust_library(generated, tmp_path):
    """The library's own features of a file, written by this crate's `features` example
    ($BOUNDED_FEATURES_EXAMPLE, default <repo>/target/debug/examples/features)."""
    default = REPO / "target" / "debug" / "examples" / "features"
    example = pathlib.Path(os.environ.get("BOUNDED_FEATURES_EXAMPLE", default))
    if not example.is_file():
        pytest.fail(f"{example} does not exist: build it with "
                    "`cargo build -p bounded-py --example features`")
    out = tmp_path / "features.f32"
    subprocess.run([example, generated[1], out, "64,32,16"], check=True)
    xyz, _ = bounded.read(generated[1])
    expected = np.fromfile(out, dtype="<f4").reshape(len(xyz), 3, 12)
    np.testing.assert_array_equal(bounded.features(xyz, scales=(64, 32, 16)), expected)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"scales": (16, 32)}, ValueError, "invalid scales [16, 32]: scales must be strictly"),
        ({"scales": ()}, ValueError, "at least one scale is needed"),
        ({"scales": (4000,)}, ValueError, "the cloud has 3000 points but the largest scale"),
        ({"groups": ["s", "curvature"]}, ValueError, "unknown feature group 'curvature'"),
        ({"groups": []}, ValueError, "no feature group selected"),
        ({"groups": "s"}, TypeError, "Can't extract `str` to `Vec`"),
        ({"threads": 0}, ValueError, "threads must be at least 1"),
    ],
)
def test_bad_settings_are_refused_clearly(box, kwargs, error, message):
    with pytest.raises(error) as raised:
        bounded.features(box, **kwargs)
    assert message in str(raised.value)
