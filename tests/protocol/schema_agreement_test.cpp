// The C++ parser's structural stage against tests/protocol/batches.json, the table the JSON Schema
// is checked against by schema_agreement_test.py: same verdicts, and the pointer of each invalid
// batch's first problem.

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "protocol/edit_parser.h"

namespace strata::protocol {
namespace {

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
            << name << (problem ? ": " + problem->message : std::string());
        if (problem && c.contains("pointer")) {
            EXPECT_EQ(problem->pointer, c["pointer"].get<std::string>())
                << name << ": " << problem->message;
        }
    }
}

TEST(SchemaAgreement, StructurallyValidCasesWithANoteFailWithAValueError) {
    for (const Json& c : load_table()["cases"]) {
        if (!c.contains("note")) continue;
        auto parsed = parse_edit_batch(c["batch"].dump(), {});
        ASSERT_FALSE(parsed.has_value()) << c["name"];
        EXPECT_EQ(parsed.error().kind, RequestErrorKind::Value) << c["name"];
    }
}

}  // namespace
}  // namespace strata::protocol
