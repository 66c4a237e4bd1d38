# Cross toolchain for the vehicle computer: 64-bit ARM (aarch64) Debian 12.
# Needs g++-aarch64-linux-gnu and the arm64 -dev packages of the libraries (multiarch for core
# and drivers; a full daemon build needs an arm64 sysroot, see docs/platform.md), e.g.
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake
# Set NAV_SYSROOT to build against a debootstrap'ed sysroot instead of multiarch.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(NAV_TRIPLE aarch64-linux-gnu)
include(${CMAKE_CURRENT_LIST_DIR}/linux-cross-common.cmake)
