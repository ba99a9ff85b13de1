// Frames as .npz: the archive read back by a reader written from the ZIP and .npy
// specifications (not by the encoder's code), each entry's CRC-32 checked with zlib, and the
// arrays holding exactly the values the EXR of the same frame holds.

#include <cstring>
#include <map>
#include <string>

#include <zlib.h>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "engine/image/npz.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

uint32_t u16(const std::string& b, std::size_t at) {
    return uint32_t(uint8_t(b[at])) | uint32_t(uint8_t(b[at + 1])) << 8;
}
uint32_t u32(const std::string& b, std::size_t at) {
    return u16(b, at) | u16(b, at + 2) << 16;
}

struct ReadArray {
    std::string header;  ///< the .npy header dict
    std::string data;
};

/// The archive's entries by name, through the central directory; checks what the format
/// requires on the way (signatures, sizes agreeing, CRCs, stored entries, aligned data).
std::map<std::string, ReadArray> read_npz(const std::string& zip) {
    std::map<std::string, ReadArray> out;
    EXPECT_GE(zip.size(), 22u);
    if (zip.size() < 22) return out;
    const std::size_t eocd = zip.size() - 22;
    EXPECT_EQ(u32(zip, eocd), 0x06054b50u);
    const uint32_t entries = u16(zip, eocd + 10);
    std::size_t at = u32(zip, eocd + 16);
    EXPECT_EQ(at + u32(zip, eocd + 12), eocd) << "the directory ends where the end record starts";
    for (uint32_t i = 0; i < entries; ++i) {
        EXPECT_EQ(u32(zip, at), 0x02014b50u);
        EXPECT_EQ(u16(zip, at + 10), 0u) << "stored";
        const uint32_t crc = u32(zip, at + 16), size = u32(zip, at + 20);
        EXPECT_EQ(size, u32(zip, at + 24));
        const uint32_t name_len = u16(zip, at + 28);
        const std::string name = zip.substr(at + 46, name_len);
        const std::size_t local = u32(zip, at + 42);
        at += 46 + name_len + u16(zip, at + 30) + u16(zip, at + 32);
        EXPECT_EQ(u32(zip, local), 0x04034b50u) << name;
        EXPECT_EQ(zip.substr(local + 30, u16(zip, local + 26)), name);
        const std::string file = zip.substr(local + 30 + u16(zip, local + 26) + u16(zip, local + 28), size);
        EXPECT_EQ(uint32_t(::crc32(0, reinterpret_cast<const Bytef*>(file.data()), uInt(file.size()))),
                  crc)
            << name;
        EXPECT_EQ(file.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8)) << name;
        const uint32_t header_len = u16(file, 8);
        EXPECT_EQ((10 + header_len) % 64, 0u) << name << ": data 64-byte aligned";
        EXPECT_EQ(file[10 + header_len - 1], '\n');
        EXPECT_TRUE(name.size() > 4 && name.substr(name.size() - 4) == ".npy") << name;
        out[name.substr(0, name.size() - 4)] =
            ReadArray{file.substr(10, header_len), file.substr(10 + header_len)};
    }
    return out;
}

TEST(Npz, HeadersSayTypeAndShapeAsNumpyWritesThem) {
    const float values[6] = {1, 2, 3, 4, 5, 6};
    const std::string one = npy_header({"a", "<f4", {2, 3}, {}});
    EXPECT_NE(one.find("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"),
              std::string::npos);
    EXPECT_NE(npy_header({"a", "<u4", {5}, {}}).find("'shape': (5,), }"), std::string::npos);
    auto zip = encode_npz({{"a", "<f4", {2, 3}, {reinterpret_cast<const char*>(values), 24}},
                           {"b.ids", "<u4", {0}, {}}});
    ASSERT_TRUE(zip.has_value());
    const auto arrays = read_npz(zip.value());
    ASSERT_EQ(arrays.size(), 2u);
    EXPECT_EQ(arrays.at("a").data, std::string(reinterpret_cast<const char*>(values), 24));
    EXPECT_EQ(arrays.at("b.ids").data, "");
}

TEST(Npz, TextsAreFixedWidthUtf32WithBadBytesReplaced) {
    std::vector<uint32_t> points;
    EXPECT_EQ(utf32_array({"ab", "\xC3\xBC", "m\xFF"}, points), "<U2");
    EXPECT_EQ(points, (std::vector<uint32_t>{'a', 'b', 0xFC, 0, 'm', 0xFFFD}));
    EXPECT_EQ(utf32_array({}, points), "<U1");
    EXPECT_TRUE(points.empty());
}

TEST(Npz, AFrameHoldsTheExrFramesValuesAndItsManifest) {
    auto engine = test::make_engine();
    Camera cam;
    cam.eye = Vec3(0.0f, 1.0f, 6.0f);
    cam.target = Vec3(0.0f);
    test::apply_ok(*engine, test::mesh_edit("ball", make_sphere(1.0f, 24)),
                   test::instance_edit("left", "ball", Vec3(-1.2f, 0.0f, 0.0f)),
                   test::instance_edit("right \xC3\xBC", "ball", Vec3(1.2f, 0.0f, 0.0f)),
                   test::camera_edit(cam));
    const std::vector<Aov> aovs = {Aov::Depth, Aov::Position, Aov::InstanceId, Aov::MeshId};
    const EncodedFrame npz =
        test::render_ok(*engine, test::request(40, 20, 2, aovs, ImageFormat::Npz));
    EXPECT_EQ(npz.content_type, "application/x-npz");
    const DecodedExr exr =
        test::decode_exr_ok(test::render_ok(*engine, test::request(40, 20, 2, aovs)).bytes);
    const auto arrays = read_npz(npz.bytes);
    ASSERT_EQ(arrays.size(), 9u);  // beauty, 4 AOVs, 2 manifests of 2 arrays
    EXPECT_NE(arrays.at("beauty").header.find("'<f4'"), std::string::npos);
    EXPECT_NE(arrays.at("beauty").header.find("(20, 40, 3)"), std::string::npos);
    EXPECT_NE(arrays.at("instance_id").header.find("'<u4'"), std::string::npos);
    // Depth and ids equal the EXR's to the bit (FLOAT and UINT there), as does the position.
    const auto same = [&](const std::string& array, const std::string& channel, int k, int n) {
        const std::string& data = arrays.at(array).data;
        const DecodedExrChannel* c = exr.find(channel);
        ASSERT_NE(c, nullptr) << channel;
        ASSERT_EQ(data.size(), std::size_t(40 * 20 * n * 4)) << array;
        for (std::size_t p = 0; p < 40 * 20; ++p) {
            uint32_t bits = 0;
            std::memcpy(&bits, data.data() + (p * n + k) * 4, 4);
            uint32_t want = 0;
            if (c->type == ExrPixel::Uint)
                want = c->u32[p];
            else
                std::memcpy(&want, &c->f32[p], 4);
            ASSERT_EQ(bits, want) << array << " pixel " << p;
        }
    };
    same("depth", "Z", 0, 1);
    same("instance_id", "instance_id", 0, 1);
    same("mesh_id", "mesh_id", 0, 1);
    same("position", "P.Y", 1, 3);
    // The manifest: ids beside UTF-32 names, the EXR manifest's entries in the same order.
    ASSERT_EQ(exr.ids.size(), 2u);
    const ExrIdTable& table = exr.ids[0].channel == "instance_id" ? exr.ids[0] : exr.ids[1];
    const std::string& ids = arrays.at("instance_id.ids").data;
    const std::string& names = arrays.at("instance_id.names").data;
    ASSERT_EQ(ids.size(), table.entries.size() * 4);
    EXPECT_NE(arrays.at("instance_id.names").header.find("'<U7'"), std::string::npos);
    for (std::size_t k = 0; k < table.entries.size(); ++k) {
        EXPECT_EQ(u32(ids, k * 4), table.entries[k].first);
        std::string ascii;
        for (std::size_t c = 0; c < 7; ++c) {
            const uint32_t cp = u32(names, (k * 7 + c) * 4);
            if (cp) ascii += cp < 0x80 ? char(cp) : '?';
        }
        EXPECT_EQ(ascii, table.entries[k].second == "left" ? "left" : "right ?");
    }
}

TEST(Npz, PngStillRefusesAovsAndNamesTheFormatsThatCarryThem) {
    RenderRequest r = test::request(8, 8, 1, {Aov::Depth}, ImageFormat::Png);
    Status s = check_render_request(r);
    ASSERT_FALSE(s);
    EXPECT_NE(s.error().message.find("exr or npz"), std::string::npos);
    r.format = ImageFormat::Npz;
    EXPECT_TRUE(check_render_request(r));
}

}  // namespace
}  // namespace strata
