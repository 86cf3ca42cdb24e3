#!/usr/bin/env bash
# Runs sketchbody's fuzz targets (fuzz/, cargo-fuzz's layout; docs/reliability.md, "Fuzzing").
#
#   scripts/fuzz.sh                 every target for 2000 executions (what scripts/test-all.sh runs)
#   scripts/fuzz.sh 1000000         the long ("nightly") run: 10^6 executions per target
#   scripts/fuzz.sh 50000 skbm      one target
#   scripts/fuzz.sh build           only build the targets (scripts/test-all.sh starts this early,
#                                   in the background)
#
# Each target starts from its committed seeds (fuzz/seeds/TARGET: small valid files of every
# format and crafted bombs, rebuilt by `cargo test --lib fuzz_seeds`) plus the working corpus it
# grew before (fuzz/corpus/TARGET, not committed), with libFuzzer's -rss_limit_mb=2048
# -timeout=10. A crash, a timeout or an allocation past the limit fails the script and leaves
# the input in fuzz/artifacts/TARGET/ (replay it with `fuzz/target/HOST/release/TARGET FILE`,
# or with `cargo fuzz run` and this script's flags: docs/reliability.md).
#
# The targets are built with cargo directly, with exactly the flags `cargo fuzz build
# --sanitizer S --codegen-units 16` passes (cargo-fuzz 0.13.2, src/project.rs), so `cargo fuzz
# run` reuses this build (e.g. to replay a finding) and a fresh machine does not first compile
# cargo-fuzz itself. Only the stable toolchain is installed: RUSTC_BOOTSTRAP=1 lets it take
# these nightly flags (sancov passes, -Zsanitizer). SKB_FUZZ_SANITIZER picks the sanitizer
# (default `none`: libFuzzer coverage without ASan, which the parsers, safe Rust, do not need;
# `address` for the C-API target's raw pointers).
# 16 codegen units instead of cargo-fuzz's 1: the instrumented build of every dependency (tract
# above all) is most of the test command's fuzz step on a fresh machine (from scratch on 2 idle
# cores: 8 min 45 s -> 7 min 44 s with this and fuzz/Cargo.toml's line tables for sketchbody
# only; docs/reliability.md, "Fuzzing").
set -euo pipefail
cd "$(dirname "$0")/.."

runs=${1:-2000}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(image skbm skbpd skbd parse_json joints_json capi_seq)
sanitizer=${SKB_FUZZ_SANITIZER:-none}
triple=$(rustc -vV | sed -n 's/^host: //p')
export RUSTC_BOOTSTRAP=1
# tract (the landmark model's inference) is built without coverage instrumentation (the
# wrapper says why); builds with and without the wrapper do not share artifacts.
export RUSTC_WRAPPER="$PWD/fuzz/rustc-wrapper.sh"

flags="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4"
flags+=" -Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table"
flags+=" -Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing"
flags+=" -Cllvm-args=-simplifycfg-branch-fold-threshold=0"
case "$sanitizer" in
  none) ;;
  address)
    flags+=" -Zsanitizer=address"
    export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_odr_violation=0"
    ;;
  *) echo "SKB_FUZZ_SANITIZER: expected none or address, got $sanitizer" >&2; exit 2 ;;
esac
case "$triple" in *-linux-*) flags+=" -Cllvm-args=-sanitizer-coverage-stack-depth" ;; esac
# cargo-fuzz adds debug assertions (and so overflow checks) unless given --release.
flags+=" -Cdebug-assertions -Ccodegen-units=16"

echo "== building the fuzz targets (sanitizer: $sanitizer)"
RUSTFLAGS="$flags${RUSTFLAGS:+ $RUSTFLAGS}" cargo build --manifest-path fuzz/Cargo.toml \
  --target "$triple" --release --config 'profile.release.debug="line-tables-only"' --bins
[ "$runs" != build ] || exit 0

for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t"
  dirs=("fuzz/corpus/$t")
  [ -d "fuzz/seeds/$t" ] && dirs+=("fuzz/seeds/$t")
  start=$(date +%s)
  log=$(mktemp)
  mkdir -p "fuzz/artifacts/$t"
  if ! "fuzz/target/$triple/release/$t" -artifact_prefix="fuzz/artifacts/$t/" \
      -runs="$runs" -rss_limit_mb=2048 -timeout=10 -max_len=65536 -seed=1 -print_final_stats=1 \
      "${dirs[@]}" >"$log" 2>&1; then
    tail -n 60 "$log"
    rm -f "$log"
    echo "== fuzz target $t FAILED (input in fuzz/artifacts/$t/)"
    exit 1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 || true)
  echo "fuzz $t: $execs executions, $cov, no crash ($(($(date +%s) - start)) s)"
  rm -f "$log"
done
