#!/usr/bin/env bash
# The tests, as the README and CI run them: first the engine wheels and the Blender extension zip
# (scripts/build_extension.py --if-stale: built only when dist/ has none of addon/ and native/ as
# they are now), which tests/blender/test_install.py installs into real Blender; then pytest, with
# any arguments given (./scripts/test.sh -x tests/blender). Run it in the activated .venv.
set -euo pipefail
cd "$(dirname "$0")/.."
python scripts/build_extension.py --if-stale
python -m pytest -q "$@"
