#!/usr/bin/env bash
# Runs one fuzz target with the harness's limits (fuzz/README.md): fuzz/run.sh TARGET [SECONDS]
# [LIBFUZZER FLAGS...]. Every run gets the memory limits, whatever else is passed: the targets'
# own allocator refuses more than 2 GiB live (fuzz_targets/limit.rs; an infallible allocation
# past it aborts, a crash), -malloc_limit_mb=2048 makes one larger malloc a crash where a
# sanitizer's hooks see it, and -rss_limit_mb=3072 ends a run whose resident memory grows past
# the allocator's limit anyway (C++ code, the codec's own buffers). Seeds from seeds/TARGET;
# the corpus grows in corpus/TARGET, crashes go to artifacts/TARGET.
set -euo pipefail
cd "$(dirname "$0")"
target="${1:?usage: fuzz/run.sh TARGET [SECONDS] [LIBFUZZER FLAGS...]}"
seconds="${2:-600}"
shift $(( $# >= 2 ? 2 : 1 ))
mkdir -p "corpus/$target" "artifacts/$target"
exec cargo +nightly fuzz run -O -s none -a "$target" "corpus/$target" "seeds/$target" -- \
    -max_total_time="$seconds" -max_len=131072 \
    -artifact_prefix="artifacts/$target/" \
    "$@" \
    -rss_limit_mb=3072 -malloc_limit_mb=2048
