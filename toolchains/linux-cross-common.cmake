# Shared part of the Debian cross toolchains: compilers by triple, multiarch or sysroot library
# lookup, pkg-config for the target, and qemu-user so ctest runs the cross-built tests.
set(CMAKE_C_COMPILER ${NAV_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${NAV_TRIPLE}-g++)

if(DEFINED ENV{NAV_SYSROOT})
  set(CMAKE_SYSROOT $ENV{NAV_SYSROOT})
  set(CMAKE_FIND_ROOT_PATH $ENV{NAV_SYSROOT})
  set(NAV_QEMU_LD_PREFIX $ENV{NAV_SYSROOT})
  # pkg-config reads the sysroot's .pc files and prefixes their paths with it (without this it
  # hands the host's /usr/include and amd64 libraries to the cross build).
  set(ENV{PKG_CONFIG_SYSROOT_DIR} $ENV{NAV_SYSROOT})
  set(ENV{PKG_CONFIG_LIBDIR} "$ENV{NAV_SYSROOT}/usr/lib/${NAV_TRIPLE}/pkgconfig:$ENV{NAV_SYSROOT}/usr/lib/pkgconfig:$ENV{NAV_SYSROOT}/usr/share/pkgconfig")
  set(NAV_FIND_ROOT_MODE ONLY)  # headers and CMake packages from the sysroot only
else()
  # Debian multiarch: target libraries in /usr/lib/<triple>, headers shared in /usr/include.
  set(CMAKE_LIBRARY_ARCHITECTURE ${NAV_TRIPLE})
  set(CMAKE_FIND_ROOT_PATH /usr/${NAV_TRIPLE} /usr)
  set(NAV_QEMU_LD_PREFIX /usr/${NAV_TRIPLE})
  set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${NAV_TRIPLE}/pkgconfig:/usr/share/pkgconfig)
  set(NAV_FIND_ROOT_MODE BOTH)  # arch-independent headers and CMake files are the host's
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ${NAV_FIND_ROOT_MODE})
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ${NAV_FIND_ROOT_MODE})

string(REGEX REPLACE "-linux-gnu.*$" "" NAV_QEMU_ARCH ${NAV_TRIPLE})
if(NAV_QEMU_ARCH STREQUAL "arm")
  set(NAV_QEMU_ARCH arm)
endif()
find_program(NAV_QEMU qemu-${NAV_QEMU_ARCH})
if(NAV_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${NAV_QEMU} -L ${NAV_QEMU_LD_PREFIX})
endif()
