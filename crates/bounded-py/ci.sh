#!/usr/bin/env bash
# The Python package's CI: a fresh virtual environment with the pinned test requirements
# (requirements-test.txt, from PyPI), the package built and installed into it as users
# install it (`pip install crates/bounded-py`), then its pytest suite.
#
# The package is built with cargo's dev profile: after `cargo test --workspace` (which .ci/run
# runs first) every dependency is compiled for it as for the workspace (see the pins in
# Cargo.toml), so only PyO3 and the bindings compile; a release build of burn and
# the rest would take minutes more. The tests compare with the `bounded` binary and the
# `features` example that `cargo test --workspace` builds (built here too when missing).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
target_dir="$(cargo metadata --format-version 1 --no-deps --manifest-path "$repo/Cargo.toml" |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')"
start=$SECONDS

venv="$(mktemp -d)/venv"
trap 'rm -rf "$(dirname "$venv")"' EXIT
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$here/requirements-test.txt"
echo "ci.sh: test requirements installed ($((SECONDS - start)) s)"
# The README examples' test imports Open3D.
bash "$repo/.ci/open3d-libusb.sh"

# Nothing to do after .ci/run's `cargo test --workspace`.
(cd "$repo" && cargo test --workspace --locked --no-run --quiet)
# Without build isolation the maturin of the test requirements builds, found on PATH.
build_log="$(dirname "$venv")/build.log"
PATH="$venv/bin:$PATH" MATURIN_PEP517_ARGS="--locked --profile dev" \
    "$venv/bin/python" -m pip install --verbose --disable-pip-version-check --no-build-isolation \
    "$here" >"$build_log" 2>&1 || { tail -n 60 "$build_log"; exit 1; }
echo "ci.sh: package built and installed ($((SECONDS - start)) s)"
# Only PyO3 (built for this interpreter) and the bindings may compile here: anything else
# means this crate's dependency graph differs from the workspace's (a feature, or a crate the
# workspace links as a normal dependency where this build has it as a build-time one) and
# CI compiles burn twice.
rebuilt="$(grep -oE 'Compiling [a-z0-9_-]+' "$build_log" | awk '{print $2}' |
    grep -vxE 'pyo3(-[a-z-]+)?|numpy|bounded-py' || true)"
if [ -n "$rebuilt" ]; then
    echo "ci.sh: the package build recompiled what cargo test had built:" $rebuilt >&2
    echo "ci.sh: pin them in crates/bounded-py/Cargo.toml as the workspace builds them" \
        "(features; a normal dependency where the workspace has one)" >&2
    exit 1
fi

# Outside the source tree, so that the tests import the installed package.
cd "$(dirname "$venv")"
status=0
BOUNDED_BIN="$target_dir/debug/bounded" \
    BOUNDED_FEATURES_EXAMPLE="$target_dir/debug/examples/features" \
    "$venv/bin/python" -m pytest "$here/tests" -ra || status=$?
echo "ci.sh: pytest finished with status $status ($((SECONDS - start)) s)"
# pytest's 5 (no test collected) is a failure too, as every non-zero status.
exit "$status"
