#pragma once
// What both asset fuzzers (asset_import_fuzzer.cpp, archive_import_fuzzer.cpp) check once an
// importer accepted its input: the asset crosses the sandbox's wire unchanged, validates again and
// its batch goes through the scene's rules; a refused batch leaves the scene as it was; an applied one is cleared for the next input.

#include <cstdio>
#include <cstdlib>
#include <utility>

#include "engine/scene/scene.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/asset_wire.h"

namespace strata::assets::fuzz {

[[noreturn]] inline void fail(const char* fuzzer, const char* what) {
    std::fprintf(stderr, "%s: %s\n", fuzzer, what);
    std::abort();
}

/// The asset through the sandbox's wire (asset_wire.h) and back: byte-identical once more.
inline Asset through_the_wire(const char* fuzzer, Asset&& asset) {
    const std::string bytes = encode_outcome(ImportOutcome{std::move(asset), AssetFormat::Obj, {}});
    auto back = decode_outcome(bytes);
    if (!back || !back.value()) fail(fuzzer, "an accepted asset does not decode from its wire");
    if (encode_outcome(back.value()) != bytes) fail(fuzzer, "the wire does not round-trip");
    return std::move(back.value().value().asset);
}

inline void apply_accepted(const char* fuzzer, Scene& scene, Asset&& accepted) {
    Asset asset = through_the_wire(fuzzer, std::move(accepted));
    if (!validate_asset(asset, ErrorSink("fuzz")).has_value())
        fail(fuzzer, "an accepted asset does not validate");
    AssetBatch b = asset_to_batch(std::move(asset), {"f", true, std::nullopt});
    const uint64_t version = scene.version();
    if (!scene.apply(std::move(b.batch))) {
        if (scene.version() != version || scene.counts().meshes != 0)
            fail(fuzzer, "a refused batch changed the scene");
        return;
    }
    EditBatch clear;
    clear.edits.emplace_back(Clear{});
    if (!scene.apply(std::move(clear)).has_value()) fail(fuzzer, "clear was refused");
    scene.clear_changes();
}

}  // namespace strata::assets::fuzz
