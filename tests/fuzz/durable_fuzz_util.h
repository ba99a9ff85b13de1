#pragma once
// What the durable fuzzers share: a failed expectation aborts (libFuzzer reports the input), and
// a decoded batch must be the canonical form of its bytes and must go through the scene's rules
// the way recovery replays it.

#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "engine/durable/edit_codec.h"
#include "engine/scene/scene.h"

/// Aborts (a crash libFuzzer reports) with the line of the broken expectation.
#define FUZZ_CHECK(expr)                                                                \
    do {                                                                                \
        if (!(expr)) {                                                                  \
            std::fprintf(stderr, "fuzz check failed: %s (line %d)\n", #expr, __LINE__); \
            std::abort();                                                               \
        }                                                                               \
    } while (false)

namespace strata::fuzz {

/// Encodes `batch` (edit_codec.h).
inline std::string encoded(const EditBatch& batch) {
    std::string out;
    durable::encode_batch(batch, out);
    return out;
}

/// An empty scene for fuzzed batches: a bulk edit names up to 2^24 instances in a few bytes, so
/// the instance budget is kept small (a batch past it is refused, as the server's would be).
inline Scene fuzz_scene() {
    Scene scene;
    SceneBudget budget;
    budget.max_instances = 4096;
    scene.set_budget(budget);
    return scene;
}

/// Decodes `payload` as an edit batch. When it decodes: the encoding is canonical (it
/// re-encodes to the very same bytes), and the batch goes through Scene::apply on an empty scene;
/// a refused batch leaves that scene empty at version 0.
inline void check_batch_payload(std::string_view payload) {
    auto batch = durable::decode_batch(payload);
    if (!batch) {
        FUZZ_CHECK(batch.error().code == ErrorCode::InvalidArgument);
        return;
    }
    FUZZ_CHECK(encoded(batch.value()) == payload);
    Scene scene = fuzz_scene();
    if (!scene.apply(std::move(batch.value()))) {
        FUZZ_CHECK(scene.version() == 0);
        FUZZ_CHECK(scene.to_batch().edits.size() == 2);  // the camera and lighting edits only
        FUZZ_CHECK(scene.changes().empty());
    }
}

}  // namespace strata::fuzz
