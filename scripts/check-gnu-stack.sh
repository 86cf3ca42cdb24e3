#!/usr/bin/env bash
# No executable stack (ctest `gnu_stack`): the shared library and a plug-in linking the static
# one must have a GNU_STACK program header with flags RW (RWE, or no header at all, asks the
# loader for an executable stack, which hardened hosts refuse), and every object inside the
# static library must carry a `.note.GNU-stack` section (one without it makes any program or
# plug-in linking that object RWE). The plug-in must contain tract's assembly kernels, so that
# the check covers the objects that once lacked the note.
# Usage: scripts/check-gnu-stack.sh LIBSKETCHBODY.so LIBSKETCHBODY.a PLUGIN.so
set -euo pipefail
so=$1 static=$2 plugin=$3
fail() { echo "check-gnu-stack: FAIL: $*" >&2; exit 1; }

# stack_flags FILE: the flags column of FILE's GNU_STACK program header (empty when absent).
stack_flags() { readelf -lW "$1" | awk '$1 == "GNU_STACK" { f = $(NF - 1); sub(/^0x.*/, "", f); print f }'; }

for f in "$so" "$plugin"; do
  flags=$(stack_flags "$f")
  echo "GNU_STACK $flags  $(basename "$f")"
  [ "$flags" = RW ] || fail "$(basename "$f") has GNU_STACK '${flags:-absent}', want RW"
done

# Objects of the archive without the note: readelf prints "File: lib.a(member.o)" before each
# member's section table.
missing=$(readelf -SW "$static" | awk '
  /^File: / { if (name != "" && !note) print name; name = $2; note = 0 }
  /\.note\.GNU-stack/ { note = 1 }
  END { if (name != "" && !note) print name }')
objects=$(readelf -SW "$static" | grep -c '^File: ')
if [ -n "$missing" ]; then
  fail "$(wc -l <<<"$missing") of $objects objects in $(basename "$static") lack .note.GNU-stack: $(head -n 5 <<<"$missing" | paste -sd' ')"
fi
echo "all $objects objects in $(basename "$static") carry .note.GNU-stack"

kernels=$(nm "$plugin" | grep -c 'avxvnni_mmm_i32_8x8' || true)
[ "$kernels" -gt 0 ] || fail "$(basename "$plugin") does not contain tract's avxvnni kernel: the check would prove nothing"
echo "$(basename "$plugin") links tract's assembly kernels ($kernels avxvnni_mmm_i32_8x8 symbols)"
