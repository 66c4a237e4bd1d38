#!/usr/bin/env bash
# Cross-builds navd, navtool and navd_vm_tool (Release) for the arm64 vehicle computer against
# an arm64 sysroot made of Debian 12 packages (hil-tests/vm/README.md "arm64"):
#   hil-tests/vm/cross-build-arm64.sh [--sysroot DIR] [--build DIR]
# --sysroot: default NAV_VM_CACHE or ~/.cache/navd-vm, /sysroot-arm64-<key>; --build: default
# build-arm64 in the source tree. Prints the time of each step.
# 1. Sysroot (cached; the key hashes the package list and this script): apt-get with its own
#    state directory (the host's dpkg and apt lists stay untouched) resolves the arm64 -dev
#    packages navd builds against and downloads their whole dependency closure; each .deb is
#    unpacked with `dpkg-deb -x` (headers, libraries and CMake/pkg-config files need no
#    maintainer script). Absolute symbolic links are made relative so that they resolve inside
#    the sysroot. Multiarch does not do here: LCM's and OpenCV's arm64 -dev packages conflict with
#    the amd64 ones (docs/platform.md "Cross builds and emulation").
# 2. cmake with toolchains/aarch64-linux-gnu.cmake and NAV_SYSROOT (tests, benchmarks off),
#    ninja navd navtool navd_vm_tool (the VM scenarios' helper). Host tools (lcm-gen, esbuild)
#    run natively.
# Needs g++-aarch64-linux-gnu (installed here with apt-get when missing; root), dpkg-deb,
# apt-get, cmake, ninja.
set -euo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
cache=${NAV_VM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/navd-vm}
sysroot=""
build=$src/build-arm64
while [ $# -gt 0 ]; do
  case "$1" in
    --sysroot) sysroot=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    *) echo "cross-build-arm64.sh: unknown argument '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
mirror=${NAV_VM_MIRROR:-http://deb.debian.org/debian}
# The arm64 -dev packages of scripts/install-deps that navd and navtool link (no test
# frameworks), plus the target's C/C++ runtime development files.
packages=(libc6-dev libstdc++-12-dev libgcc-12-dev
  libeigen3-dev libsuitesparse-dev libceres-dev libopencv-dev
  liblcm-dev libyaml-cpp-dev libspdlog-dev libfmt-dev libcli11-dev libconcurrentqueue-dev
  libreaderwriterqueue-dev libsystemd-dev nlohmann-json3-dev libssl-dev
  libgpiod-dev libaravis-dev libusb-1.0-0-dev libv4l-dev libwebsocketpp-dev libasio-dev)
secs() { echo $(( $(date +%s) - $1 )); }

if ! command -v aarch64-linux-gnu-g++ > /dev/null; then
  echo "cross-build-arm64.sh: installing g++-aarch64-linux-gnu" >&2
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends g++-aarch64-linux-gnu
fi

# The sysroot in directory $1 (see the header); its cache key hashes this function's text.
make_sysroot() {
  local sysroot=$1 apt_dir=$1.apt t0 debs deb link target lib so multi
  t0=$(date +%s)
  rm -rf "$sysroot" "$apt_dir"; mkdir -p "$sysroot"
  mkdir -p "$apt_dir/state/lists/partial" "$apt_dir/cache/archives/partial"
  echo "deb [arch=arm64 signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] $mirror bookworm main" \
    > "$apt_dir/sources.list"
  : > "$apt_dir/status"  # nothing installed: the download is the whole closure
  local apt_opts=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o "Dir::Etc::SourceParts=/dev/null"
    -o "Dir::State=$apt_dir/state" -o "Dir::State::status=$apt_dir/status"
    -o "Dir::Cache=$apt_dir/cache" -o "APT::Architecture=arm64" -o "APT::Architectures::=arm64"
    -o "Debug::NoLocking=1" -o "APT::Install-Recommends=0" -o "APT::Sandbox::User=root")
  apt-get "${apt_opts[@]}" update -qq
  apt-get "${apt_opts[@]}" install -y -qq --download-only "${packages[@]}" > "$apt_dir/download.log"
  debs=("$apt_dir"/cache/archives/*.deb)
  echo "cross-build-arm64.sh: ${#debs[@]} packages downloaded ($(du -sm "$apt_dir/cache" | cut -f1) MB) in $(secs "$t0") s" >&2
  for deb in "${debs[@]}"; do dpkg-deb -x "$deb" "$sysroot"; done
  # Absolute links (e.g. libfoo.so -> /lib/aarch64-linux-gnu/libfoo.so.1) made relative.
  find "$sysroot" -type l -lname '/*' | while read -r link; do
    target=$(readlink "$link")
    ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$sysroot$target")" "$link"
  done
  # What update-alternatives does in libblas3's and liblapack3's maintainer scripts: the
  # generic libblas.so / liblapack.so (Ceres' FindSuiteSparse links them) point to the
  # reference implementations in blas/ and lapack/.
  multi=$sysroot/usr/lib/aarch64-linux-gnu
  for lib in blas lapack; do
    for so in "$multi/$lib/lib$lib.so" "$multi/$lib/lib$lib.so.3"; do
      [ -e "$so" ] && ln -sfn "$lib/$(basename "$so")" "$multi/$(basename "$so")"
    done
  done
  rm -rf "$apt_dir"
  touch "$sysroot/.complete"
  echo "cross-build-arm64.sh: sysroot $sysroot ($(du -sm "$sysroot" | cut -f1) MB) in $(secs "$t0") s" >&2
}

# CMake package files that name target paths absolutely (Ceres' LAPACK/BLAS libraries,
# Imath's include directory) would hand the host's /usr to the cross build: they get
# ${CMAKE_SYSROOT} in front. Idempotent (a prefixed path no longer matches), run every time.
prefix_cmake_paths() {
  local files
  files=$(grep -rlE '[";](/usr/include|/usr/lib/aarch64-linux-gnu)' --include='*.cmake' "$1/usr" || true)
  [ -z "$files" ] && return
  echo "$files" | xargs sed -i -E 's#([";])(/usr/include|/usr/lib/aarch64-linux-gnu)#\1${CMAKE_SYSROOT}\2#g'
}

key=$( (echo "$mirror ${packages[*]}"; declare -f make_sysroot) | sha256sum | cut -c1-16)
sysroot=${sysroot:-$cache/sysroot-arm64-$key}
t0=$(date +%s)
if [ -f "$sysroot/.complete" ]; then
  echo "cross-build-arm64.sh: sysroot $sysroot (cached)" >&2
else
  make_sysroot "$sysroot"
fi
prefix_cmake_paths "$sysroot"

t1=$(date +%s)
export NAV_SYSROOT=$sysroot  # read by the toolchain file at every (re)configure
mkdir -p "$build"
cmake -S "$src" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$src/toolchains/aarch64-linux-gnu.cmake" \
  -DNAV_BUILD_TESTS=OFF -DNAV_BUILD_BENCH=OFF > "$build/cross-cmake.log" 2>&1 || {
  echo "cross-build-arm64.sh: cmake failed, last lines of $build/cross-cmake.log:" >&2
  tail -20 "$build/cross-cmake.log" >&2; exit 1; }
echo "cross-build-arm64.sh: configured in $(secs "$t1") s" >&2
t2=$(date +%s)
ninja -C "$build" -j"${NAV_JOBS:-2}" navd navtool navd_vm_tool
for bin in navd navtool navd_vm_tool; do
  file "$build/bin/$bin" | grep -q "ARM aarch64" || {
    echo "cross-build-arm64.sh: $build/bin/$bin is not an aarch64 executable" >&2; exit 1; }
done
echo "cross-build-arm64.sh: navd, navtool and navd_vm_tool built in $(secs "$t2") s (total $(secs "$t0") s)" >&2
