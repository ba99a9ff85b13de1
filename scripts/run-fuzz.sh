#!/usr/bin/env bash
# Builds the libFuzzer targets with clang++ (libFuzzer + AddressSanitizer + UBSan) in their own
# build folder and runs each for a bounded number of iterations from its committed seed corpus:
#
#   edit_batch_fuzzer     JSON edit batches: the JSON reader, the batch parser, engine validation
#   http_request_fuzzer   raw HTTP/1.1 bytes: the front end's request reader (request line,
#                         headers, framing, target, query, body), then the routes, protocol/api.h
#                         and the engine
#   journal_record_fuzzer journal segments and the edit-batch codec of their records (what
#                         recovery reads from disk)
#   snapshot_fuzzer       snapshots: header checks, the scene batch, import against restore (POST
#                         /v1/scene/snapshot takes them from anyone)
#   gltf_import_fuzzer    .glb and .gltf files: tinygltf (compiled here, instrumented), the glTF
#   obj_import_fuzzer     importer, OBJ (tinyobjloader) and our PLY reader, then the asset's batch
#   ply_import_fuzzer     through the scene's rules (protocol/assets/)
#   assimp_import_fuzzer  FBX, COLLADA, STL, 3DS, OFF, X, AC, ASE, ... through Debian's assimp (not
#                         instrumented; it leaks on some broken files, so no leak detection here,
#                         and its out-of-memory inputs are skipped in fork mode): our IOSystem,
#                         scene, material and texture glue, then the batch
#   archive_import_fuzzer tar uploads: our ustar reader, the one model it holds and its side files,
#                         then that model's importer and batch (protocol/assets/archive_import.h)
#   texture_decode_fuzzer PNG and JPEG bytes: libpng and libturbojpeg behind our header checks and
#                         limits, then texture lookups (engine/image/texture_decode.h)
#
# The two durable fuzzers' seed corpora are written by the encoder (tests/fuzz/durable_corpus.cpp)
# into the scratch folder at each run, so they always match the current formats.
#
#   scripts/run-fuzz.sh [RUNS]        default RUNS=100000; CI calls it without arguments. The HTTP
#                                     fuzzer gets RUNS/4: each of its inputs runs through the engine.
#                                     Each importer fuzzer gets RUNS/4 too (assimp's RUNS/16),
#                                     and so do the archive fuzzer and the texture decoder.
#   scripts/run-fuzz.sh --build-only  configures and builds only. STRATA_FUZZ_ALSO names more
#                                     targets to build in the same folder: scripts/test.sh builds
#                                     strata_engine_tests here and runs it under ASan + UBSan,
#                                     so the sanitized libraries are compiled once for both.
#
# The archive fuzzer's seeds are tar archives written at run time by `tar` (an OBJ with its MTL,
# a .gltf with its .bin and PNG from assimp-testmodels). The importers' corpora start from the small seeds in tests/fuzz/asset_corpus/ plus every file of
# that format in Debian's assimp-testmodels (copied to scratch at run time, never committed); the
# texture decoder's from tests/fuzz/texture_corpus/ plus assimp-testmodels' small PNG and JPEG
# files.
#
# New inputs the fuzzers find go to scratch copies of the corpora, never into the repository.
set -euo pipefail

build_only=0
if [ "${1:-}" = "--build-only" ]; then
    build_only=1
    shift
fi
runs="${1:-100000}"
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"

cmake -S "$root" -B "$build" -G Ninja \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSTRATA_FUZZ=ON -DSTRATA_BUILD_BENCHMARKS=OFF
ninja -C "$build" -j "${STRATA_BUILD_JOBS:-2}" edit_batch_fuzzer http_request_fuzzer \
    journal_record_fuzzer snapshot_fuzzer durable_corpus \
    gltf_import_fuzzer obj_import_fuzzer ply_import_fuzzer assimp_import_fuzzer \
    archive_import_fuzzer \
    texture_decode_fuzzer ${STRATA_FUZZ_ALSO:-}
[ "$build_only" = 1 ] && exit 0

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
# A crashing input is kept in build-fuzz/artifacts/ (reproduce: <fuzzer> FILE).
mkdir -p "$build/artifacts"

run() {  # fuzzer corpus dictionary runs [libFuzzer flags...] (corpus: a folder in tests/fuzz, a
         # scratch one, or both)
    mkdir -p "$scratch/$2"
    if [ -d "$root/tests/fuzz/$2" ]; then cp -r "$root/tests/fuzz/$2/." "$scratch/$2/"; fi
    local dict=()
    [ -n "$3" ] && dict=(-dict="$root/tests/fuzz/$3")
    "$build/tests/fuzz/$1" -runs="$4" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
        "${dict[@]}" -artifact_prefix="$build/artifacts/$1-" "${@:5}" ${STRATA_FUZZ_ARGS:-} \
        "$scratch/$2"
    echo "fuzz: $1, $4 runs, no crash"
}
run edit_batch_fuzzer corpus json.dict "$runs"
run http_request_fuzzer http_corpus http.dict "$((runs / 4))"
mkdir -p "$scratch/journal_corpus" "$scratch/snapshot_corpus"
"$build/tests/fuzz/durable_corpus" "$scratch/journal_corpus" "$scratch/snapshot_corpus"
run journal_record_fuzzer journal_corpus "" "$runs"
run snapshot_fuzzer snapshot_corpus "" "$runs"

# The importers, seeded from assimp-testmodels' files of their format (odd and broken ones too).
models="${STRATA_ASSIMP_MODELS_DIR:-/usr/share/assimp/models}"
for format in gltf obj ply; do
    mkdir -p "$scratch/asset_corpus/$format"
    if [ -d "$models" ]; then
        case "$format" in
            gltf) pattern='.*\.\(gltf\|glb\)' ;;
            *) pattern=".*\\.$format" ;;
        esac
        n=0
        while IFS= read -r -d '' f; do
            cp "$f" "$scratch/asset_corpus/$format/assimp-$n-$(basename "$f")"
            n=$((n + 1))
        done < <(find "$models" -type f -size -64k -iregex "$pattern" -print0)
    fi
    run "${format}_import_fuzzer" "asset_corpus/$format" "" "$((runs / 4))"
done

# assimp's formats, seeded from their small assimp-testmodels files, each behind its format's line.
mkdir -p "$scratch/asset_corpus/assimp"
if [ -d "$models" ]; then
    n=0
    for ext in fbx dae stl 3ds off x ac ase lwo ms3d b3d dxf 3mf amf smd nff cob xgl; do
        while IFS= read -r -d '' f; do
            { printf '%s\n' "$ext"; cat "$f"; } > "$scratch/asset_corpus/assimp/$n-$(basename "$f")"
            n=$((n + 1))
        done < <(find "$models" -type f -size -64k -iname "*.$ext" -print0)
    done
fi
# assimp allocates what a file's header declares (invalid/'s OFF file asks for 16 GB) and lets
# some exceptions escape through noexcept code (std::terminate): in the server the sandbox turns
# both into a 422. Here libFuzzer's fork mode runs the inputs in children and carries on past
# them; each crash it kept is then run again and triaged by the first frame that is ours or
# libassimp's: ours fails the run, assimp's own are only listed. It gets RUNS/16: assimp is slow
# and crashes often, and each crash costs fork mode a new child (measured, RUNS/4 took 7 of the
# run's 10 minutes on a 2-core VM; RUNS/16 keeps it to about 2).
run assimp_import_fuzzer asset_corpus/assimp "" "$((runs / 16))" -fork=1 -ignore_ooms=1 \
    -ignore_timeouts=1 -ignore_crashes=1 -detect_leaks=0 ||
    echo "fuzz: assimp_import_fuzzer kept crashes; triaging them"
ours=0
for crash in "$build"/artifacts/assimp_import_fuzzer-crash-*; do
    [ -e "$crash" ] || continue
    if trace="$("$build/tests/fuzz/assimp_import_fuzzer" -detect_leaks=0 "$crash" 2>&1)"; then
        echo "fuzz: does not crash when run again (a fork-mode job's): $crash"
        continue
    fi
    first="$(grep -E '^ +#[0-9]+ ' <<<"$trace" |
        grep -m1 -E "libassimp|$root/[^ ]+\.(cpp|h):[0-9]+" || true)"
    case "$first" in
        *libassimp*) echo "fuzz: assimp's own crash, contained by the sandbox: $crash" ;;
        *) echo "fuzz: a crash in Strata's assimp glue: $crash"; echo "$trace" | tail -40; ours=1 ;;
    esac
done
[ "$ours" = 0 ] || exit 1
echo "fuzz: assimp_import_fuzzer, $((runs / 16)) runs, no crash in Strata's glue"

# Tar uploads, seeded with archives tar writes now.
mkdir -p "$scratch/archive_corpus"
tar cf "$scratch/archive_corpus/quad-obj.tar" -C "$root/tests/fuzz/asset_corpus/obj" quad-mtl.obj
if [ -d "$models/glTF2/BoxTextured-glTF" ]; then
    tar cf "$scratch/archive_corpus/box-gltf.tar" -C "$models/glTF2" BoxTextured-glTF
fi
if [ -f "$models/OBJ/cube_usemtl.obj" ]; then
    tar cf "$scratch/archive_corpus/cube-obj-mtl.tar" -C "$models/OBJ" cube_usemtl.obj \
        cube_usemtl.mtl
fi
run archive_import_fuzzer archive_corpus "" "$((runs / 4))"

# The texture decoder, seeded from small PNG and JPEG files of assimp-testmodels too.
mkdir -p "$scratch/texture_corpus"
if [ -d "$models" ]; then
    n=0
    while IFS= read -r -d '' f; do
        cp "$f" "$scratch/texture_corpus/assimp-$n-$(basename "$f")"
        n=$((n + 1))
    done < <(find "$models" -type f -size -64k -iregex '.*\.\(png\|jpg\|jpeg\)' -print0)
fi
run texture_decode_fuzzer texture_corpus "" "$((runs / 4))"
