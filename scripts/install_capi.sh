#!/usr/bin/env bash
# Installs nephele's C library for C and C++ programs under PREFIX (Linux):
#   PREFIX/include/nephele.h
#   PREFIX/lib/libnephele_c.a, libnephele_c.so.VERSION (SONAME libnephele_c.so.ABI, with the
#     libnephele_c.so.ABI and libnephele_c.so links)
#   PREFIX/lib/pkgconfig/nephele.pc          pkg-config --cflags --libs nephele
#   PREFIX/lib/cmake/nephele/                find_package(nephele 0.1 REQUIRED), then link
#                                            nephele::nephele (shared) or nephele::nephele_static
# Usage: bash scripts/install_capi.sh PREFIX      (docs/integration.md, "From C and C++")
set -euo pipefail
prefix=${1:?"usage: bash scripts/install_capi.sh PREFIX (e.g. \$HOME/.local or /usr/local)"}
cd "$(dirname "$0")/.."
mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
abi=$(sed -n 's/^const ABI_VERSION: u32 = \([0-9]*\);/\1/p' capi/build.rs)
[ -n "$version" ] && [ -n "$abi" ] || { echo "error: cannot read the version or the ABI version" >&2; exit 1; }
cargo build --release --locked -q -p nephele-c
target=${CARGO_TARGET_DIR:-target}/release
lib="$prefix/lib"
install -d "$prefix/include" "$lib/pkgconfig" "$lib/cmake/nephele"
install -m 644 capi/include/nephele.h "$prefix/include/nephele.h"
install -m 644 "$target/libnephele_c.a" "$lib/libnephele_c.a"
install -m 755 "$target/libnephele_c.so" "$lib/libnephele_c.so.$version"
ln -sf "libnephele_c.so.$version" "$lib/libnephele_c.so.$abi"
ln -sf "libnephele_c.so.$abi" "$lib/libnephele_c.so"

cat > "$lib/pkgconfig/nephele.pc" <<PC
prefix=\${pcfiledir}/../..
libdir=\${prefix}/lib
includedir=\${prefix}/include

Name: nephele
Description: nephele-runtime's C ABI: cloud transport tables and phase models of water droplets
Version: $version
Libs: -L\${libdir} -lnephele_c
Libs.private: -lm -lpthread -ldl
Cflags: -I\${includedir}
PC

cat > "$lib/cmake/nephele/nepheleConfig.cmake" <<CMAKE
# nephele's C library: the targets nephele::nephele (shared, SONAME libnephele_c.so.$abi) and
# nephele::nephele_static, with the header's directory. Written by scripts/install_capi.sh.
get_filename_component(_nephele_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
set(nephele_ABI_VERSION $abi)
if(NOT TARGET nephele::nephele)
  add_library(nephele::nephele SHARED IMPORTED)
  set_target_properties(nephele::nephele PROPERTIES
    IMPORTED_LOCATION "\${_nephele_prefix}/lib/libnephele_c.so.$abi"
    IMPORTED_SONAME "libnephele_c.so.$abi"
    INTERFACE_INCLUDE_DIRECTORIES "\${_nephele_prefix}/include")
  add_library(nephele::nephele_static STATIC IMPORTED)
  set_target_properties(nephele::nephele_static PROPERTIES
    IMPORTED_LOCATION "\${_nephele_prefix}/lib/libnephele_c.a"
    INTERFACE_INCLUDE_DIRECTORIES "\${_nephele_prefix}/include"
    INTERFACE_LINK_LIBRARIES "m;pthread;dl")
endif()
unset(_nephele_prefix)
CMAKE

cat > "$lib/cmake/nephele/nepheleConfigVersion.cmake" <<CMAKE
# Before 1.0 a minor version may break the interface: the same major and minor are compatible.
set(PACKAGE_VERSION "$version")
string(REGEX MATCH "^[0-9]+\\\\.[0-9]+" _have "\${PACKAGE_VERSION}")
string(REGEX MATCH "^[0-9]+\\\\.[0-9]+" _want "\${PACKAGE_FIND_VERSION}")
if(PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION OR (PACKAGE_FIND_VERSION AND NOT _have STREQUAL _want))
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
else()
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
  if(PACKAGE_FIND_VERSION STREQUAL PACKAGE_VERSION)
    set(PACKAGE_VERSION_EXACT TRUE)
  endif()
endif()
CMAKE
echo "installed nephele $version (ABI $abi) under $prefix: include/nephele.h, lib/libnephele_c.{a,so}, lib/pkgconfig/nephele.pc, lib/cmake/nephele/"
