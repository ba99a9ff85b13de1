// The PLY reader: the three encodings agree, polygons are fan-triangulated, attributes are read,
// a file without faces is a point cloud, and every broken header or body is refused naming the
// element.

#include <bit>
#include <cstring>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::Not;

const std::string QUAD_ASCII = R"(ply
format ascii 1.0
comment a unit quad and a triangle, with normals and colours
element vertex 5
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
property uchar green
property uchar blue
element face 2
property list uchar int vertex_indices
end_header
0 0 0 0 0 1 255 0 0
1 0 0 0 0 1 0 255 0
1 1 0 0 0 1 0 0 255
0 1 0 0 0 1 255 255 255
2 2 2 0 0 1 0 0 0
4 0 1 2 3
3 1 4 2
)";

/// The same file in binary, little- or big-endian.
std::string quad_binary(bool big) {
    std::string header = QUAD_ASCII.substr(0, QUAD_ASCII.find("end_header\n") + 11);
    header.replace(header.find("ascii"), 5, big ? "binary_big_endian" : "binary_little_endian");
    const float v[5][6] = {{0, 0, 0, 0, 0, 1},
                           {1, 0, 0, 0, 0, 1},
                           {1, 1, 0, 0, 0, 1},
                           {0, 1, 0, 0, 0, 1},
                           {2, 2, 2, 0, 0, 1}};
    const uint8_t c[5][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}, {0, 0, 0}};
    auto put = [&](std::string& out, const void* p, std::size_t n) {
        std::string b(static_cast<const char*>(p), n);
        if (big) std::reverse(b.begin(), b.end());
        out += b;
    };
    std::string body;
    for (int i = 0; i < 5; ++i) {
        for (float f : v[i]) put(body, &f, 4);
        body.append(reinterpret_cast<const char*>(c[i]), 3);
    }
    const int32_t quad[4] = {0, 1, 2, 3}, tri[3] = {1, 4, 2};
    body += char(4);
    for (int32_t i : quad) put(body, &i, 4);
    body += char(3);
    for (int32_t i : tri) put(body, &i, 4);
    return header + body;
}

void expect_quad_mesh(const Asset& a) {
    ASSERT_EQ(a.meshes.size(), 1u);
    const AssetMesh& m = a.meshes[0];
    ASSERT_EQ(m.positions.size(), 5u);
    EXPECT_EQ(m.positions[4], Vec3(2, 2, 2));
    ASSERT_EQ(m.triangles.size(), 3u);  // the quad as a fan of two, then the triangle
    EXPECT_EQ(m.triangles[0], Triangle(0, 1, 2));
    EXPECT_EQ(m.triangles[1], Triangle(0, 2, 3));
    EXPECT_EQ(m.triangles[2], Triangle(1, 4, 2));
    ASSERT_EQ(m.normals.size(), 5u);
    EXPECT_EQ(m.normals[0], Vec3(0, 0, 1));
    ASSERT_EQ(m.colors.size(), 5u);
    EXPECT_EQ(m.colors[1], Vec3(0, 1, 0));
    ASSERT_EQ(a.nodes.size(), 1u);
    EXPECT_EQ(a.nodes[0].meshes, std::vector<int>{0});
}

TEST(PlyImport, AsciiQuadsAreFanTriangulatedWithNormalsAndColours) {
    auto a = import_text(AssetFormat::Ply, QUAD_ASCII);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    expect_quad_mesh(a.value());
}

TEST(PlyImport, BinaryLittleAndBigEndianGiveTheSameMeshAsAscii) {
    for (bool big : {false, true}) {
        auto a = import_text(AssetFormat::Ply, quad_binary(big));
        ASSERT_TRUE(a.has_value()) << a.error().detail;
        expect_quad_mesh(a.value());
    }
}

TEST(PlyImport, TextureCoordinatesAreReadUnderEitherName) {
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nproperty float s\n"
        "property float t\nelement face 1\n"
        "property list uchar uint vertex_index\nend_header\n"
        "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n";
    auto a = import_text(AssetFormat::Ply, ply);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes[0].uvs.size(), 3u);
    // PLY's v grows upward; the engine's downward from the image's top row.
    EXPECT_EQ(a.value().meshes[0].uvs[2], glm::vec2(0, 0));
    EXPECT_EQ(a.value().meshes[0].uvs[1], glm::vec2(1, 1));
}

/// The error of importing `text`, which must fail.
protocol::Problem refusal(const std::string& text, const ImportLimits& limits = {}) {
    auto a = import_text(AssetFormat::Ply, text, {}, limits);
    EXPECT_FALSE(a.has_value());
    return a.has_value() ? protocol::Problem{} : a.error();
}

TEST(PlyImport, AFaceIndexOutsideTheVerticesIsRefusedNamingTheFace) {
    std::string ply = QUAD_ASCII;
    ply.replace(ply.find("3 1 4 2"), 7, "3 1 5 2");
    const protocol::Problem e = refusal(ply);
    EXPECT_EQ(e.type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(e.file, "test.ply");
    EXPECT_EQ(e.element, "element face 1");
    EXPECT_THAT(e.detail, HasSubstr("vertex index 5"));
}

TEST(PlyImport, ATruncatedBinaryBodyIsRefused) {
    const std::string ply = quad_binary(false);
    for (std::size_t cut : {std::size_t(1), std::size_t(7), std::size_t(40)}) {
        const protocol::Problem e = refusal(ply.substr(0, ply.size() - cut));
        EXPECT_THAT(e.element.value_or(""), HasSubstr("element")) << e.detail;
        EXPECT_THAT(e.detail, HasSubstr("missing or malformed")) << e.detail;
    }
}

TEST(PlyImport, AHugeDeclaredCountIsRefusedBeforeAnythingIsAllocated) {
    std::string ply = QUAD_ASCII;
    ply.replace(ply.find("vertex 5"), 8, "vertex 4000000000");
    EXPECT_THAT(refusal(ply).detail, HasSubstr("more than the"));
    // Within the bytes that follow but over the scene's room: TooLarge.
    ImportLimits small;
    small.max_vertices = 4;
    const protocol::Problem e = refusal(QUAD_ASCII, small);
    EXPECT_EQ(e.type, protocol::ProblemType::TooLarge);
    EXPECT_THAT(e.detail, HasSubstr("max_scene_vertices"));
}

TEST(PlyImport, BrokenHeadersAreRefusedNamingTheLine) {
    EXPECT_EQ(refusal("ply\nformat ascii 1.0\nelement vertex 1\n").element, "header");
    EXPECT_THAT(refusal("plx\nformat ascii 1.0\nend_header\n").detail, HasSubstr("'ply'"));
    EXPECT_EQ(refusal("ply\nformat ascii 2.0\nend_header\n").type,
              protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(refusal("ply\nformat ascii 1.0\nproperty float x\nend_header\n").element,
              "header line 3");
    EXPECT_THAT(refusal("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                        "end_header\n1\n")
                    .detail,
                HasSubstr("x, y and z"));
}

TEST(PlyImport, HeaderLinesWithUnknownKeywordsAreSkippedWithAWarning) {
    // As Blender 2.47 wrote them (assimp-testmodels' PLY/Wuson.ply): free text without `comment`.
    std::string ply = QUAD_ASCII;
    ply.insert(ply.find("element vertex"),
               "Created by Blender3D 247 - www.blender.org, source file: ''\n");
    auto a = import_text(AssetFormat::Ply, ply);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    expect_quad_mesh(a.value());
    ASSERT_EQ(a.value().warnings.size(), 1u);
    EXPECT_EQ(a.value().warnings[0], "header line 4 skipped: unknown keyword 'Created'");
    // Many such lines: the first few named, the rest counted.
    std::string noisy = QUAD_ASCII;
    std::string lines;
    for (int i = 0; i < 100; ++i) lines += "junk " + std::to_string(i) + "\n";
    noisy.insert(noisy.find("element vertex"), lines);
    auto b = import_text(AssetFormat::Ply, noisy);
    ASSERT_TRUE(b.has_value()) << b.error().detail;
    ASSERT_EQ(b.value().warnings.size(), 9u);
    EXPECT_EQ(b.value().warnings.back(), "92 more header lines with unknown keywords skipped");
}

TEST(PlyImport, BlendersOldHeaderImports) {
    const std::string text = read_file(std::string(STRATA_ASSIMP_MODELS_DIR) + "/PLY/Wuson.ply");
    if (text.empty()) GTEST_SKIP() << "assimp-testmodels missing";
    auto a = import_text(AssetFormat::Ply, text);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_EQ(a.value().meshes.at(0).positions.size(), 11184u);
    EXPECT_GE(a.value().meshes.at(0).triangles.size(), 3732u);
    EXPECT_THAT(a.value().warnings[0], HasSubstr("unknown keyword 'Created'"));
}

/// An ASCII PLY of 4 vertices with `properties`, the elements `after` declares, and `rows`.
std::string cloud_ascii(const std::string& properties, const std::string& rows,
                        const std::string& after = "") {
    return "ply\nformat ascii 1.0\nelement vertex 4\n" + properties + after + "end_header\n" + rows;
}

const std::string XYZ = "property float x\nproperty float y\nproperty float z\n";
/// Four corners of a 3 by 4 rectangle: their bounds' diagonal is 5.
const std::string CORNER_ROWS = "0 0 0\n3 0 0\n3 4 0\n0 4 0\n";

TEST(PlyImport, APointCloudWithoutFacesIsAPointsMeshWithTheDefaultRadius) {
    // No face element, or one of no faces: the same point cloud.
    for (const std::string faces :
         {"", "element face 0\nproperty list uchar int vertex_indices\n"}) {
        auto a = import_text(AssetFormat::Ply, cloud_ascii(XYZ, CORNER_ROWS, faces));
        ASSERT_TRUE(a.has_value()) << a.error().detail;
        ASSERT_EQ(a.value().meshes.size(), 1u);
        const AssetMesh& m = a.value().meshes[0];
        EXPECT_EQ(m.kind, MeshKind::Points);
        ASSERT_EQ(m.positions.size(), 4u);
        EXPECT_EQ(m.positions[2], Vec3(3, 4, 0));
        EXPECT_TRUE(m.triangles.empty());
        // 0.5 * D / sqrt(N) with D = 5 and N = 4, named in a warning.
        EXPECT_EQ(m.radii, std::vector<float>(4, 1.25f));
        EXPECT_THAT(a.value().warnings,
                    Contains(HasSubstr("4 vertices are points, without a radius property; "
                                       "each has radius 1.25")));
        EXPECT_EQ(a.value().nodes.at(0).meshes, std::vector<int>{0});
    }
}

TEST(PlyImport, APointCloudTakesItsRadiusPropertyAndDropsItsNormals) {
    const std::string props = XYZ + "property float nx\nproperty float ny\nproperty float nz\n" +
                              "property uchar red\nproperty uchar green\nproperty uchar blue\n" +
                              "property float radius\n";
    const std::string rows =
        "0 0 0 0 0 1 255 0 0 0.5\n3 0 0 0 0 1 0 255 0 0.25\n"
        "3 4 0 0 0 1 0 0 255 1\n0 4 0 0 0 1 0 0 0 2\n";
    const std::string ascii = cloud_ascii(props, rows);
    // The same file in binary little-endian.
    std::string binary = ascii.substr(0, ascii.find("end_header\n") + 11);
    binary.replace(binary.find("ascii"), 5, "binary_little_endian");
    const float xyz[4][3] = {{0, 0, 0}, {3, 0, 0}, {3, 4, 0}, {0, 4, 0}};
    const float radii[4] = {0.5f, 0.25f, 1.0f, 2.0f};
    const uint8_t rgb[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {0, 0, 0}};
    const float normal[3] = {0, 0, 1};
    for (int i = 0; i < 4; ++i) {
        binary.append(reinterpret_cast<const char*>(xyz[i]), 12);
        binary.append(reinterpret_cast<const char*>(normal), 12);
        binary.append(reinterpret_cast<const char*>(rgb[i]), 3);
        binary.append(reinterpret_cast<const char*>(&radii[i]), 4);
    }
    for (const std::string& text : {ascii, binary}) {
        auto a = import_text(AssetFormat::Ply, text);
        ASSERT_TRUE(a.has_value()) << a.error().detail;
        const AssetMesh& m = a.value().meshes.at(0);
        EXPECT_EQ(m.kind, MeshKind::Points);
        EXPECT_EQ(m.radii, (std::vector<float>{0.5f, 0.25f, 1.0f, 2.0f}));
        EXPECT_EQ(m.positions[3], Vec3(0, 4, 0));
        EXPECT_TRUE(m.normals.empty());
        ASSERT_EQ(m.colors.size(), 4u);
        EXPECT_EQ(m.colors[1], Vec3(0, 1, 0));
        EXPECT_THAT(a.value().warnings, Contains(HasSubstr("normals and texture coordinates "
                                                           "dropped: points carry none")));
        EXPECT_THAT(a.value().warnings, Not(Contains(HasSubstr("without a radius property"))));
    }
}

TEST(PlyImport, APointCloudsBadRadiusIsRefusedNamingTheVertex) {
    const std::string props = XYZ + "property float radius\n";
    for (const auto& [bad, text] :
         {std::pair{"-1", "radius -1 "}, std::pair{"nan", "radius nan "},
          std::pair{"0", "radius 0 "}, std::pair{"1e300", "radius inf "}}) {
        const std::string rows = "0 0 0 1\n3 0 0 " + std::string(bad) + "\n3 4 0 1\n0 4 0 1\n";
        const protocol::Problem e = refusal(cloud_ascii(props, rows));
        EXPECT_EQ(e.type, protocol::ProblemType::InvalidAsset);
        EXPECT_EQ(e.element, "element vertex 1") << bad;
        EXPECT_THAT(e.detail, HasSubstr(text)) << e.detail;
        EXPECT_THAT(e.detail, HasSubstr("not a finite number > 0"));
    }
}

TEST(PlyImport, AMeshWithFacesIgnoresARadiusPropertyAndStaysTriangles) {
    std::string ply = QUAD_ASCII;
    ply.replace(ply.find("property uchar blue\n"), 20,
                "property uchar blue\nproperty float radius\n");
    for (const char* row : {"0 0 0 0 0 1 255 0 0", "1 0 0 0 0 1 0 255 0", "1 1 0 0 0 1 0 0 255",
                            "0 1 0 0 0 1 255 255 255", "2 2 2 0 0 1 0 0 0"})
        ply.replace(ply.find(row), std::strlen(row), std::string(row) + " -1");
    auto a = import_text(AssetFormat::Ply, ply);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    expect_quad_mesh(a.value());
    EXPECT_EQ(a.value().meshes[0].kind, MeshKind::Triangles);
    EXPECT_TRUE(a.value().meshes[0].radii.empty());
}

TEST(PlyImport, FacesThatAllHaveFewerThanThreeCornersAreRefused) {
    const std::string ply = cloud_ascii(XYZ, CORNER_ROWS + "2 0 1\n",
                                        "element face 1\nproperty list uchar int vertex_indices\n");
    const protocol::Problem e = refusal(ply);
    EXPECT_EQ(e.element, "element face");
    EXPECT_THAT(e.detail, HasSubstr("none of its 1 faces has 3 corners"));
}

TEST(PlyImport, NonFinitePositionsAreRefused) {
    std::string ply = QUAD_ASCII;
    ply.replace(ply.find("2 2 2 0 0 1"), 5, "2 nan 2");
    EXPECT_THAT(refusal(ply).detail, HasSubstr("not finite"));
}

}  // namespace
}  // namespace strata::assets::test
