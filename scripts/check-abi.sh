#!/usr/bin/env bash
# The C API's compatibility check (docs/c-api.md, "Compatibility policy") against the committed
# baseline of this major version in abi/:
#   1. the shared library exports exactly the functions the header declares, all `skb_*`;
#   2. libabigail's abidiff between the baseline's ABI (abi/sketchbody-MAJOR.abi) and the header's
#      ABI now (scripts/abi-probe.py: every declared function defined with the header's own
#      signature, compiled with -g, read by abidw): a removed function, or a changed signature,
#      struct or enum of the header fails; added functions pass and are listed;
#   3. every `#define SKB_*` of the baseline (abi/sketchbody-MAJOR.defines) keeps its value;
#   4. every struct layout of the baseline (abi/sketchbody-MAJOR.layout, printed by the abi_layout
#      program: sizes and field offsets as a C compiler sees them) is unchanged.
# Usage: scripts/check-abi.sh LIBSKETCHBODY.so ABI_LAYOUT_PROGRAM [--bless]
#        scripts/check-abi.sh --header HEADER   (steps 2 and 3 only, for HEADER: the check's own
#                                                test, scripts/test-abi-check.sh)
# --bless writes the baseline of the header's major version; it refuses to overwrite one (a
# released major's baseline never changes: an incompatible change needs a new major version).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$1" = "--header" ]; then
  lib="" layout="" header=$2
else
  lib=$1 layout=$2 header=include/sketchbody.h
fi
major=$(sed -n 's/^#define SKB_VERSION_MAJOR \([0-9]*\)$/\1/p' "$header")
base=abi/sketchbody-$major
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "check-abi: $*" >&2; exit 1; }
# defines HEADER: its `#define SKB_* VALUE` lines as "NAME VALUE", sorted.
defines() { sed -n 's/^#define \(SKB_[A-Z0-9_]*\) \(.*\)$/\1 \2/p' "$1" | sort; }
for tool in abidw abidiff cc nm python3; do
  command -v "$tool" >/dev/null || fail "$tool is missing (Debian: apt-get install abigail-tools gcc binutils python3)"
done

# 1. Exports and declarations.
grep -oE '\bskb_[a-z0-9_]+\(' "$header" | tr -d '(' | sort -u >"$work/declared"
if [ -n "$lib" ]; then
  nm -D --defined-only "$lib" | awk '$2 ~ /^[TDBR]$/ {print $3}' | sort >"$work/exports"
  bad=$(grep -v '^skb_' "$work/exports" || true)
  [ -z "$bad" ] || fail "symbols outside the skb_ prefix are exported: $bad"
  diff -u "$work/declared" "$work/exports" >&2 ||
    fail "the library's exports differ from the header's declarations (- declared, + exported)"
fi

# 2. The header's ABI, as a C compiler sees it.
python3 scripts/abi-probe.py "$header" >"$work/probe.c"
cp "$header" "$work/sketchbody.h"
cc -std=c11 -g -O0 -shared -fPIC -I"$work" -o "$work/probe.so" "$work/probe.c"
abidw --no-corpus-path --no-show-locs "$work/probe.so" >"$work/now.abi"

if [ "${3:-}" = "--bless" ]; then
  [ ! -e "$base.abi" ] || fail "$base.abi exists: a released major's baseline never changes"
  mkdir -p abi
  cp "$work/now.abi" "$base.abi"
  defines "$header" >"$base.defines"
  "$layout" | grep '^layout ' >"$base.layout"
  echo "check-abi: wrote the baseline $base.{abi,defines,layout} ($(wc -l <"$work/declared") functions)"
  exit 0
fi
[ -e "$base.abi" ] || fail "no baseline $base.abi for major version $major (write it once with --bless)"

set +e
abidiff --no-show-locs --no-added-syms "$base.abi" "$work/now.abi" >"$work/diff"
status=$?
set -e
if [ $status -ne 0 ]; then
  cat "$work/diff" >&2
  fail "abidiff: the C API changed incompatibly against $base.abi (status $status; above)"
fi
added=$(abidiff --no-show-locs "$base.abi" "$work/now.abi" | sed -n "s/^  \[A\] 'function .* \(skb_[a-z0-9_]*\)(.*/\1/p" | paste -sd' ' || true)

# 3. Constants.
changed=$(comm -23 "$base.defines" <(defines "$header"))
[ -z "$changed" ] || fail "constants of $base.defines removed or changed: $changed"

# 4. Struct layouts.
if [ -n "$layout" ]; then
  moved=$(comm -23 <(sort "$base.layout") <("$layout" | grep '^layout ' | sort))
  [ -z "$moved" ] || fail "struct layouts of $base.layout changed: $moved"
fi

echo "check-abi: $(wc -l <"$work/declared") functions declared${lib:+ and exported}; compatible with $base" \
  "($(grep -c '<function-decl' "$base.abi") baseline functions, $(wc -l <"$base.layout") layout lines," \
  "$(wc -l <"$base.defines") constants); added since: ${added:-none}"
