#!/usr/bin/env bash
# End-to-end tests of the outputs with the real readers (laspy + lazrs, meshio, Open3D,
# plyfile, pymeshlab, pye57, pypcd4; CloudCompare and PCL's tools from Debian): creates a virtual environment (VENV, default
# target/venv-interop), installs the pinned requirements and runs pytest on the binary
# BOUNDED_BIN (default target/debug/bounded, relative to the repository root; build it
# first). Fails when pytest collects no test (its exit code 5).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
venv="${VENV:-$repo/target/venv-interop}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet -r "$here/requirements.txt"
bash "$repo/.ci/open3d-libusb.sh"
# The desktop tools of test_desktop.py, from Debian's packages; without apt-get (or root)
# those tests skip and say why.
if ! command -v CloudCompare >/dev/null || ! command -v pcl_passthrough_filter >/dev/null ||
    ! command -v xvfb-run >/dev/null; then
    if command -v apt-get >/dev/null && [ "$(id -u)" -eq 0 ]; then
        echo "installing cloudcompare, pcl-tools and xvfb" >&2
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
            --no-install-recommends cloudcompare pcl-tools xvfb xauth >/dev/null
    fi
fi
cd "$repo"
status=0
"$venv/bin/python" -m pytest -q -rs "$here" "$@" || status=$?
if [ "$status" -eq 5 ]; then
    echo "pytest collected no test" >&2
    exit 1
fi
exit "$status"
