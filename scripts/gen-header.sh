#!/usr/bin/env bash
# Regenerates include/sketchbody.h with the cbindgen version pinned in Cargo.toml.
set -euo pipefail
cd "$(dirname "$0")/.."
SKB_BLESS_HEADER=1 cargo test --release --quiet --test header committed_header_matches_fresh_generation
echo "include/sketchbody.h regenerated"
