#include <gtest/gtest.h>

#include "protocol/base64.h"

namespace strata::protocol {
namespace {

TEST(Base64, RoundTripsEveryLengthAndByte) {
    std::string bytes;
    for (int i = 0; i < 300; ++i) {
        bytes.push_back(static_cast<char>(i * 37));
        const auto decoded = decode_base64(encode_base64(bytes));
        ASSERT_TRUE(decoded.has_value()) << i;
        EXPECT_EQ(*decoded, bytes);
    }
}

TEST(Base64, DecodesTheRfc4648Vectors) {
    EXPECT_EQ(decode_base64(""), "");
    EXPECT_EQ(decode_base64("Zg=="), "f");
    EXPECT_EQ(decode_base64("Zm8="), "fo");
    EXPECT_EQ(decode_base64("Zm9v"), "foo");
    EXPECT_EQ(decode_base64("Zm9vYmFy"), "foobar");
}

TEST(Base64, RefusesBadCharactersAndLengthsWithTheirOffset) {
    std::size_t at = 0;
    EXPECT_FALSE(decode_base64("Zm9v*mFy", &at));
    EXPECT_EQ(at, 4u);
    EXPECT_FALSE(decode_base64("Zm9", &at));
    EXPECT_EQ(at, 3u);
    EXPECT_FALSE(decode_base64("Zm 9v", &at));
    EXPECT_FALSE(decode_base64("Z===", &at));
    EXPECT_FALSE(decode_base64("Zg=a", &at));
    EXPECT_FALSE(decode_base64("Zm9v\n", &at));
}

}  // namespace
}  // namespace strata::protocol
