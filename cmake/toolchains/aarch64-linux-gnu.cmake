# Cross-compiling toposlam for 64-bit ARM Linux (arm64 / aarch64) with Debian's cross compiler
# (g++-aarch64-linux-gnu). scripts/cross-arm64.sh uses it; docs/arm64.md says how and why.
#
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake \
#         [-DTOPOSLAM_ARM64_SYSROOT=/path/to/sysroot]
#
# Where the arm64 libraries (OpenCV, yaml-cpp, LCM, ...) come from:
#  - TOPOSLAM_ARM64_SYSROOT set: a folder holding Debian's arm64 packages unpacked (usr/, lib/, etc/), as
#    scripts/cross-arm64.sh makes it. This is the way that works beside a native build: on Debian 12,
#    libopencv-dev, liblcm-dev and libyaml-cpp-dev are not Multi-Arch: same, so their :arm64 form cannot be
#    installed next to the :amd64 one (docs/arm64.md has apt's answer).
#  - TOPOSLAM_ARM64_SYSROOT empty: Debian multiarch, the :arm64 -dev packages installed by dpkg into
#    /usr/lib/aarch64-linux-gnu on this machine.
# Tests run through qemu-user (CMAKE_CROSSCOMPILING_EMULATOR), so ctest and Catch2's test discovery work.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(TOPOSLAM_ARM64_SYSROOT "$ENV{TOPOSLAM_ARM64_SYSROOT}" CACHE PATH
    "Unpacked Debian arm64 packages to build against (empty: the multiarch packages in /usr)")
# try_compile() projects read this file again without the cache: hand the variable on to them.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES TOPOSLAM_ARM64_SYSROOT)

find_program(TOPOSLAM_ARM64_CC aarch64-linux-gnu-gcc)
find_program(TOPOSLAM_ARM64_CXX aarch64-linux-gnu-g++)
if(NOT TOPOSLAM_ARM64_CC OR NOT TOPOSLAM_ARM64_CXX)
  message(FATAL_ERROR "aarch64 toolchain: aarch64-linux-gnu-gcc / aarch64-linux-gnu-g++ not found on PATH. "
                      "Install Debian's cross compiler: apt-get install gcc-aarch64-linux-gnu g++-aarch64-linux-gnu "
                      "(scripts/cross-arm64.sh does it).")
endif()
set(CMAKE_C_COMPILER ${TOPOSLAM_ARM64_CC})
set(CMAKE_CXX_COMPILER ${TOPOSLAM_ARM64_CXX})

if(TOPOSLAM_ARM64_SYSROOT)
  if(NOT EXISTS ${TOPOSLAM_ARM64_SYSROOT}/usr/include/aarch64-linux-gnu)
    message(FATAL_ERROR "aarch64 toolchain: TOPOSLAM_ARM64_SYSROOT=${TOPOSLAM_ARM64_SYSROOT} holds no arm64 "
                        "libc headers (usr/include/aarch64-linux-gnu). Make it with scripts/cross-arm64.sh.")
  endif()
  set(CMAKE_SYSROOT ${TOPOSLAM_ARM64_SYSROOT})
  set(CMAKE_FIND_ROOT_PATH ${TOPOSLAM_ARM64_SYSROOT})
  set(_toposlam_arm64_root ${TOPOSLAM_ARM64_SYSROOT})
  # Shared libraries that the libraries we link need (OpenCV's GDAL, HDF5, ...) are looked up in the sysroot.
  string(APPEND CMAKE_EXE_LINKER_FLAGS_INIT
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/lib/aarch64-linux-gnu"
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
  string(APPEND CMAKE_SHARED_LINKER_FLAGS_INIT
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/lib/aarch64-linux-gnu"
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
  string(APPEND CMAKE_MODULE_LINKER_FLAGS_INIT
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/lib/aarch64-linux-gnu"
         " -Wl,-rpath-link,${TOPOSLAM_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
  set(ENV{PKG_CONFIG_SYSROOT_DIR} ${TOPOSLAM_ARM64_SYSROOT})
  set(ENV{PKG_CONFIG_LIBDIR}
      "${TOPOSLAM_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${TOPOSLAM_ARM64_SYSROOT}/usr/share/pkgconfig")
else()
  # Multiarch: the arm64 libraries live beside the native ones under /usr; headers are shared.
  set(_toposlam_arm64_root /usr/aarch64-linux-gnu)  # Debian's cross libc, for qemu's -L
  set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")
endif()

# Libraries, headers and CMake packages for the target only; programs (lcm-gen, python3) from the build host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Run the arm64 test programs (ctest, Catch2's discovery at build time) under qemu-user. -L: where qemu finds
# the arm64 dynamic loader and libraries.
find_program(TOPOSLAM_QEMU_AARCH64 NAMES qemu-aarch64 qemu-aarch64-static)
if(TOPOSLAM_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${TOPOSLAM_QEMU_AARCH64} -L ${_toposlam_arm64_root})
else()
  message(WARNING "aarch64 toolchain: no qemu-aarch64 on PATH, so the arm64 tests cannot run here "
                  "(apt-get install qemu-user). Build only.")
endif()
