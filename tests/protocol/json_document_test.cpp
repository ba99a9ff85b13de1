// The strict JSON reader: RFC 8259 conformance, limits, duplicate keys and packed numeric arrays.

#include <gtest/gtest.h>

#include "protocol/json_document.h"

namespace strata::protocol {
namespace {

Json parse_ok(std::string_view text, const JsonLimits& limits = {}) {
    auto r = parse_json(text, limits);
    EXPECT_TRUE(r.has_value()) << text << ": " << (r.has_value() ? "" : r.error().detail);
    return r.has_value() ? r.value() : Json();
}

Problem parse_fails(std::string_view text, const JsonLimits& limits = {}) {
    auto r = parse_json(text, limits);
    EXPECT_FALSE(r.has_value()) << text;
    return r.has_value() ? Problem{} : r.error();
}

TEST(JsonDocument, ReadsEveryKindOfValueLikeNlohmann) {
    const char* texts[] = {
        R"({"a": [1, -2, 3.5, 1e3, -0, 0.25E-2], "b": {"c": null, "d": true, "e": false}, "s": "x\"\\\/\b\f\n\r\t\u00e9\ud83d\ude00"})",
        "  [ ]  ",
        "{}",
        "0",
        "-1",
        "18446744073709551615",
        "-9223372036854775808",
        "\"\"",
        "[[[]]]",
        "12345678901234567890123",
        "1.5e308",
        "\"h\xC3\xA9llo\"",
    };
    for (const char* t : texts) EXPECT_EQ(parse_ok(t), Json::parse(t)) << t;
}

TEST(JsonDocument, RefusesWhatStrictJsonRefuses) {
    const char* texts[] = {"",
                           " ",
                           "{",
                           "[1,]",
                           "{\"a\":1,}",
                           "01",
                           "1.",
                           ".5",
                           "+1",
                           "1e",
                           "-",
                           "NaN",
                           "Infinity",
                           "tru",
                           "nul",
                           "'a'",
                           "{a:1}",
                           "[1 2]",
                           "\"\\x\"",
                           "\"\\ud800\"",
                           "\"\\udc00\"",
                           "\"a\nb\"",
                           "\"\xC0\xAF\"",
                           "\"\xED\xA0\x80\"",
                           "\"\xF5\x80\x80\x80\"",
                           "\"\xE2\x82\"",
                           "[1] x",
                           "// c\n1",
                           "{\"a\" 1}",
                           "\"unterminated"};
    for (const char* t : texts) {
        EXPECT_EQ(parse_fails(t).type, ProblemType::MalformedJson) << t;
        EXPECT_FALSE(Json::accept(t)) << t;
    }
}

TEST(JsonDocument, NamesTheByteWhereItStopped) {
    EXPECT_NE(parse_fails("[1, 2, x]").detail.find("byte 7"), std::string::npos);
}

TEST(JsonDocument, RefusesDuplicateKeys) {
    const Problem e = parse_fails(R"({"edits": [], "edits": []})");
    EXPECT_EQ(e.type, ProblemType::MalformedJson);
    EXPECT_NE(e.detail.find("duplicate key 'edits'"), std::string::npos);
}

TEST(JsonDocument, OverflowingNumbersBecomeInfinityAndUnderflowingOnesZero) {
    const Json j = parse_ok("[1e999, -1e999, 1e-999]");
    EXPECT_TRUE(std::isinf(j[0].get<double>()));
    EXPECT_LT(j[1].get<double>(), 0.0);
    EXPECT_EQ(j[2].get<double>(), 0.0);
}

TEST(JsonDocument, EnforcesTheDepthLimit) {
    JsonLimits limits;
    limits.max_depth = 4;
    parse_ok("[[[[1]]]]", limits);
    EXPECT_EQ(parse_fails("[[[[[1]]]]]", limits).type, ProblemType::NestingTooDeep);
    EXPECT_EQ(parse_fails(std::string(100000, '['), {}).type, ProblemType::NestingTooDeep);
}

TEST(JsonDocument, EnforcesTheArrayLimitOnPackedAndPlainArrays) {
    JsonLimits limits;
    limits.max_array_elements = 100;
    std::string numbers = "[0", strings = "[\"a\"";
    for (int i = 1; i < 101; ++i) numbers += ",1", strings += ",\"a\"";
    EXPECT_EQ(parse_fails(numbers + "]", limits).type, ProblemType::TooLarge);
    EXPECT_EQ(parse_fails(strings + "]", limits).type, ProblemType::TooLarge);
}

TEST(JsonDocument, PacksLongNumericArraysAndKeepsShortOnesAsNodes) {
    std::string text = "{\"short\": [1, 2.5], \"long\": [";
    for (std::size_t i = 0; i < PACK_THRESHOLD * 3; ++i)
        text += (i ? "," : "") + std::to_string(i) + ".5";
    text += "]}";
    const Json j = parse_ok(text);
    EXPECT_TRUE(j["short"].is_array());
    ASSERT_TRUE(is_packed_numbers(j["long"]));
    ASSERT_EQ(packed_size(j["long"]), PACK_THRESHOLD * 3);
    for (std::size_t i = 0; i < PACK_THRESHOLD * 3; ++i)
        EXPECT_EQ(packed_value(j["long"], i), double(i) + 0.5);
}

TEST(JsonDocument, UnpacksALongArrayThatTurnsOutMixed) {
    std::string text = "[";
    for (std::size_t i = 0; i < PACK_THRESHOLD * 2; ++i) text += std::to_string(i) + ",";
    text += "\"x\", {\"a\": 1}]";
    const Json j = parse_ok(text);
    ASSERT_TRUE(j.is_array());
    ASSERT_EQ(j.size(), PACK_THRESHOLD * 2 + 2);
    EXPECT_EQ(j[5].get<double>(), 5.0);
    EXPECT_EQ(j[PACK_THRESHOLD * 2], "x");
    EXPECT_EQ(j.back()["a"], 1);
}

TEST(JsonDocument, NeverPacksAnArrayThatStartedWithANonNumber) {
    // Found by the fuzzer: an object first, then PACK_THRESHOLD numbers.
    std::string text = "[{\"g\": 50}";
    for (std::size_t i = 0; i < PACK_THRESHOLD * 2; ++i) text += "," + std::to_string(i) + ".5";
    text += "]";
    const Json j = parse_ok(text);
    ASSERT_TRUE(j.is_array());
    EXPECT_EQ(j.size(), PACK_THRESHOLD * 2 + 1);
    EXPECT_EQ(j, Json::parse(text));
}

}  // namespace
}  // namespace strata::protocol
