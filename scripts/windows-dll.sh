#!/usr/bin/env bash
# sketchbody for 64-bit Windows, cross-built on Linux with the MinGW-w64 toolchain (Rust target
# x86_64-pc-windows-gnu; Debian: gcc-mingw-w64-x86-64, g++-mingw-w64-x86-64, wine, wine64;
# docs/plugins.md, "Windows").
#
#   scripts/windows-dll.sh build [PROFILE]   the DLL with cargo's PROFILE (default release) into
#                                            target/windows-gnu/sketchbody-win64/:
#       bin/sketchbody.dll        the library (debug info and COFF symbol table stripped)
#       lib/sketchbody.def        its exports (the skb_* functions), for `lib /def` (MSVC)
#       lib/sketchbody.lib        import library made from the .def by dlltool (MSVC or MinGW)
#       lib/libsketchbody.dll.a   rustc's MinGW import library
#       include/sketchbody.h, sketchbody.hpp
#   scripts/windows-dll.sh test              checks that package (exports = the pinned manifest's,
#                                            no MinGW runtime DLL needed), cross-compiles the C and
#                                            C++ API tests of cpp_tests/ against sketchbody.lib,
#                                            links a probe with lld-link (the MSVC linker's flavour)
#                                            and runs them under Wine (prefix target/windows-gnu/wine)
#
# cargo's folder is target/windows-gnu (CARGO_TARGET_DIR), apart from target/ so that this build
# never waits for, or invalidates, the Linux test build's lock and artifacts.
set -euo pipefail
cd "$(dirname "$0")/.."

triple=x86_64-pc-windows-gnu
cross=x86_64-w64-mingw32
out_dir="$PWD/target/windows-gnu"
pkg="$out_dir/sketchbody-win64"
tests="$out_dir/tests"
major=$(sed -n 's/^#define SKB_VERSION_MAJOR \([0-9]*\)$/\1/p' include/sketchbody.h)
layouts=abi/sketchbody-$major.layout

# The package's DLL exports, one name a line, sorted (objdump's export name table).
dll_exports() {
  "$cross-objdump" -p "$1" | sed -n '/^\[Ordinal\/Name Pointer\] Table/,/^$/p' |
    sed -n 's/^[[:space:]]*\[ *[0-9]*\] \([A-Za-z_][A-Za-z0-9_]*\)$/\1/p' | sort
}

build() {
  local profile=${1:-release} dir
  CARGO_TARGET_DIR="$out_dir" cargo build --profile "$profile" --locked --target "$triple" -p sketchbody-capi
  [ "$profile" = dev ] && dir=debug || dir=$profile
  dir="$out_dir/$triple/$dir"
  rm -rf "$pkg"
  mkdir -p "$pkg/bin" "$pkg/lib" "$pkg/include"
  "$cross-strip" --strip-all -o "$pkg/bin/sketchbody.dll" "$dir/sketchbody.dll"
  cp "$dir/libsketchbody.dll.a" "$pkg/lib/"
  cp include/sketchbody.h include/sketchbody.hpp "$pkg/include/"
  { echo "LIBRARY sketchbody.dll"; echo "EXPORTS"; dll_exports "$pkg/bin/sketchbody.dll" | sed 's/^/    /'; } \
    >"$pkg/lib/sketchbody.def"
  "$cross-dlltool" --input-def "$pkg/lib/sketchbody.def" --dllname sketchbody.dll --output-lib "$pkg/lib/sketchbody.lib"
  printf 'windows-dll: %s (profile %s): sketchbody.dll %s bytes (%s with debug info), sketchbody.lib %s bytes\n' \
    "$pkg" "$profile" "$(stat -c %s "$pkg/bin/sketchbody.dll")" "$(stat -c %s "$dir/sketchbody.dll")" \
    "$(stat -c %s "$pkg/lib/sketchbody.lib")"
}

# check_package: exports equal the header's functions; the DLL imports only Windows' own DLLs.
check_package() {
  local dll="$pkg/bin/sketchbody.dll" imports bad
  if ! diff -u <(grep -oE '\bskb_[a-z0-9_]+\(' include/sketchbody.h | tr -d '(' | sort -u) <(dll_exports "$dll"); then
    echo "windows-dll: sketchbody.dll's exports differ from include/sketchbody.h's functions (- declared, + the DLL)" >&2
    exit 1
  fi
  imports=$("$cross-objdump" -p "$dll" | sed -n 's/^[[:space:]]*DLL Name: //p' | sort -u)
  bad=$(grep -viE '^(kernel32|ntdll|msvcrt|advapi32|bcrypt|bcryptprimitives|userenv|ws2_32|shell32|ole32|api-ms-win-[a-z0-9-]*)\.dll$' \
        <<<"$imports" || true)
  [ -z "$bad" ] || { echo "windows-dll: sketchbody.dll needs DLLs a Windows machine lacks: $bad" >&2; exit 1; }
  echo "windows-dll: $(dll_exports "$dll" | wc -l) exports match the header; imports: $(paste -sd' ' <<<"$imports")"
}

# wine_exe NAME ARGS...: runs NAME.exe of the tests' folder (beside sketchbody.dll, as a plug-in
# sits beside it) under Wine, once.
wine_exe() {
  local exe=$1
  shift
  WINEPREFIX="$out_dir/wine" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=" wine "$tests/$exe.exe" "$@"
}

# wine_run NAME ARGS...: wine_exe, except that a run that fails because Wine itself lost its
# server ("wine client error: ... recvmsg: Connection reset by peer", seen about once in ten full
# runs on this kind of machine, never from the test) is run once more; any other failure fails.
wine_run() {
  local log status=0
  echo "== wine $1.exe ${*:2}"
  log=$(mktemp)
  wine_exe "$@" >"$log" 2>&1 || status=$?
  cat "$log"
  if [ "$status" -ne 0 ] && grep -q '^wine client error' "$log"; then
    echo "== Wine lost its server (not the test): wine $1.exe once more"
    status=0
    wine_exe "$@" || status=$?
  fi
  rm -f "$log"
  return "$status"
}

test_package() {
  [ -f "$pkg/bin/sketchbody.dll" ] || { echo "windows-dll: run '$0 build' first" >&2; exit 1; }
  check_package
  rm -rf "$tests"
  mkdir -p "$tests"
  cp -l "$pkg/bin/sketchbody.dll" "$tests/" 2>/dev/null || cp "$pkg/bin/sketchbody.dll" "$tests/"
  local cflags=(-Wall -Wextra -Werror -O1 -I"$pkg/include" -D__USE_MINGW_ANSI_STDIO=1)
  local link=(-static "$pkg/lib/sketchbody.lib")
  local cc="$cross-gcc-posix" cxx="$cross-g++-posix" t
  # Wine 8 lacks bcryptprimitives.dll (Windows 10 has it; the Rust standard library needs it).
  "$cc" "${cflags[@]}" -shared -o "$tests/bcryptprimitives.dll" cpp_tests/windows/bcryptprimitives.c -lbcrypt
  for t in capi_c_test capi_sketch_test capi_rig_test abi_layout; do
    "$cc" -std=c11 "${cflags[@]}" -o "$tests/$t.exe" "cpp_tests/$t.c" "${link[@]}" -lm -lpthread
  done
  # The detector test reads assets/detector.skbd: Wine maps this Linux path to drive Z:.
  "$cc" -std=c11 "${cflags[@]}" -DSKB_SOURCE_DIR="\"Z:$PWD\"" -o "$tests/capi_detect_test.exe" \
    cpp_tests/capi_detect_test.c "${link[@]}" -lm -lpthread
  "$cc" -std=c11 "${cflags[@]}" -DSKB_CONSUMER_HOW='"windows-dll"' -o "$tests/consumer.exe" \
    cpp_tests/consumer/main.c "${link[@]}"
  "$cxx" -std=c++17 "${cflags[@]}" -DSKB_SOURCE_DIR="\"Z:$PWD\"" -o "$tests/capi_cpp_test.exe" cpp_tests/capi_cpp_test.cpp "${link[@]}"
  "$cxx" -std=c++17 "${cflags[@]}" -o "$tests/plugin_host.exe" examples/plugin_host.cpp "${link[@]}"
  # An MSVC-style link: lld-link (rustup's rust-lld) takes sketchbody.lib, no C runtime involved.
  local lld
  lld="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/rust-lld"
  "$cc" "${cflags[@]}" -ffreestanding -c -o "$tests/msvc_link_probe.obj" cpp_tests/windows/msvc_link_probe.c
  "$lld" -flavor link /nologo /nodefaultlib /entry:probe_main /subsystem:console \
    /out:"$tests/msvc_link_probe.exe" "$tests/msvc_link_probe.obj" "$pkg/lib/sketchbody.lib" \
    "$("$cc" -print-file-name=libkernel32.a)"

  # The struct layouts seen by a Windows compiler are the baseline's (Linux) ones.
  local moved
  moved=$(comm -23 <(sort "$layouts") <(wine_run abi_layout | tr -d '\r' | grep '^layout ' | sort))
  if [ -n "$moved" ]; then
    echo "windows-dll: struct layouts under Windows differ from $layouts: $moved" >&2
    exit 1
  fi
  echo "windows-dll: $(wc -l <"$layouts") layout lines match $layouts"
  for t in consumer capi_c_test capi_sketch_test capi_rig_test capi_detect_test capi_cpp_test; do
    wine_run "$t"
  done
  wine_run plugin_host "Z:$PWD/assets/examples/sketch.png" "Z:$PWD/assets/examples/sketch_joints.json"
  wine_run msvc_link_probe
  echo "msvc_link_probe: linked by lld-link against sketchbody.lib, version strings equal"
  echo "windows-dll: every C API test passed under Wine"
}

case ${1:-} in
  build) build "${2:-release}" ;;
  test) test_package ;;
  *)
    echo "usage: $0 build [PROFILE] | test" >&2
    exit 2
    ;;
esac
