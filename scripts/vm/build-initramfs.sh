#!/usr/bin/env bash
# Builds the VM test's initramfs: a static busybox, the kernel modules prepared by prepare.sh (in load
# order) and an /init that loads them (videodev, vivid, v4l2loopback, vimc, 9p), mounts the host's root
# read-only over 9p at /host, and runs the guest script given on the kernel command line
# (tsguest=/path/guest.sh tsbuild=/path/build) inside `chroot /host`, then powers off.
# Usage: scripts/vm/build-initramfs.sh CACHE_DIR OUTPUT.cpio.gz
set -euo pipefail

cache=${1:?usage: build-initramfs.sh CACHE_DIR OUTPUT}
output=${2:?usage: build-initramfs.sh CACHE_DIR OUTPUT}
busybox=/bin/busybox  # from busybox-static (statically linked: nothing else needed in the initramfs)
[ -x "$busybox" ] || { echo "build-initramfs: busybox-static is not installed" >&2; exit 1; }
[ -f "$cache/mods/order" ] || { echo "build-initramfs: run scripts/vm/prepare.sh $cache first" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work"/{bin,proc,sys,dev,mods,host}
cp "$busybox" "$work/bin/busybox"
for applet in sh mount umount insmod poweroff cat echo sleep chroot mkdir ls; do
  ln -sf busybox "$work/bin/$applet"
done
cp "$cache"/mods/*.ko "$cache/mods/order" "$work/mods/"

cat >"$work/init" <<'INIT'
#!/bin/sh
# toposlam VM test guest init (busybox). Prints "VMTEST ..." lines the host looks for.
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(cat /mods/order); do
  case $m in
    v4l2loopback.ko) insmod /mods/$m devices=1 video_nr=0 exclusive_caps=0 card_label=toposlam-loopback ;;
    vivid.ko) insmod /mods/$m n_devs=1 node_types=0x1 vid_cap_nr=1 ;;
    *) insmod /mods/$m ;;
  esac || echo "VMTEST FAIL insmod $m"
done
if mount -t 9p -o trans=virtio,version=9p2000.L,ro,cache=loose,msize=512000 host /host; then
  mount -t proc proc /host/proc
  mount -t sysfs sys /host/sys
  mount -t devtmpfs dev /host/dev
  # /tmp in the guest is a writable tmpfs; a checkout or build folder under the host's /tmp (CI clones
  # may live there) is bound back over it so the guest still sees the project.
  mkdir -p /hosttmp
  mount -o bind /host/tmp /hosttmp
  mount -t tmpfs tmp /host/tmp
  for dir in "${tsguest%/tests/vm/guest.sh}" "$tsbuild"; do
    case "$dir" in
      /tmp/?*) mkdir -p "/host$dir" && mount -o bind "/hosttmp${dir#/tmp}" "/host$dir" ||
                 echo "VMTEST FAIL cannot bind $dir over the guest's /tmp" ;;
    esac
  done
  mount -t tmpfs run /host/run
  # The boot time on the guest's own clock: the machine's slowness now (tests/vm/budget.sh), for the host's
  # watcher (this line) and the guest script's own timeouts (tsboot, inherited through chroot).
  tsboot=$(cut -d" " -f1 /proc/uptime)
  export tsboot
  echo "VMTEST BOOTED [$tsboot s]"
  chroot /host /bin/sh "$tsguest" "$tsbuild"
  echo "VMTEST GUEST-EXIT rc=$?"
else
  echo "VMTEST FAIL cannot mount the host root over 9p"
fi
poweroff -f
INIT
chmod +x "$work/init"
(cd "$work" && find . | cpio -o -H newc --quiet | gzip -1) >"$output"
