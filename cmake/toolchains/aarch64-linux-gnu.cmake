# Cross build for arm64 (aarch64) rig computers from an amd64 Debian 12 machine (docs/arm64.md).
# Compilers: crossbuild-essential-arm64. Libraries: a sysroot made of Debian 12's arm64 packages by
# scripts/arm64_sysroot.sh. Not the host's multiarch :arm64 packages: liblcm-dev, glog and gflags
# (under Ceres) are not Multi-Arch: same, so installing them for arm64 would remove the host's own.
# Build-time tools (lcm-gen) are the host's; test executables run under qemu-user.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

set(FURUTA_ARM64_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../../build/arm64-sysroot/root"
    CACHE PATH "Root made of Debian 12's arm64 packages (scripts/arm64_sysroot.sh)")
get_filename_component(FURUTA_ARM64_SYSROOT "${FURUTA_ARM64_SYSROOT}" ABSOLUTE)
if(NOT EXISTS "${FURUTA_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/libc.so.6")
  message(FATAL_ERROR "No arm64 sysroot at ${FURUTA_ARM64_SYSROOT}: run scripts/arm64_sysroot.sh")
endif()
set(CMAKE_SYSROOT "${FURUTA_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH "${FURUTA_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# The libraries' own dependencies (Ceres -> SuiteSparse -> BLAS) are found at link time in the root.
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,-rpath-link,${FURUTA_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-Wl,-rpath-link,${FURUTA_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")

# pkg-config reads the root's .pc files and prefixes their paths with it.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${FURUTA_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${FURUTA_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${FURUTA_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# ctest and gtest_discover_tests run the arm64 executables through qemu-user, with the root as the
# place its dynamic loader and libraries are read from.
find_program(FURUTA_QEMU_AARCH64 qemu-aarch64-static qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${FURUTA_QEMU_AARCH64};-L;${FURUTA_ARM64_SYSROOT}")

# The .deb: the target's architecture (CPack would ask the host's dpkg).
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
