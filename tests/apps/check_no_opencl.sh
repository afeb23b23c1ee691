#!/bin/sh
# OpenCV stays off OpenCL (platform/os/opencv_runtime.hpp): `toposlam segment` and `toposlamd` on image
# files never load libOpenCL (the dynamic loader's own trace, LD_DEBUG=files, names every library loaded),
# and a user's OPENCV_OPENCL_RUNTIME is left as it is. Without keepOpenCvOffOpenCl() the first image
# operation loads it (and, under LeakSanitizer, crashed its tracer at exit).
# Usage: check_no_opencl.sh TOPOSLAM TOPOSLAMD SAMPLES_DIR OUT_DIR
set -u
toposlam=$1 toposlamd=$2 samples=$3 out=$4
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
LD_DEBUG=files "$toposlam" segment "images:$samples?fps=1" --out "$out/seg" >/dev/null 2>"$out/segment.trace" ||
  fail "segment exited $?"
grep -q "libopencv_imgproc" "$out/segment.trace" || fail "no loader trace (LD_DEBUG ignored?)"
grep -q "libOpenCL" "$out/segment.trace" && fail "toposlam segment loaded libOpenCL"
LD_DEBUG=files "$toposlamd" --source "images:$samples?fps=1" --map '' --lcm-url memq:// >/dev/null 2>"$out/daemon.trace" ||
  fail "toposlamd exited $?"
grep -q "libOpenCL" "$out/daemon.trace" && fail "toposlamd loaded libOpenCL"
# A user's choice wins: with the runtime named explicitly, OpenCV may load it (only checked where installed).
if [ -e /usr/lib/x86_64-linux-gnu/libOpenCL.so.1 ]; then
  OPENCV_OPENCL_RUNTIME=/usr/lib/x86_64-linux-gnu/libOpenCL.so.1 LD_DEBUG=files "$toposlam" segment \
    "images:$samples?fps=1" --out "$out/seg2" >/dev/null 2>"$out/user.trace" || fail "segment exited $?"
  grep -q "libOpenCL" "$out/user.trace" || fail "the user's OPENCV_OPENCL_RUNTIME was overridden"
fi
echo "no OpenCL OK"
