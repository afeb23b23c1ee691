// OpenCV's process-wide settings that must be made before its first call. Linux only.
#pragma once

namespace toposlam {

/// Keeps OpenCV off OpenCL: sets OPENCV_OPENCL_RUNTIME=disabled unless the environment already sets it.
/// Call first thing in main(), before any OpenCV call (OpenCV reads it once). Without it, the first
/// image operation dlopen()s libOpenCL and scans for GPU drivers: start-up time and memory for nothing
/// (every algorithm here runs on the CPU, deterministically); and LeakSanitizer's tracer in GCC 12 crashed
/// reading that late-loaded library's dynamic TLS (docs/architecture.md, "Sanitizers").
void keepOpenCvOffOpenCl();

}  // namespace toposlam
