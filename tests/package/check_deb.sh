#!/bin/sh
# The Debian package of a built tree: `cpack -G DEB` packages the build as it is (no rebuild) into a temporary
# folder; the package holds exactly what `cmake --install --prefix /usr` installs, the two configs are
# conffiles, dpkg-shlibdeps filled Depends, lintian reports no error (E:), and the extracted programs run.
# Usage: check_deb.sh CPACK BUILD_DIR VERSION. Exit 77 (skipped) without dpkg-deb or lintian.
set -eu
cpack="$1" build="$2" version="$3"
for tool in dpkg-deb lintian; do
  command -v "$tool" >/dev/null || { echo "SKIP: $tool is not installed (scripts/setup.sh --test)"; exit 77; }
done
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# 1. Build the package from the build tree.
"$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$tmp/out" >"$tmp/cpack.log" 2>&1 \
  || { cat "$tmp/cpack.log"; fail "cpack -G DEB failed"; }
deb="$tmp/out/toposlam_${version}_$(dpkg --print-architecture).deb"
[ -f "$deb" ] || { cat "$tmp/cpack.log"; fail "no $(basename "$deb") in $(ls "$tmp/out")"; }
echo "package: $(basename "$deb"), $(wc -c <"$deb") bytes"

# 2. Its files: what the install rules put in place with prefix /usr, and these in particular.
dpkg-deb -c "$deb" | awk '$1 !~ /^d/ { print $6 }' | sed 's|^\./|/|' | sort >"$tmp/files"
DESTDIR="$tmp/install" cmake --install "$build" --prefix /usr >/dev/null
(cd "$tmp/install" && find . ! -type d | sed 's|^\./|/|' | sort) >"$tmp/installed"
diff "$tmp/installed" "$tmp/files" >"$tmp/files.diff" \
  || { cat "$tmp/files.diff"; fail "the package's files differ from cmake --install --prefix /usr (< install, > package)"; }
for f in /usr/bin/toposlam /usr/sbin/toposlamd /usr/bin/toposlam-bridge /usr/bin/toposlam-bench \
         /usr/share/man/man1/toposlam-bench.1.gz /usr/lib/systemd/system/toposlamd.service \
         /usr/lib/systemd/system/toposlam-bridge.service \
         /etc/toposlam/toposlam.yaml /etc/toposlam/toposlam-bridge.yaml /usr/share/toposlam/lcm/place_t.lcm \
         /usr/include/toposlam_lcm/place_t.hpp /usr/share/pkgconfig/toposlam-lcm.pc /usr/share/doc/toposlam/copyright \
         /usr/share/doc/toposlam/changelog.gz /usr/share/man/man1/toposlam.1.gz /usr/share/man/man8/toposlamd.8.gz \
         /usr/share/man/man1/toposlam-bridge.1.gz /usr/lib/python3/dist-packages/toposlam_lcm/__init__.py \
         /usr/lib/python3/dist-packages/toposlam_lcm/place_t.py /usr/lib/python3/dist-packages/toposlam_lcm/topology_edge_t.py \
         /usr/lib/python3/dist-packages/toposlam_lcm/udpm_reader.py /usr/share/doc/toposlam/examples/python/listen_places.py \
         /usr/share/doc/toposlam/examples/cpp/listen_places.cpp /usr/share/toposlam/view/live_view.py \
         /usr/share/toposlam/view/live_view.html; do
  grep -qx "$f" "$tmp/files" || fail "the package has no $f (man pages need help2man: scripts/setup.sh)"
done
if grep -E '^/usr/local/|^/usr/etc/' "$tmp/files"; then fail "files outside the FHS paths of a package"; fi
if dpkg-deb -c "$deb" | awk '{ print $2 }' | grep -vx root/root; then fail "files not owned by root/root"; fi

# 3. Control: conffiles, the fields, Depends from dpkg-shlibdeps.
[ "$(dpkg-deb -I "$deb" conffiles)" = "$(printf '/etc/toposlam/toposlam.yaml\n/etc/toposlam/toposlam-bridge.yaml')" ] \
  || fail "conffiles: $(dpkg-deb -I "$deb" conffiles)"
field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = toposlam ] || fail "Package: $(field Package)"
[ "$(field Version)" = "$version" ] || fail "Version: $(field Version), project() says $version"
for f in Maintainer Section Description; do [ -n "$(field "$f")" ] || fail "no $f field"; done
for lib in libc6 liblcm1 libopencv-core libyaml-cpp libsystemd0; do
  field Depends | grep -q "$lib" || fail "Depends (dpkg-shlibdeps) has no $lib: $(field Depends)"
done

# 4. lintian: no error. Warnings are listed (docs/deploy.md says which are expected).
lintian --no-tag-display-limit "$deb" >"$tmp/lintian.log" 2>&1 || true
grep -E '^[EWI]:' "$tmp/lintian.log" || true
if grep -q '^E:' "$tmp/lintian.log"; then fail "lintian reports errors (E:)"; fi
echo "lintian: $(grep -c '^E:' "$tmp/lintian.log") errors, $(grep -c '^W:' "$tmp/lintian.log") warnings"

# 5. Extracted, the programs run: the shipped config is valid, the versions are the package's.
dpkg-deb -x "$deb" "$tmp/root"
out="$("$tmp/root/usr/sbin/toposlamd" --check-config -c "$tmp/root/etc/toposlam/toposlam.yaml" 2>&1)" \
  || fail "toposlamd --check-config on the shipped config: $out"
echo "$out" | grep -q "config OK" || fail "toposlamd --check-config said: $out"
[ "$("$tmp/root/usr/bin/toposlam" --version)" = "toposlam $version" ] || fail "toposlam --version: $("$tmp/root/usr/bin/toposlam" --version)"
[ "$("$tmp/root/usr/sbin/toposlamd" --version)" = "toposlamd $version" ] || fail "toposlamd --version"
[ "$("$tmp/root/usr/bin/toposlam-bridge" --version)" = "toposlam-bridge $version" ] || fail "toposlam-bridge --version"
[ "$("$tmp/root/usr/bin/toposlam-bench" --version)" = "toposlam-bench $version" ] \
  || fail "toposlam-bench --version"
grep -qx "ExecStart=/usr/sbin/toposlamd" "$tmp/root/usr/lib/systemd/system/toposlamd.service" \
  || fail "the packaged unit does not start /usr/sbin/toposlamd"
grep -qx "ExecStart=/usr/bin/toposlam-bridge" "$tmp/root/usr/lib/systemd/system/toposlam-bridge.service" \
  || fail "the packaged bridge unit does not start /usr/bin/toposlam-bridge"
# The shipped bridge config is valid but names no link yet: --check-config says so (exit 2); with one, OK.
rc=0
out="$("$tmp/root/usr/bin/toposlam-bridge" --check-config -c "$tmp/root/etc/toposlam/toposlam-bridge.yaml" 2>&1)" || rc=$?
[ $rc -eq 2 ] && echo "$out" | grep -q "no link" || fail "toposlam-bridge --check-config on the shipped config: $out"
out="$("$tmp/root/usr/bin/toposlam-bridge" --check-config -c "$tmp/root/etc/toposlam/toposlam-bridge.yaml" \
         --serial /dev/ttyACM0 2>&1)" || fail "toposlam-bridge --check-config --serial on the shipped config: $out"
# Both units as packaged: systemd-analyze verify, with the extracted programs in place of /usr's.
if command -v systemd-analyze >/dev/null; then
  for unit in toposlamd toposlam-bridge; do
    sed "s|^ExecStart=/usr/|ExecStart=$tmp/root/usr/|" "$tmp/root/usr/lib/systemd/system/$unit.service" >"$tmp/$unit.service"
    out="$(systemd-analyze verify "$tmp/$unit.service" 2>&1)" && [ -z "$out" ] \
      || fail "systemd-analyze verify of the packaged $unit.service: $out"
  done
  echo "units: systemd-analyze verify accepts toposlamd.service and toposlam-bridge.service"
else
  echo "units: not verified (systemd-analyze not installed; apt-get install systemd)"
fi
# The message headers compile with the flags of the packaged pkg-config file.
cflags="$(PKG_CONFIG_PATH="$tmp/root/usr/share/pkgconfig" pkg-config --cflags toposlam-lcm)" \
  || fail "pkg-config toposlam-lcm"
# shellcheck disable=SC2086  # $cflags is a list of flags
echo '#include <toposlam_lcm/place_event_t.hpp>' | c++ -std=c++17 -fsyntax-only $cflags -x c++ - \
  || fail "toposlam_lcm/place_event_t.hpp does not compile with pkg-config --cflags toposlam-lcm ($cflags)"
# The Python package imports with Debian's python3 (types and reader; no python3-lcm), and the C++ example
# compiles with the packaged headers.
if [ -x /usr/bin/python3 ]; then
  PYTHONPATH="$tmp/root/usr/lib/python3/dist-packages" PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 -c \
    'import toposlam_lcm, toposlam_lcm.udpm_reader as r; e = toposlam_lcm.topology_edge_t(); e.from_node = 1; r.parse_url(r.DEFAULT_URL)' \
    || fail "the packaged Python package toposlam_lcm does not import"
fi
# shellcheck disable=SC2086  # $cflags is a list of flags
c++ -std=c++17 -fsyntax-only $cflags "$tmp/root/usr/share/doc/toposlam/examples/cpp/listen_places.cpp" \
  || fail "the packaged examples/cpp/listen_places.cpp does not compile with pkg-config --cflags toposlam-lcm"
echo "package OK"
