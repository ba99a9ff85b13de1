// The C++ parser's structural stage against tests/protocol/batches.json, the table the JSON Schema
// is checked against by schema_agreement_test.py: same verdicts, and the pointer of each invalid
// batch's first problem; and the kinds of Edit each op's parser produces.

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "protocol/edit_ops.h"
#include "protocol/edit_parser.h"

namespace strata::protocol {
namespace {

/// The structural verdict alone (what the JSON Schema decides): the parser's schema error, or
/// nullopt when the batch has none (a value error may remain).
std::optional<Problem> check_edit_batch_structure(const Json& body) {
    auto parsed = parse_edit_batch(body);
    if (parsed.has_value() || parsed.error().type != ProblemType::InvalidRequest)
        return std::nullopt;
    return parsed.error();
}

Json load_table() {
    std::ifstream in(STRATA_SOURCE_DIR "/tests/protocol/batches.json");
    std::stringstream text;
    text << in.rdbuf();
    auto doc = parse_json(text.str());
    EXPECT_TRUE(doc.has_value());
    return doc.has_value() ? doc.value() : Json();
}

TEST(SchemaAgreement, ParserGivesTheTableVerdicts) {
    const Json table = load_table();
    ASSERT_TRUE(table.contains("cases"));
    ASSERT_GT(table["cases"].size(), 50u);
    for (const Json& c : table["cases"]) {
        const std::string name = c["name"].get<std::string>();
        // Re-parse through the text form so the batch goes through the same reader as requests.
        auto body = parse_json(c["batch"].dump());
        ASSERT_TRUE(body.has_value()) << name;
        const auto problem = check_edit_batch_structure(body.value());
        EXPECT_EQ(!problem.has_value(), c["valid"].get<bool>())
            << name << (problem ? ": " + problem->detail : std::string());
        if (problem && c.contains("pointer")) {
            EXPECT_EQ(problem->pointer, c["pointer"].get<std::string>())
                << name << ": " << problem->detail;
        }
    }
}

TEST(SchemaAgreement, StructurallyValidCasesWithANoteFailWithAValueError) {
    const Json table = load_table();  // the loop below must not outlive it
    for (const Json& c : table["cases"]) {
        if (!c.contains("note")) continue;
        auto parsed = parse_edit_batch(c["batch"].dump(), {});
        ASSERT_FALSE(parsed.has_value()) << c["name"];
        EXPECT_EQ(parsed.error().status, 422) << c["name"];
    }
}

TEST(SchemaAgreement, ParsedEditsAreOfKindsTheirOpDeclaresAndCoverEveryEditAlternative) {
    EditKinds seen = 0;
    const Json table = load_table();
    for (const Json& c : table["cases"]) {
        auto parsed = parse_edit_batch(c["batch"].dump(), {});
        if (!parsed.has_value()) continue;
        const Json& edits = c["batch"]["edits"];
        for (std::size_t i = 0; i < edits.size(); ++i) {
            const EditOp* op = find_edit_op(edits[i]["op"].get<std::string>());
            ASSERT_NE(op, nullptr) << c["name"];
            const EditKinds kind = edit_kind(parsed.value().batch.edits.at(i));
            EXPECT_TRUE(op->produces & kind) << c["name"] << ", edit " << i;
            seen |= kind;
        }
    }
    EXPECT_EQ(seen, (EditKinds{1} << std::variant_size_v<Edit>)-1)
        << "some Edit alternative comes from no valid batch of the table";
}

}  // namespace
}  // namespace strata::protocol
