#!/usr/bin/env bash
# Installs the core's two header-only dependencies into PREFIX for a cibuildwheel build, the same
# release on every platform: Eigen 3.4.0 (CMake-installed, for its Eigen3Config.cmake) and
# nanoflann 1.5.5 (its one header). CMake finds both through CMAKE_PREFIX_PATH=PREFIX.
# Runs on the manylinux_2_28 image, on macOS and in Git Bash on Windows.
#   bash .github/scripts/install_headers.sh PREFIX
set -euo pipefail
PREFIX="$1"
WORK="$(mktemp -d)"
git clone --quiet --depth 1 --branch 3.4.0 https://gitlab.com/libeigen/eigen.git "$WORK/eigen"
# Configured for its install rules only: no tests, no BLAS, no docs.
cmake -S "$WORK/eigen" -B "$WORK/eigen-build" -DCMAKE_INSTALL_PREFIX="$PREFIX" \
  -DBUILD_TESTING=OFF -DEIGEN_BUILD_DOC=OFF -DEIGEN_BUILD_PKGCONFIG=OFF >/dev/null
cmake --install "$WORK/eigen-build" >/dev/null
git clone --quiet --depth 1 --branch v1.5.5 https://github.com/jlblancoc/nanoflann.git "$WORK/nanoflann"
mkdir -p "$PREFIX/include"
cp "$WORK/nanoflann/include/nanoflann.hpp" "$PREFIX/include/"
echo "Eigen 3.4.0 and nanoflann 1.5.5 in $PREFIX"
