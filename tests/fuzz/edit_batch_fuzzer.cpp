// libFuzzer target for the edit batch parser (and the JSON reader under it).
//
// Checks, besides "no crash, no sanitizer report":
//   - the JSON reader accepts exactly what nlohmann accepts (but for duplicate keys, which it
//     refuses on purpose, and inputs over its limits), and reads the same values;
//   - the structural stage alone and the full parse agree;
//   - a parsed batch goes through the engine's validation, and any error maps to a problem.
// Build and run: scripts/run-fuzz.sh.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "engine/scene/scene.h"
#include "protocol/edit_parser.h"
#include "protocol/problem.h"

namespace {

using strata::protocol::Json;

bool has_packed(const Json& j) {
    if (strata::protocol::is_packed_numbers(j)) return true;
    if (j.is_structured()) {
        for (const Json& e : j) {
            if (has_packed(e)) return true;
        }
    }
    return false;
}

void check(bool ok) {
    if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata::protocol;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    JsonLimits limits;
    limits.max_depth = 32;
    limits.max_array_elements = 1 << 16;

    // Step: the JSON reader against nlohmann.
    auto doc = parse_json(text, limits);
    const bool nlohmann_accepts = Json::accept(text);
    if (doc.ok()) {
        check(nlohmann_accepts);
        if (!has_packed(doc.value())) check(doc.value() == Json::parse(text));
    } else if (doc.error().kind == RequestErrorKind::Syntax &&
               doc.error().message.find("duplicate key") == std::string::npos) {
        check(!nlohmann_accepts);
    }
    if (!doc.ok()) {
        (void)problem_to_json(problem_from(doc.error()));
        return 0;
    }

    // Step: structural stage and full parse agree.
    const auto structure = check_edit_batch_structure(doc.value());
    auto batch = parse_edit_batch(doc.value());
    if (structure) {
        check(!batch.ok() && batch.error().kind == RequestErrorKind::Schema);
        check(batch.error().pointer == structure->pointer);
    } else if (!batch.ok()) {
        check(batch.error().kind == RequestErrorKind::Value);
    }
    if (!batch.ok()) {
        (void)problem_to_json(problem_from(batch.error()));
        return 0;
    }

    // Step: engine validation of what the parser produced.
    static const strata::Scene scene;
    if (strata::Status s = scene.validate(batch.value().batch); !s) {
        (void)problem_to_json(problem_from_batch_error(s.error(), batch.value().sources));
    }
    return 0;
}
