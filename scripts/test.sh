#!/usr/bin/env bash
# Installs what is missing, builds Strata and runs every test. This is README command (2) and
# exactly what CI runs (.ci/run).
#
# Steps:
#   1. scripts/install-deps.sh              Debian packages (idempotent)
#   2. build/ (RelWithDebInfo)               full build, then every CTest test
#   3. build-fuzz/ (clang, ASan + UBSan)     engine tests under the sanitizers, in the build the
#                                            fuzzers use (the sanitized libraries compile once)
#   4. build-tsan/ (ThreadSanitizer)         the engine tests that run background TLAS merges beside
#                                            commits, launches and edits, engines sharing one
#                                            Embree device, renders whose threads share the
#                                            level-of-detail wrappers, and a commit that refreshes
#                                            thousands of instances in parallel (only those are
#                                            built)
#   5. build-fuzz/ (clang, libFuzzer)        every fuzzer (scripts/run-fuzz.sh), bounded runs
#   6. build-docker/ (mmdebstrap, chroot)    docker/: lint, and the image's runtime stage run in a
#                                            fresh Debian 12 root (scripts/check-docker.sh)
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "installing dependencies"
scripts/install-deps.sh

step "building (build/)"
scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo

step "running the test suite"
# Tests that time themselves or load the whole machine are RUN_SERIAL; the rest share the cores.
ctest --test-dir build --output-on-failure --timeout 600 --parallel "$(nproc)"

step "engine tests under AddressSanitizer and UndefinedBehaviorSanitizer (build-fuzz/, clang)"
STRATA_FUZZ_ALSO=strata_engine_tests scripts/run-fuzz.sh --build-only
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    build-fuzz/tests/engine/strata_engine_tests
# Again for the suites that trace instances, with every static TLAS tier an instance array
# (CTest runs the whole suite that way; tests/engine/CMakeLists.txt).
STRATA_TEST_ARRAY_MIN_INSTANCES=0 \
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    build-fuzz/tests/engine/strata_engine_tests --gtest_brief=1 --gtest_filter="$(printf %s \
    'Differential.*:IncrementalTlas.*:*LevelOfDetail*:*Motion*:Picking.*:*CoverageRender*:' \
    '*LeastWorkGroups*:BulkInstances.*:Groups.*:SeparatedInstances.*' \
    '-IncrementalTlas.ARemovedMeshLeavesTheBlasMemoryEvenWhileStaleCopiesReferenceIt')"

step "engine concurrency tests under ThreadSanitizer (build-tsan/)"
STRATA_TARGETS=strata_engine_tsan_tests scripts/build.sh build-tsan \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSTRATA_TSAN=ON -DSTRATA_BUILD_BENCHMARKS=OFF
# history_size=7: the longest access history, so that the earlier access of a race report keeps
# its stack and the library suppressions can match it (tests/engine/tsan.supp).
tsan_options="halt_on_error=1 history_size=7 second_deadlock_stack=1"
# One process per group: a test late in a long TSan process ran up to eight times slower than
# alone (TSan's state grows with every thread and lock the process has seen).
tsan_groups=(
    'IncrementalTlas.*'
    'Differential.ThousandsOfInstancesMatchAFreshBuildThroughMerges*'
    'InstanceArray.AStale*:Differential.ThousandsOfInstancesInAnInstanceArray*ThroughMerges'
    'ClusteredBlas.RendersDuringLocalEdits*'
    '*BlasSharing.*'
    '*LevelOfDetail.PicksNameTheLevelTheFrameShows*'
    'BulkInstances.AFirstCommitOfMany*'
)
for group in "${tsan_groups[@]}"; do
    TSAN_OPTIONS="$tsan_options suppressions=$PWD/tests/engine/tsan.supp" \
        timeout 900 build-tsan/tests/engine/strata_engine_tsan_tests --gtest_filter="$group"
done

step "fuzzing: edit batches, HTTP requests, journal, snapshots, assets, textures (build-fuzz/)"
scripts/run-fuzz.sh

step "docker image checks: lint, runtime stage in a Debian 12 root (build-docker/)"
scripts/check-docker.sh build

step "all tests passed"
