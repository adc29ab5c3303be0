"""Times bounded.detect on a numpy array beside the library (the CLI's own detection time, on
the same cloud) and, when pgeof is installed, pgeof's compute_features_multiscale.

    python crates/bounded-py/bench.py CLOUD [--bin target/release/bounded] [--runs 3]

CLOUD is any cloud file (e.g. the 1M-point cube of `cargo run --release -p bounded-data
--example big_cloud -- 1000000 /tmp/cube1m.ply`). Build the package and the CLI in release
mode for figures (`pip install crates/bounded-py`, `cargo build --release -p bounded-cli`).
Runs alternate between the contenders, and each prints its median.
"""

import argparse
import re
import statistics
import subprocess
import tempfile
import time

import numpy as np

import bounded


def cli_seconds(binary, cloud, out):
    done = subprocess.run(
        [binary, "detect", cloud, "-o", out], capture_output=True, text=True, check=True
    )
    return float(re.search(r"detection ([0-9.]+) s", done.stderr).group(1))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("cloud")
    parser.add_argument("--bin", default="target/release/bounded")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    xyz, _ = bounded.read(args.cloud)
    print(f"{len(xyz)} points, {xyz.dtype}")
    try:
        import pgeof
    except ImportError:
        pgeof = None
    times = {"bounded.detect (numpy)": [], "library (bounded detect)": []}
    if pgeof is not None:
        times["pgeof knn_search + compute_features_multiscale"] = []
        xyz32 = xyz.astype("float32")
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.runs):
            start = time.perf_counter()
            bounded.detect(xyz)
            times["bounded.detect (numpy)"].append(time.perf_counter() - start)
            seconds = cli_seconds(args.bin, args.cloud, f"{tmp}/out.ply")
            times["library (bounded detect)"].append(seconds)
            if pgeof is not None:
                start = time.perf_counter()
                nn, _ = pgeof.knn_search(xyz32, xyz32, 128)
                nn_ptr = 128 * np.arange(len(xyz) + 1, dtype=np.uint32)
                pgeof.compute_features_multiscale(xyz32, nn.ravel(), nn_ptr, [16, 32, 64, 128])
                times["pgeof knn_search + compute_features_multiscale"].append(
                    time.perf_counter() - start
                )
    for name, values in times.items():
        median = statistics.median(values)
        runs = ", ".join(f"{v:.2f}" for v in values)
        print(f"{name}: median {median:.2f} s ({len(xyz) / median / 1e6:.2f} M points/s; runs {runs})")


if __name__ == "__main__":
    main()
