# Shared part of the Debian cross toolchains: compilers by triple, multiarch or sysroot library
# lookup, pkg-config for the target, and qemu-user so ctest runs the cross-built tests.
set(CMAKE_C_COMPILER ${NAV_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${NAV_TRIPLE}-g++)

if(DEFINED ENV{NAV_SYSROOT})
  set(CMAKE_SYSROOT $ENV{NAV_SYSROOT})
  set(CMAKE_FIND_ROOT_PATH $ENV{NAV_SYSROOT})
  set(NAV_QEMU_LD_PREFIX $ENV{NAV_SYSROOT})
else()
  # Debian multiarch: target libraries in /usr/lib/<triple>, headers shared in /usr/include.
  set(CMAKE_LIBRARY_ARCHITECTURE ${NAV_TRIPLE})
  set(CMAKE_FIND_ROOT_PATH /usr/${NAV_TRIPLE} /usr)
  set(NAV_QEMU_LD_PREFIX /usr/${NAV_TRIPLE})
  set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${NAV_TRIPLE}/pkgconfig:/usr/share/pkgconfig)
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

string(REGEX REPLACE "-linux-gnu.*$" "" NAV_QEMU_ARCH ${NAV_TRIPLE})
if(NAV_QEMU_ARCH STREQUAL "arm")
  set(NAV_QEMU_ARCH arm)
endif()
find_program(NAV_QEMU qemu-${NAV_QEMU_ARCH})
if(NAV_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${NAV_QEMU} -L ${NAV_QEMU_LD_PREFIX})
endif()
