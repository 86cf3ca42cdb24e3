#!/usr/bin/env bash
# Regenerates include/sketchbody.h from capi/src with the cbindgen version pinned in capi/Cargo.toml.
set -euo pipefail
cd "$(dirname "$0")/.."
SKB_BLESS_HEADER=1 cargo test --release --quiet -p sketchbody-capi --lib tests::header::committed_header_matches_fresh_generation
echo "include/sketchbody.h regenerated"
