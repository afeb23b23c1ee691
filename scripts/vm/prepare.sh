#!/usr/bin/env bash
# Prepares everything the VM test boots, cached in CACHE_DIR so reruns take a second:
#   - Debian's own kernel (the ABI linux-image-amd64 depends on), downloaded with `apt-get download`,
#     unpacked privately (nothing is installed on the host);
#   - v4l2loopback.ko, built from Debian's v4l2loopback-dkms source against that kernel's headers,
#     which are also only unpacked into the cache (their Makefile is pointed at the private copy);
#   - vimc.ko (the virtual media-controller camera libcamera has a pipeline handler for), which Debian's
#     kernel does not build: compiled the same way from that kernel's linux-source package;
#   - the kernel modules the guest needs (videodev, vivid, vimc, 9p over virtio) with their dependencies,
#     in load order, listed in CACHE_DIR/mods/order (CACHE_DIR/mods/wanted: the list they came from; a
#     cache prepared for another list is prepared again).
# Usage: scripts/vm/prepare.sh CACHE_DIR        Prints the kernel release on success.
# Needs: apt-get (download only), dpkg-deb, xz, make, gcc, kmod (modprobe/depmod). No root needed except
# for apt-get's download cache permissions on some systems.
set -euo pipefail

cache=${1:?usage: prepare.sh CACHE_DIR}
mkdir -p "$cache"
cache=$(cd "$cache" && pwd)
stamp="$cache/prepared.stamp"
# Load order: v4l2loopback comes right after vivid so it still gets /dev/video0; vimc (5 nodes) loads last.
wanted="virtio_pci 9pnet_virtio 9p videodev vivid v4l2loopback vimc"
if [ -f "$stamp" ] && [ -f "$cache/vmlinuz" ] && [ -f "$cache/mods/order" ] &&
   [ "$(cat "$cache/mods/wanted" 2>/dev/null)" = "$wanted" ]; then
  cat "$stamp"
  exit 0
fi

log() { echo "vm-prepare: $*" >&2; }

# The tools it needs, each named with the package that brings it (scripts/setup.sh --test installs them all):
# without one, exit 77 (ctest: skipped) and say what to install, rather than fail half-way.
missing=""
for need in qemu-system-x86_64:qemu-system-x86 depmod:kmod modprobe:kmod xz:xz-utils dpkg-deb:dpkg make:make \
            gcc:gcc apt-get:apt apt-cache:apt cpio:cpio; do
  tool=${need%%:*} package=${need#*:}
  command -v "$tool" >/dev/null 2>&1 || [ -x "/sbin/$tool" ] || [ -x "/usr/sbin/$tool" ] || missing="$missing $tool ($package)"
done
if [ -n "$missing" ]; then
  echo "vm-prepare: skipped: missing$missing; install them with scripts/setup.sh --test" >&2
  exit 77
fi

kpkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/{print $2; exit}')
[ -n "$kpkg" ] || { log "cannot find the kernel package linux-image-amd64 depends on (apt-get update?)"; exit 1; }
kver=${kpkg#linux-image-}
kbuild="linux-kbuild-$(echo "$kver" | cut -d. -f1,2)"
log "kernel $kver"

debs="$cache/debs"
mkdir -p "$debs" "$cache/source"
(
  cd "$debs"
  for p in "$kpkg" "linux-headers-$kver" "linux-headers-${kver%-amd64}-common" "$kbuild" v4l2loopback-dkms; do
    ls "${p}"_*.deb >/dev/null 2>&1 || apt-get download "$p" >&2 2>/dev/null || apt-get download "$p" >&2
  done
)
# Debian's kernel is built without vimc (CONFIG_VIDEO_VIMC is not set): its source comes from the
# kernel's own source package, at exactly the kernel's version, kept out of the unpacked tree below.
kdebver=$(dpkg-deb -f "$debs/${kpkg}"_*.deb Version)
ksrc="linux-source-$(echo "$kver" | cut -d. -f1,2)"
(
  cd "$cache/source"
  ls "${ksrc}_${kdebver}"_*.deb >/dev/null 2>&1 || apt-get download "$ksrc=$kdebver" >&2 2>/dev/null ||
    apt-get download "$ksrc=$kdebver" >&2
)

root="$cache/root"
rm -rf "$root" && mkdir -p "$root"
for d in "$debs"/*.deb; do dpkg-deb -x "$d" "$root"; done

# The headers' Makefile includes the common tree by absolute path: point it at our private copy.
hdr="$root/usr/src/linux-headers-$kver"
sed -i "s|/usr/src/|$root/usr/src/|g" "$hdr/Makefile"
lbsrc=$(echo "$root"/usr/src/v4l2loopback-*)
log "building v4l2loopback.ko from $(basename "$lbsrc")"
make -s -j"$(nproc)" -C "$hdr" M="$lbsrc" modules >"$cache/v4l2loopback-build.log" 2>&1 || {
  cat "$cache/v4l2loopback-build.log" >&2; log "module build failed"; exit 1; }

vimcsrc="$root/vimc-src"
log "building vimc.ko from $ksrc $kdebver"
mkdir -p "$vimcsrc"
dpkg-deb --fsys-tarfile "$cache/source/${ksrc}_${kdebver}"_*.deb | tar -xO "./usr/src/$ksrc.tar.xz" |
  xz -dc | tar -x -C "$vimcsrc" --strip-components=5 "$ksrc/drivers/media/test-drivers/vimc"
make -s -j"$(nproc)" -C "$hdr" M="$vimcsrc" CONFIG_VIDEO_VIMC=m modules >"$cache/vimc-build.log" 2>&1 || {
  cat "$cache/vimc-build.log" >&2; log "vimc build failed"; exit 1; }
# Installed into the private tree so depmod and modprobe --show-depends resolve it like the others.
mkdir -p "$root/lib/modules/$kver/extra"
cp "$vimcsrc/vimc.ko" "$root/lib/modules/$kver/extra/"

depmod -b "$root" "$kver"
mods="$cache/mods"
rm -rf "$mods" && mkdir -p "$mods"
: >"$mods/order"
for m in $wanted; do
  if [ "$m" = v4l2loopback ]; then
    cp "$lbsrc/v4l2loopback.ko" "$mods/" && echo v4l2loopback.ko >>"$mods/order"
    continue
  fi
  deps=$(modprobe -d "$root" -S "$kver" --show-depends "$m") || { log "no module $m in $kpkg"; exit 1; }
  for f in $(echo "$deps" | awk '$1=="insmod"{print $2}'); do
    b=$(basename "$f")
    if ! grep -qx "$b" "$mods/order"; then
      cp "$f" "$mods/"
      echo "$b" >>"$mods/order"
    fi
  done
done
echo "$wanted" >"$mods/wanted"
cp "$root/boot/vmlinuz-$kver" "$cache/vmlinuz"
# The unpacked headers and kernel modules are large and no longer needed.
rm -rf "$root"
echo "$kver" >"$stamp"
cat "$stamp"
