#!/usr/bin/env bash
# The packaging test (ctest `consumer_packaging`): installs an already built sketchbody to a
# temporary prefix and checks the installed files (SONAME, symlinks, only skb_* exported), then
# builds and runs cpp_tests/consumer three ways, shared and static each:
#   1. find_package(sketchbody) from the prefix (plus examples/plugin_host.cpp, run on the example),
#   2. pkg-config (sketchbody.pc; Libs.private for the static link),
#   3. add_subdirectory of the source tree, sharing cargo's folder and the parent build's cargo
#      selection and profile (SKB_CARGO_SELECTION, SKB_CARGO_PROFILE: cargo has nothing to
#      rebuild), checking
#      that it writes nothing into the source tree (no new files, Cargo.lock untouched: what a
#      read-only checkout needs) and that the tests default to OFF.
# Usage: run.sh SOURCE_DIR BUILD_DIR CARGO_TARGET_DIR BUILD_TYPE [CARGO_SELECTION [CARGO_PROFILE]]
set -euo pipefail
src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
cargo_dir=$3
build_type=${4:-Release}
selection=${5:--p;sketchbody-capi}
profile=${6:-}
here="$src/cpp_tests/consumer"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/skb-consumer.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
fail() { echo "FAIL: $*" >&2; exit 1; }

echo "== cmake --install to a temporary prefix"
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; fail "install"; }
version=$(sed -n 's/^#define SKB_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)$/\2/p' "$src/include/sketchbody.h" | paste -sd.)
major=${version%%.*}
libdir=$(dirname "$(find "$prefix" -name "libsketchbody.so.$version" -type f | head -n 1)")
[ -f "$libdir/libsketchbody.so.$version" ] || fail "libsketchbody.so.$version not installed"
for f in include/sketchbody.h include/sketchbody.hpp; do [ -f "$prefix/$f" ] || fail "$f not installed"; done
for f in libsketchbody.a cmake/sketchbody/sketchbodyConfig.cmake cmake/sketchbody/sketchbodyConfigVersion.cmake \
         pkgconfig/sketchbody.pc; do
  [ -f "$libdir/$f" ] || fail "$f not installed in $libdir"
done
[ "$(readlink "$libdir/libsketchbody.so.$major")" = "libsketchbody.so.$version" ] || fail "libsketchbody.so.$major symlink"
[ "$(readlink "$libdir/libsketchbody.so")" = "libsketchbody.so.$major" ] || fail "libsketchbody.so symlink"
(cd "$prefix" && find . \( -type f -o -type l \) -printf '%P %s bytes%l\n' | sed 's/bytes\(.\)/bytes -> \1/' | sort)
soname=$(readelf -d "$libdir/libsketchbody.so.$version" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
echo "SONAME: $soname"
[ "$soname" = "libsketchbody.so.$major" ] || fail "SONAME is '$soname'"
exported=$(nm -D --defined-only "$libdir/libsketchbody.so.$version" | awk '{print $3}')
others=$(grep -v '^skb_' <<<"$exported" || true)
[ -z "$others" ] || fail "non-skb_ symbols exported: $(head -n 5 <<<"$others" | paste -sd' ')"
echo "exported: $(wc -l <<<"$exported") symbols, all skb_*"
# What install strips (cmake/install.cmake): the .so's debug info and static symbol table, the
# .a's debug info and LLVM bitcode. Debug, RelWithDebInfo and SKB_KEEP_DEBUG_INFO=ON keep them.
so_sections=$(readelf -SW "$libdir/libsketchbody.so.$version")
a_sections=$(readelf -SW "$libdir/libsketchbody.a")
if [[ "$build_type" =~ ^(Debug|RelWithDebInfo)$ ]]; then
  echo "debug info kept ($build_type)"
elif grep -q 'SKB_KEEP_DEBUG_INFO:BOOL=ON' "$build/CMakeCache.txt"; then
  echo "debug info kept (SKB_KEEP_DEBUG_INFO=ON)"
else
  for unneeded in '\.debug_info' '\.symtab'; do
    ! grep -q " $unneeded " <<<"$so_sections" || fail "installed .so has a ${unneeded#\\} section"
  done
  for unneeded in '\.debug_info' '\.llvmbc'; do
    ! grep -q " $unneeded " <<<"$a_sections" || fail "installed .a has ${unneeded#\\} sections"
  done
  echo "stripped: no debug info or static symbol table in the .so, no debug info or LLVM bitcode in the .a"
fi
mb() { awk -v b="$(stat -c %s "$1")" 'BEGIN { printf "%.1f MB", b / 1e6 }'; }
echo "installed sizes: libsketchbody.so.$version $(mb "$libdir/libsketchbody.so.$version"), libsketchbody.a $(mb "$libdir/libsketchbody.a")"

# Runs ./NAME, prints its line; checks whether libsketchbody.so is a runtime dependency.
run_consumer() {
  local exe=$1 want_needed=$2 needed
  needed=$(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(libsketchbody[^]]*\)\]/\1/p')
  if [ "$want_needed" = shared ]; then
    [ "$needed" = "libsketchbody.so.$major" ] || fail "$exe needs '$needed', want libsketchbody.so.$major"
  else
    [ -z "$needed" ] || fail "$exe (static) still needs $needed"
  fi
  "$exe" || fail "$exe exited non-zero"
}

echo "== 1. find_package(sketchbody) after install"
cmake -S "$here" -B "$tmp/pkg" -DCMAKE_BUILD_TYPE="$build_type" -DCMAKE_PREFIX_PATH="$prefix" \
  -DSKB_CONSUMER_MODE=package -DSKB_PLUGIN_HOST="$src/examples/plugin_host.cpp" >"$tmp/pkg.log" \
  || { cat "$tmp/pkg.log"; fail "find_package configure"; }
cmake --build "$tmp/pkg" >>"$tmp/pkg.log" 2>&1 || { cat "$tmp/pkg.log"; fail "find_package build"; }
run_consumer "$tmp/pkg/consumer_shared" shared
run_consumer "$tmp/pkg/consumer_static" static
"$tmp/pkg/plugin_host" "$src/assets/examples/sketch.png" "$src/assets/examples/sketch_joints.json" \
  >"$tmp/plugin_host.log" 2>&1 || { cat "$tmp/plugin_host.log"; fail "plugin_host against the installed package"; }
echo "plugin_host (installed package): $(grep -m 1 "vertices" "$tmp/plugin_host.log")"

echo "== 2. pkg-config"
export PKG_CONFIG_PATH="$libdir/pkgconfig"
cc=${CC:-cc}
shared_libs=$(pkg-config --libs sketchbody)
static_libs=$(pkg-config --static --libs sketchbody)
private=${static_libs#"$shared_libs"}
echo "pkg-config --libs: $shared_libs; Libs.private: $private"
# shellcheck disable=SC2046,SC2086
"$cc" -o "$tmp/pc_shared" "$here/main.c" -DSKB_CONSUMER_HOW='"pkg-config/shared"' $(pkg-config --cflags sketchbody) \
  $shared_libs -Wl,-rpath,"$(pkg-config --variable=libdir sketchbody)"
# shellcheck disable=SC2046,SC2086
"$cc" -o "$tmp/pc_static" "$here/main.c" -DSKB_CONSUMER_HOW='"pkg-config/static"' $(pkg-config --cflags sketchbody) \
  "$(pkg-config --variable=libdir sketchbody)/libsketchbody.a" $private
run_consumer "$tmp/pc_shared" shared
run_consumer "$tmp/pc_static" static

echo "== 3. add_subdirectory(sketchbody source tree)"
# What would show a write into the source tree: new untracked files (git), a rewritten
# Cargo.lock, anything new in <source>/target unless that is the cargo folder in use. (Edits to
# tracked files by someone working in the tree while the test runs are not counted.)
untracked() { git -C "$src" status --porcelain --untracked-files=all 2>/dev/null | grep '^??' | sort || true; }
untracked >"$tmp/untracked.before"
touch "$tmp/stamp"
# CC and CXX stay out of this build's environment (the compilers go in as cache variables): the
# cc crate's build scripts (tract-linalg's) rerun when CC changes, and cargo then recompiles
# tract and everything above it instead of reusing the parent build.
nocc=(env -u CC -u CXX)
"${nocc[@]}" cmake -S "$here" -B "$tmp/sub" -DCMAKE_BUILD_TYPE="$build_type" -DSKB_CONSUMER_MODE=subdir \
  -DCMAKE_C_COMPILER="${CC:-cc}" -DCMAKE_CXX_COMPILER="${CXX:-c++}" \
  -DSKETCHBODY_SOURCE_DIR="$src" -DSKB_CARGO_TARGET_DIR="$cargo_dir" \
  -DSKB_CARGO_SELECTION="$selection" -DSKB_CARGO_PROFILE="$profile" >"$tmp/sub.log" \
  || { cat "$tmp/sub.log"; fail "add_subdirectory configure"; }
grep -q '^SKB_BUILD_TESTS:BOOL=OFF$' "$tmp/sub/CMakeCache.txt" || fail "SKB_BUILD_TESTS is not OFF under add_subdirectory"
"${nocc[@]}" cmake --build "$tmp/sub" >>"$tmp/sub.log" 2>&1 || { cat "$tmp/sub.log"; fail "add_subdirectory build"; }
grep -E '^ *(Finished|Compiling)' "$tmp/sub.log" | sed 's/^ */cargo: /'
cargo_abs=$(cd "$cargo_dir" && pwd)
written=$(comm -13 "$tmp/untracked.before" <(untracked) | grep -v -e "^?? ${build#"$src"/}/" -e "^?? ${cargo_abs#"$src"/}/" || true)
[ "$src/Cargo.lock" -nt "$tmp/stamp" ] && written="$written Cargo.lock"
if [ -d "$src/target" ] && [ "$cargo_abs" != "$src/target" ]; then
  written="$written $(find "$src/target" -newer "$tmp/stamp" -type f | head -n 3)"
fi
written=$(echo "$written" | xargs)
[ -z "$written" ] || fail "add_subdirectory wrote into the source tree: $written"
echo "source tree unchanged by the add_subdirectory build"
run_consumer "$tmp/sub/consumer_shared" shared
run_consumer "$tmp/sub/consumer_static" static
echo "== consumer_packaging: all three ways passed"
