// libFuzzer target for the edit batch parser (and the JSON reader under it).
//
// Checks, besides "no crash, no sanitizer report":
//   - the JSON reader accepts exactly what nlohmann accepts (but for duplicate keys, which it
//     refuses on purpose, inputs over its limits, NUL bytes, where nlohmann stops reading, and
//     numbers that overflow, which it keeps as infinity), and reads the same values;
//   - a parse error names a place inside the edit it blames;
//   - a parsed batch goes through the engine's rules on a small scene; a refused batch leaves
//     that scene as it was, and its error maps to a problem;
//   - a batch with bulk instance edits is accepted or refused as the same batch with their
//     single edits is, and leaves the same objects.
// Build and run: scripts/run-fuzz.sh.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "engine/durable/edit_codec.h"
#include "engine/scene/scene.h"
#include "protocol/edit_parser.h"
#include "protocol/problem.h"
#include "tests/engine/bulk_singles.h"

namespace {

using strata::protocol::Json;

/// True when a number overflowed to infinity: this reader keeps it (so that the protocol can
/// answer 422 not-finite with its pointer) where nlohmann refuses the document.
bool has_infinity(const Json& j) {
    if (strata::protocol::is_packed_numbers(j)) {
        for (std::size_t i = 0; i < strata::protocol::packed_size(j); ++i) {
            if (!std::isfinite(strata::protocol::packed_value(j, i))) return true;
        }
        return false;
    }
    if (j.is_number_float()) return !std::isfinite(j.get<double>());
    if (j.is_structured()) {
        for (const Json& e : j) {
            if (has_infinity(e)) return true;
        }
    }
    return false;
}

bool has_packed(const Json& j) {
    if (strata::protocol::is_packed_numbers(j)) return true;
    if (j.is_structured()) {
        for (const Json& e : j) {
            if (has_packed(e)) return true;
        }
    }
    return false;
}

/// A small scene for fuzzed batches to edit: ids that the corpus and dictionary use exist, so
/// batches get past "unknown id" into the other rules (and into undoing what they applied).
strata::Scene seed_scene() {
    strata::EditBatch b;
    b.edits.emplace_back(strata::AddMaterial{"red", strata::Material{}});
    strata::AddMesh mesh;
    mesh.id = "tri";
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    b.edits.emplace_back(std::move(mesh));
    strata::AddInstance inst;
    inst.id = "i";
    inst.mesh = "tri";
    b.edits.emplace_back(std::move(inst));
    strata::Scene scene;
    // Bulk edits name up to 2^24 instances in a few bytes: keep the fuzzed scenes small.
    strata::SceneBudget budget;
    budget.max_instances = 4096;
    scene.set_budget(budget);
    if (!scene.apply(std::move(b))) std::abort();
    scene.clear_changes();
    return scene;
}

/// A scene's objects, each encoded, sorted: equal for equal scenes whatever their slots.
std::vector<std::string> state_of(const strata::Scene& s) {
    std::vector<std::string> out;
    for (strata::Edit& e : s.to_batch().edits) {
        strata::EditBatch one;
        one.edits.push_back(std::move(e));
        out.emplace_back();
        strata::durable::encode_batch(one, out.back());
    }
    std::sort(out.begin(), out.end());
    return out;
}

bool has_bulk(const std::vector<strata::Edit>& edits) {
    for (const strata::Edit& e : edits) {
        if (std::holds_alternative<strata::AddInstances>(e) ||
            std::holds_alternative<strata::UpdateInstances>(e) ||
            std::holds_alternative<strata::RemoveInstances>(e))
            return true;
    }
    return false;
}

/// Aborts (a crash libFuzzer reports) with the line of the broken expectation.
#define FUZZ_CHECK(expr)                                                                \
    do {                                                                                \
        if (!(expr)) {                                                                  \
            std::fprintf(stderr, "fuzz check failed: %s (line %d)\n", #expr, __LINE__); \
            std::abort();                                                               \
        }                                                                               \
    } while (false)

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata::protocol;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    JsonLimits limits;
    limits.max_depth = 32;
    limits.max_array_elements = 1 << 16;

    // Step: the JSON reader against nlohmann.
    auto doc = parse_json(text, limits);
    // nlohmann stops reading at a NUL byte (for C strings) and would accept "1\0garbage"; the
    // comparison only holds for inputs without one.
    const bool comparable = text.find('\0') == std::string_view::npos;
    const bool nlohmann_accepts = comparable && Json::accept(text);
    if (!comparable) {
        // Our reader must refuse a NUL outside strings and accept none inside them either.
        FUZZ_CHECK(!doc.has_value());
    } else if (doc.has_value()) {
        if (has_infinity(doc.value())) {
            FUZZ_CHECK(!nlohmann_accepts);
        } else {
            FUZZ_CHECK(nlohmann_accepts);
            if (!has_packed(doc.value())) FUZZ_CHECK(doc.value() == Json::parse(text));
        }
    } else if (doc.error().type == ProblemType::MalformedJson &&
               doc.error().detail.find("duplicate key") == std::string::npos) {
        FUZZ_CHECK(!nlohmann_accepts);
    }
    if (!doc.has_value()) {
        (void)problem_to_json(doc.error());
        return 0;
    }

    // Step: a parse error points into the edit it blames.
    auto batch = parse_edit_batch(doc.value());
    if (!batch.has_value()) {
        const Problem& e = batch.error();
        FUZZ_CHECK(e.type == ProblemType::InvalidRequest || e.status == 422);
        if (e.edit_index != strata::Error::NO_INDEX) {
            const std::string edit = "/edits/" + std::to_string(e.edit_index);
            FUZZ_CHECK(e.pointer == edit || e.pointer.value_or("").starts_with(edit + "/"));
        }
        (void)problem_to_json(e);
        return 0;
    }

    // Step: the engine's rules on what the parser produced, against a small scene; a refused
    // batch must leave that scene exactly as it was.
    // Bulk edits also go through their single edits, on a second scene: both must be accepted
    // or refused together, and leave the same objects.
    std::optional<std::vector<strata::Edit>> twin;
    if (has_bulk(batch.value().batch.edits)) twin = strata::test::with_singles(batch.value().batch.edits);
    strata::Scene scene = seed_scene();
    const uint64_t before = scene.version();
    const std::size_t before_edits = scene.to_batch().edits.size();
    auto applied = scene.apply(std::move(batch.value().batch));
    if (!applied) {
        (void)problem_to_json(problem_from_batch_error(applied.error(), batch.value().sources));
        FUZZ_CHECK(scene.version() == before);
        FUZZ_CHECK(scene.to_batch().edits.size() == before_edits);
        FUZZ_CHECK(scene.changes().empty());
    }
    if (twin) {
        strata::Scene singles = seed_scene();
        const bool singles_applied = singles.apply(strata::EditBatch{std::move(*twin)}).has_value();
        FUZZ_CHECK(singles_applied == applied.has_value());
        if (singles_applied) FUZZ_CHECK(state_of(singles) == state_of(scene));
    }
    return 0;
}
