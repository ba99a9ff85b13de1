#!/usr/bin/env bash
# Builds the edit batch fuzzer with clang++ (libFuzzer + AddressSanitizer + UBSan) in its own
# build folder and runs it for a bounded number of iterations from the committed seed corpus.
#
#   scripts/run-fuzz.sh [RUNS]        default RUNS=100000; CI calls it without arguments
#
# New inputs the fuzzer finds go to a scratch copy of the corpus, never into the repository.
set -euo pipefail

runs="${1:-100000}"
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"

cmake -S "$root" -B "$build" -G Ninja \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSTRATA_FUZZ=ON -DSTRATA_BUILD_BENCHMARKS=OFF
ninja -C "$build" -j "${STRATA_BUILD_JOBS:-2}" edit_batch_fuzzer

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
cp -r "$root/tests/fuzz/corpus" "$scratch/corpus"
# A crashing input is kept in build-fuzz/artifacts/ (reproduce: edit_batch_fuzzer FILE).
mkdir -p "$build/artifacts"
"$build/tests/fuzz/edit_batch_fuzzer" -runs="$runs" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
    -dict="$root/tests/fuzz/json.dict" -artifact_prefix="$build/artifacts/" ${STRATA_FUZZ_ARGS:-} \
    "$scratch/corpus"
echo "fuzz: $runs runs, no crash"
