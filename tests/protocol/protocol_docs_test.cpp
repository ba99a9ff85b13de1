// The written protocol against the tables it describes: protocol/edit-batch.schema.json is what
// the op table generates, and protocol/README.md's ops index and counters table are generated
// from the op table, ENGINE_COUNTERS and DURABLE_COUNTERS between marker comments; every op has a
// `### ` section
// whose examples parse as that op.
//
// After a change to an op or a counter, regenerate both files, then read the diff:
//   STRATA_UPDATE_DOCS=1 ctest --test-dir build -R ProtocolDocs

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/counters.h"
#include "engine/durable/durable_stats.h"
#include "protocol/edit_ops.h"
#include "protocol/edit_schema.h"
#include "protocol/field_json.h"
#include "protocol/openapi.h"
#include "protocol/problem.h"
#include "protocol/stat_names.h"
#include "tests/generated_docs.h"

namespace strata::protocol {
namespace {

const std::string SCHEMA_PATH = STRATA_SOURCE_DIR "/protocol/edit-batch.schema.json";
const std::string README_PATH = STRATA_SOURCE_DIR "/protocol/README.md";

using test::read_text;
using test::with_region;
using test::write_text;

/// GitHub's anchor of a heading: lower case, spaces to '-', other punctuation dropped.
std::string anchor(std::string_view heading) {
    std::string out;
    for (char c : heading) {
        if (c == ' ') {
            out += '-';
        } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') {
            out += char(std::tolower(static_cast<unsigned char>(c)));
        }
    }
    return out;
}

/// True when `text` names `word` as a whole word (ops are snake_case words).
bool names(std::string_view text, std::string_view word) {
    auto is_word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    for (std::size_t at = text.find(word); at != std::string_view::npos;
         at = text.find(word, at + 1)) {
        const std::size_t end = at + word.size();
        if ((at == 0 || !is_word(text[at - 1])) && (end == text.size() || !is_word(text[end])))
            return true;
    }
    return false;
}

/// One `### ` section of the README's "## Edit ops" part.
struct OpSection {
    std::string heading;
    std::vector<std::string> examples;  ///< the `{"op": ...}` lines of its ```json blocks
};

std::vector<OpSection> op_sections(const std::string& readme) {
    std::vector<OpSection> sections;
    std::istringstream in(readme);
    bool in_ops = false, in_json = false;
    for (std::string line; std::getline(in, line);) {
        if (line.starts_with("## ")) in_ops = line == "## Edit ops";
        if (!in_ops) continue;
        if (line.starts_with("### ")) sections.push_back({line.substr(4), {}});
        if (line.starts_with("```")) in_json = !in_json && line == "```json";
        if (in_json && line.starts_with("{\"op\"") && !sections.empty())
            sections.back().examples.push_back(line);
    }
    return sections;
}

const OpSection* section_of(const std::vector<OpSection>& sections, std::string_view op) {
    for (const OpSection& s : sections) {
        if (names(s.heading, op)) return &s;
    }
    return nullptr;
}

std::string ops_index(const std::vector<OpSection>& sections) {
    std::string out = "| op | what it does |\n|---|---|\n";
    for (const EditOp& op : edit_ops()) {
        const OpSection* s = section_of(sections, op.name);
        const std::string link = s ? "#" + anchor(s->heading) : "#edit-ops";
        out += "| [`" + std::string(op.name) + "`](" + link + ") | " + std::string(op.doc) + " |\n";
    }
    return out;
}

const char* unit_name(StatUnit u) {
    static const char* const UNITS[] = {"count", "bytes", "seconds", "milliseconds"};
    return UNITS[int(u)];
}

std::string counters_table() {
    std::string out =
        "| `counters` member | Prometheus counter | unit | counts |\n|---|---|---|---|\n";
    for (const CounterSpec& c : ENGINE_COUNTERS) {
        out += "| `" + std::string(c.name) + "` | `" + metric_name("strata_", c) + "` | " +
               unit_name(c.unit) + " | " + std::string(c.help) + " |\n";
    }
    return out;
}

std::string durable_counters_table() {
    std::string out =
        "| `durability` member | Prometheus | type | unit | what it is |\n"
        "|---|---|---|---|---|\n";
    for (const durable::DurableCounterSpec& c : durable::DURABLE_COUNTERS) {
        out += "| `" + std::string(c.name) + "` | `" + metric_name("strata_durable_", c) + "` | " +
               (c.cumulative ? "counter" : "gauge") + " | " + unit_name(c.unit) + " | " +
               std::string(c.help) + " |\n";
    }
    return out;
}

/// Every problem type by status: the README's table of them is the OpenAPI `Problem` schema's.
std::string problem_types_table() {
    std::vector<ProblemType> types;
    for (int i = 0; i <= int(ProblemType::Internal); ++i) types.push_back(ProblemType(i));
    std::stable_sort(types.begin(), types.end(), [](ProblemType a, ProblemType b) {
        return problem_status(a) < problem_status(b);
    });
    std::string out =
        "| status | `type` (after `https://strata.dev/problems/`) | when |\n"
        "|---|---|---|\n";
    for (ProblemType t : types) {
        const std::string uri = problem_type_uri(t);
        out += "| " + std::to_string(problem_status(t)) + " | `" + uri.substr(uri.rfind('/') + 1) +
               "` | " + problem_when(t) + " |\n";
    }
    return out;
}

/// A member's values in words, from its schema: "integer, [1, 65536]", "`png`, `exr`", ...
std::string values_of(const OrderedJson& s) {
    const auto range = [&s] {
        return "[" + s["minimum"].dump() + ", " + s["maximum"].dump() + "]";
    };
    if (s.contains("enum")) {
        std::string out;
        for (const auto& v : s["enum"])
            out += (out.empty() ? "`" : ", `") + v.get<std::string>() + "`";
        return out;
    }
    if (s.contains("$ref")) {
        const std::string ref = s["$ref"];
        return "`" + ref.substr(ref.rfind('/') + 1) + "` object";
    }
    const std::string type = s.value("type", "");
    if (type == "array" && s.contains("items")) return "list of " + values_of(s["items"]);
    if (type == "array") return "array of " + std::to_string(s.value("minItems", 0)) + " integers";
    if (s.contains("minimum")) return type + ", " + range();
    return type;
}

/// An object schema's members as a table: member, default, values, what it does.
std::string members_table(const OrderedJson& schema) {
    std::string out = "| member | default | values | |\n|---|---|---|---|\n";
    for (const auto& [name, member] : schema["properties"].items()) {
        out += "| `" + name + "` | " +
               (member.contains("default") ? "`" + member["default"].dump() + "`" : "") + " | " +
               values_of(member) + " | " + member.value("description", "") + " |\n";
    }
    return out;
}

/// Each object kind's fields, as the README's op sections show them.
std::vector<std::pair<std::string, std::string>> field_tables() {
    return {{"mesh", fields_markdown<MeshFields>()},
            {"texture", fields_markdown<TextureFields>()},
            {"material", fields_markdown<MaterialFields>()},
            {"material-textures", texture_slots_markdown()},
            {"instance", fields_markdown<InstanceFields>()},
            {"group", fields_markdown<GroupFields>()},
            {"light", fields_markdown<LightFields>()},
            {"camera", fields_markdown<CameraFields>()},
            {"lighting", fields_markdown<LightingFields>()},
            {"timeline", fields_markdown<TimelineFields>()}};
}

TEST(ProtocolDocs, CommittedSchemaIsTheOneTheOpTableGenerates) {
    const std::string generated = edit_batch_schema_text();
    if (test::updating_docs()) {
        write_text(SCHEMA_PATH, generated);
        GTEST_SKIP() << "rewrote " << SCHEMA_PATH;
    }
    EXPECT_TRUE(read_text(SCHEMA_PATH) == generated)
        << SCHEMA_PATH << " is not what the op table generates; see the top of this file";
}

TEST(ProtocolDocs, ReadmeOpsIndexAndCountersTableAreGeneratedFromTheirTables) {
    const std::string readme = read_text(README_PATH);
    auto updated = with_region(readme, "edit-ops", ops_index(op_sections(readme)));
    ASSERT_TRUE(updated) << "README lacks the edit-ops markers";
    updated = with_region(*updated, "counters", counters_table());
    ASSERT_TRUE(updated) << "README lacks the counters markers";
    updated = with_region(*updated, "durable-counters", durable_counters_table());
    ASSERT_TRUE(updated) << "README lacks the durable-counters markers";
    updated = with_region(*updated, "problem-types", problem_types_table());
    ASSERT_TRUE(updated) << "README lacks the problem-types markers";
    updated = with_region(*updated, "render-request",
                          members_table(component_schemas().at("RenderRequest")));
    ASSERT_TRUE(updated) << "README lacks the render-request markers";
    for (const auto& [kind, table] : field_tables()) {
        updated = with_region(*updated, "fields-" + kind, table);
        ASSERT_TRUE(updated) << "README lacks the fields-" << kind << " markers";
    }
    if (test::updating_docs()) {
        if (*updated != readme) write_text(README_PATH, *updated);
        GTEST_SKIP() << "rewrote the generated parts of " << README_PATH;
    }
    EXPECT_TRUE(*updated == readme)
        << README_PATH << ": a generated table is stale; see the top of this file";
}

TEST(ProtocolDocs, EveryOpHasAReadmeSectionWhoseExamplesParseAsThatOp) {
    const std::vector<OpSection> sections = op_sections(read_text(README_PATH));
    std::map<std::string, int> examples;
    for (const OpSection& section : sections) {
        for (const std::string& line : section.examples) {
            auto parsed = parse_edit_batch("{\"edits\": [" + line + "]}", {});
            ASSERT_TRUE(parsed.has_value()) << line << ": " << parsed.error().detail;
            const std::string name = parse_json(line).value()["op"].get<std::string>();
            EXPECT_TRUE(names(section.heading, name)) << line << " is under " << section.heading;
            const EditOp* op = find_edit_op(name);
            ASSERT_NE(op, nullptr);
            EXPECT_TRUE(op->produces & edit_kind(parsed.value().batch.edits.at(0))) << line;
            ++examples[name];
        }
    }
    for (const EditOp& op : edit_ops()) {
        EXPECT_NE(section_of(sections, op.name), nullptr)
            << "no ### section under ## Edit ops names " << op.name;
        EXPECT_GT(examples[std::string(op.name)], 0) << "no ```json example of " << op.name;
    }
}

}  // namespace
}  // namespace strata::protocol
