#include <gtest/gtest.h>

#include "protocol/transform_parser.h"

namespace strata::protocol {
namespace {

Affine parse(const char* text) {
    FieldReader r;
    const Affine a = parse_transform(r, Json::parse(text), "/t");
    EXPECT_FALSE(r.value_error().has_value()) << text;
    return a;
}

void expect_near(const Affine& a, const Affine& b) {
    for (int i = 0; i < 12; ++i) EXPECT_NEAR(a.m[i], b.m[i], 1e-6f) << i;
}

TEST(TransformParser, TwelveNumbersAreRowMajor) {
    const Affine a = parse("[1,0,0,5, 0,1,0,6, 0,0,1,7]");
    EXPECT_EQ(a, Affine::translation({5, 6, 7}));
}

TEST(TransformParser, SixteenNumbersDropTheLastRow) {
    EXPECT_EQ(parse("[2,0,0,1, 0,2,0,2, 0,0,2,3, 0,0,0,1]"),
              Affine::trs({1, 2, 3}, Affine::identity(), Vec3(2.0f)));
}

TEST(TransformParser, SixteenNumbersWithAProjectiveRowAreAValueError) {
    FieldReader r;
    parse_transform(r, Json::parse("[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]"), "/t");
    ASSERT_TRUE(r.value_error().has_value());
    EXPECT_EQ(r.value_error()->pointer, "/t/14");
}

TEST(TransformParser, ObjectFormComposesTranslateRotateScale) {
    expect_near(parse(R"({"translate": [1,2,3], "rotate_deg": [0,90,0], "scale": 2})"),
                Affine::trs({1, 2, 3}, Affine::rotation_euler_deg({0, 90, 0}), Vec3(2.0f)));
    expect_near(
        parse(R"({"quaternion": [0,0,0.7071068,0.7071068], "scale": [1,2,3]})"),
        Affine::trs({}, Affine::rotation_quaternion({0, 0, 0.7071068f, 0.7071068f}), {1, 2, 3}));
    EXPECT_EQ(parse("{}"), Affine::identity());
}

TEST(TransformParser, OverflowingNumbersAreNotFiniteAtTheirPointer) {
    FieldReader r;
    parse_transform(r, Json::parse(R"({"translate": [0, 1e39, 0]})"), "/t");
    ASSERT_TRUE(r.value_error().has_value());
    EXPECT_EQ(r.value_error()->type, ProblemType::NotFinite);
    EXPECT_EQ(r.value_error()->pointer, "/t/translate/1");
}

TEST(TransformParser, AQuaternionFarFromUnitLengthIsAValueError) {
    for (const char* q :
         {R"([1e19, 1e19, 1e19, 1e19])", R"([1e-30, 0, 0, 1e-30])", R"([3e38, 3e38, 0, 0])"}) {
        FieldReader r;
        parse_transform(r, Json::parse(std::string(R"({"quaternion": )") + q + "}"), "/t");
        ASSERT_TRUE(r.value_error().has_value()) << q;
        EXPECT_EQ(r.value_error()->pointer, "/t/quaternion") << q;
        EXPECT_NE(r.value_error()->detail.find("unit quaternion"), std::string::npos) << q;
    }
    FieldReader ok;
    parse_transform(ok, Json::parse(R"({"quaternion": [0, 0, 2, 2]})"), "/t");
    EXPECT_FALSE(ok.value_error().has_value());
}

TEST(TransformParser, AZeroQuaternionIsAValueError) {
    FieldReader r;
    parse_transform(r, Json::parse(R"({"quaternion": [0,0,0,0]})"), "/t");
    ASSERT_TRUE(r.value_error().has_value());
    EXPECT_EQ(r.value_error()->pointer, "/t/quaternion");
}

}  // namespace
}  // namespace strata::protocol
