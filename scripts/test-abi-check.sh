#!/usr/bin/env bash
# The ABI check's own test: scripts/check-abi.sh --header must pass the committed header and a
# header with one function added, and fail a header with a function removed, a parameter's type
# changed, a struct field's type changed, or a constant's value changed (each a variant of the
# committed header, written to a temporary folder).
set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
header=include/sketchbody.h
failures=0

# variant NAME EXPECT SED_SCRIPT: checks the header edited by SED_SCRIPT; EXPECT pass or fail.
variant() {
  local name=$1 expect=$2 script=$3 out="$work/$1.h" got
  sed "$script" "$header" >"$out"
  if cmp -s "$out" "$header" && [ "$name" != unchanged ]; then
    echo "test-abi-check: the edit for '$name' changed nothing (the header moved on: update this test)" >&2
    failures=$((failures + 1))
    return
  fi
  if scripts/check-abi.sh --header "$out" >"$work/$name.log" 2>&1; then got=pass; else got=fail; fi
  if [ "$got" = "$expect" ]; then
    echo "test-abi-check: $name: $got as expected ($(tail -n 1 "$work/$name.log" | cut -c1-150))"
  else
    echo "test-abi-check: $name: $got, expected $expect" >&2
    cat "$work/$name.log" >&2
    failures=$((failures + 1))
  fi
}

variant unchanged pass ''
variant function_added pass \
  's/^skb_status skb_image_gaussian_blur(/skb_status skb_image_added_for_the_test(const struct skb_image *src);\n\n&/'
variant function_removed fail '/^skb_status skb_image_canny(/,/);$/d'
variant parameter_type_changed fail \
  '/^skb_status skb_image_gaussian_blur(/,/);$/s/double sigma/float sigma/'
variant struct_field_changed fail '/^typedef struct skb_camera {/,/} skb_camera;/s/^  double /  float /'
variant constant_changed fail 's/^#define SKB_NUM_LIMBS \([0-9]*\)$/#define SKB_NUM_LIMBS 99/'

if [ $failures -ne 0 ]; then
  echo "test-abi-check: $failures variant(s) wrong" >&2
  exit 1
fi
echo "test-abi-check: the ABI check passes additions and fails removals and changes"
