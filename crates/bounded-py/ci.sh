#!/usr/bin/env bash
# The Python package's CI: a fresh virtual environment with the pinned test requirements
# (requirements-test.txt, from PyPI), the package built and installed into it as users
# install it (`pip install crates/bounded-py`), then its pytest suite.
#
# The package is built with cargo's dev profile (BOUNDED_PY_PROFILE, default `dev`): after
# `cargo test --workspace` every dependency is already compiled for it, so only the bindings
# and PyO3 compile (a release build of burn and the rest would take minutes more). The tests
# compare with the dev `bounded` binary and the `features` example, built here if needed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
profile="${BOUNDED_PY_PROFILE:-dev}"
target_dir="$(cargo metadata --format-version 1 --no-deps --manifest-path "$repo/Cargo.toml" |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')"
case "$profile" in dev) out="$target_dir/debug" ;; *) out="$target_dir/$profile" ;; esac
start=$SECONDS

venv="$(mktemp -d)/venv"
trap 'rm -rf "$(dirname "$venv")"' EXIT
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$here/requirements-test.txt"
echo "ci.sh: test requirements installed ($((SECONDS - start)) s)"

cargo build --locked --profile "$profile" -p bounded-cli -p bounded-py --bin bounded --example features
MATURIN_PEP517_ARGS="--locked --profile $profile" \
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-build-isolation \
    "$here"
echo "ci.sh: package built and installed ($((SECONDS - start)) s)"

# Outside the source tree, so that the tests import the installed package.
cd "$(dirname "$venv")"
status=0
BOUNDED_BIN="$out/bounded" BOUNDED_FEATURES_EXAMPLE="$out/examples/features" \
    "$venv/bin/python" -m pytest "$here/tests" -p no:cacheprovider -ra || status=$?
echo "ci.sh: pytest finished with status $status ($((SECONDS - start)) s)"
# pytest's 5 (no test collected) is a failure too, as every non-zero status.
exit "$status"
