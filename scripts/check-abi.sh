#!/usr/bin/env bash
# Compares the C ABI with the pinned manifest cpp_tests/abi_manifest.txt: the skb_* symbols the
# shared library exports (and that nothing else is exported), the functions the header declares,
# and the struct layouts printed by the abi_layout program. Usage:
#   scripts/check-abi.sh LIBSKETCHBODY.so ABI_LAYOUT_PROGRAM [--bless]
# --bless rewrites the manifest (do it only for a deliberate ABI change, and say so in the commit).
set -euo pipefail
cd "$(dirname "$0")/.."
lib=$1 layout=$2
manifest=cpp_tests/abi_manifest.txt
fresh=$(mktemp)
trap 'rm -f "$fresh"' EXIT
{
  nm -D --defined-only "$lib" | awk '$2 ~ /^[TDBR]$/ {print "export " $3}' | sort
  grep -oE '\bskb_[a-z0-9_]+\(' include/sketchbody.h | tr -d '(' | sort -u | sed 's/^/declared /'
  "$layout"
} >"$fresh"
if [ "${3:-}" = "--bless" ]; then
  cp "$fresh" "$manifest"
  echo "check-abi: $manifest rewritten ($(wc -l <"$manifest") lines)"
  exit 0
fi
if ! diff -u "$manifest" "$fresh"; then
  echo "check-abi: the ABI differs from $manifest (lines: - pinned, + now)." >&2
  echo "check-abi: if the change is deliberate (a new export), rerun with --bless and commit the manifest." >&2
  exit 1
fi
bad=$(grep '^export ' "$fresh" | grep -v '^export skb_' || true)
if [ -n "$bad" ]; then
  echo "check-abi: symbols outside the skb_ prefix are exported: $bad" >&2
  exit 1
fi
echo "check-abi: $(grep -c '^export ' "$fresh") exported symbols, $(grep -c '^declared ' "$fresh") declared, $(grep -c '^layout ' "$fresh") layout lines match $manifest"
