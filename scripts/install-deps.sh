#!/usr/bin/env bash
# Installs what slidestack needs to build on Debian/Ubuntu: libhdf5-dev and pkg-config (for the
# hdf5-metno crate). Needs a Rust toolchain (cargo) already on PATH. Without apt-get or root it
# stops and says what to install.
set -euo pipefail
if ! command -v cargo >/dev/null 2>&1; then
  echo "slidestack needs a Rust toolchain (cargo >= 1.85): install it from https://rustup.rs" >&2
  exit 1
fi
if pkg-config --exists hdf5 2>/dev/null || [ -e /usr/include/hdf5/serial/hdf5.h ]; then
  exit 0
fi
if command -v apt-get >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libhdf5-dev pkg-config >/dev/null
else
  echo "slidestack needs the HDF5 C library and headers (1.10 or newer) and pkg-config:" >&2
  echo "  Debian/Ubuntu: apt-get install libhdf5-dev pkg-config" >&2
  echo "  Fedora: dnf install hdf5-devel pkgconf;  macOS: brew install hdf5 pkg-config" >&2
  exit 1
fi
