#!/usr/bin/env bash
# Builds the Debian package: a Release build (scripts/build.sh), then `cpack -G DEB` on it.
# Usage: scripts/package.sh [BUILD_DIR]   -> BUILD_DIR/toposlam_<version>_<arch>.deb (BUILD_DIR: build/)
# What goes in it and why: packaging/CMakeLists.txt; installing it: docs/deploy.md.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(realpath -m "${1:-$root/build}")"
BUILD_TYPE=Release "$root/scripts/build.sh" "$build"
cd "$build"
cpack -G DEB
ls "$build"/toposlam_*.deb
