# Cross build for 64-bit ARM Linux (Debian's aarch64-linux-gnu-gcc) against an arm64 sysroot of Debian
# bookworm's packages. Used by scripts/cross-arm64, which makes the sysroot; by hand:
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64-linux-gnu.cmake \
#         -DLIVO_ARM64_SYSROOT=/path/to/sysroot
# LIVO_ARM64_MARCH (default armv8.2-a: Cortex-A76 and A55 of the RK3588, Jetson Orin's A78AE, the
# Raspberry Pi 5's A76; use armv8-a for a Pi 4's A72) sets -march. No -march=native here ever.
# The tests run through qemu-user (CMAKE_CROSSCOMPILING_EMULATOR), so that ctest and GoogleTest's
# discovery work on an x86 machine: scripts/test-arm64.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(LIVO_ARM64_SYSROOT "" CACHE PATH "arm64 Debian sysroot (scripts/cross-arm64 makes one)")
set(LIVO_ARM64_MARCH "armv8.2-a" CACHE STRING "-march of the arm64 build")
if(NOT LIVO_ARM64_SYSROOT OR NOT EXISTS "${LIVO_ARM64_SYSROOT}/usr/include")
  message(FATAL_ERROR "LIVO_ARM64_SYSROOT='${LIVO_ARM64_SYSROOT}' is not an arm64 sysroot (no usr/include): "
                      "make one with scripts/cross-arm64")
endif()
# try_compile projects see the toolchain file again: hand them the cache values.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES LIVO_ARM64_SYSROOT LIVO_ARM64_MARCH)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_SYSROOT "${LIVO_ARM64_SYSROOT}")
set(CMAKE_C_FLAGS_INIT "-march=${LIVO_ARM64_MARCH}")
set(CMAKE_CXX_FLAGS_INIT "-march=${LIVO_ARM64_MARCH}")
# The sysroot's libraries name their dependencies by absolute paths in the target's layout (/lib/...,
# /usr/lib/aarch64-linux-gnu/...): the linker resolves them inside the sysroot.
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "-Wl,-rpath-link,${LIVO_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu -Wl,-rpath-link,${LIVO_ARM64_SYSROOT}/lib/aarch64-linux-gnu")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "${CMAKE_EXE_LINKER_FLAGS_INIT}")

# Libraries, headers and CMake packages from the sysroot only; programs (lcm-gen, python3) from the host.
set(CMAKE_FIND_ROOT_PATH "${LIVO_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${LIVO_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${LIVO_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${LIVO_ARM64_SYSROOT}/usr/share/pkgconfig")

find_program(LIVO_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(LIVO_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${LIVO_QEMU_AARCH64};-L;${LIVO_ARM64_SYSROOT}")
endif()
