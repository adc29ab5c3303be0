"""Shared fixtures: the `bounded` binary to compare with, and small generated clouds."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import bounded

REPO = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def bounded_bin():
    """The CLI binary: $BOUNDED_BIN, default <repo>/target/debug/bounded."""
    path = pathlib.Path(os.environ.get("BOUNDED_BIN", REPO / "target" / "debug" / "bounded"))
    if not path.is_file():
        pytest.fail(
            f"{path} does not exist: build it with `cargo build -p bounded-cli` "
            "or set BOUNDED_BIN"
        )
    return path


def run_cli(binary, *args):
    """Runs `bounded ARGS...`, failing the test with its stderr if it fails."""
    done = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done


def open_box(n=3000, size=(4.0, 3.0, 2.0), seed=0):
    """n points drawn uniformly on an open box (a floor and four walls, no lid), float64.

    Sharp edges where the faces meet, a boundary around the opening. Every coordinate is a
    multiple of 1/1024 below 8, so float32 holds it exactly, and so does every offset from
    the bounding-box centre: float32 and float64 input describe the same cloud.
    """
    sx, sy, sz = size
    rng = np.random.default_rng(seed)
    faces = [  # (width, height, the point at (u, v) in [0, 1)^2)
        (sx, sy, lambda u, v: (u * sx, v * sy, 0 * u)),
        (sx, sz, lambda u, v: (u * sx, 0 * u, v * sz)),
        (sx, sz, lambda u, v: (u * sx, sy + 0 * u, v * sz)),
        (sy, sz, lambda u, v: (0 * u, u * sy, v * sz)),
        (sy, sz, lambda u, v: (sx + 0 * u, u * sy, v * sz)),
    ]
    areas = np.array([w * h for w, h, _ in faces])
    face = rng.choice(len(faces), n, p=areas / areas.sum())
    u, v = rng.random(n), rng.random(n)
    xyz = np.zeros((n, 3))
    for k, (_, _, place) in enumerate(faces):
        on = face == k
        xyz[on] = np.column_stack(place(u[on], v[on]))
    return np.round(xyz * 1024) / 1024


@pytest.fixture(scope="session")
def box():
    """The open box of `open_box`, 3000 points, float64."""
    return open_box()


@pytest.fixture(scope="session")
def generated(bounded_bin, tmp_path_factory):
    """Clouds written by `bounded generate` (binary float PLY with a `class` property)."""
    out = tmp_path_factory.mktemp("generated")
    run_cli(bounded_bin, "generate", "--kind", "cad", "-o", out, "--seed", "7", "--shapes", "2")
    files = sorted(out.glob("*.ply"))
    assert len(files) == 2, files
    return files


def cli_detect(binary, cloud_path, out_path, *options):
    """The CLI's classes and probabilities for the cloud file `cloud_path`."""
    run_cli(binary, "detect", cloud_path, "-o", out_path, *options)
    _, fields = bounded.read(out_path)
    # PLY and text outputs name the results for CloudCompare (`scalar_class`, ...).
    field = lambda name: fields[name] if name in fields else fields["scalar_" + name]
    probabilities = np.column_stack(
        [field("p_nonedge"), field("p_sharp"), field("p_boundary")]
    )
    return field("class"), probabilities
