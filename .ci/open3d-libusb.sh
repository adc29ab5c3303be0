#!/usr/bin/env bash
# Open3D's wheel links libusb, which Debian packages apart: installs libusb-1.0-0 when the
# library is missing and apt-get can (as root). Both Python suites import Open3D
# (crates/bounded-py/ci.sh, tests/python/run.sh).
set -euo pipefail
if ldconfig -p | grep -q "libusb-1.0.so.0"; then
    exit 0
fi
if command -v apt-get >/dev/null && [ "$(id -u)" -eq 0 ]; then
    echo "installing libusb-1.0-0 for open3d" >&2
    apt-get update -qq && apt-get install -y -qq libusb-1.0-0 >/dev/null
else
    echo "libusb-1.0.so.0 is missing and apt-get cannot install it: Open3D will not import" >&2
fi
