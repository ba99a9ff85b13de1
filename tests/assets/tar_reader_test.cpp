// The tar reader (protocol/assets/tar_reader.h): archives GNU tar writes at test time in its
// three formats are read back byte for byte; every malformed archive is refused with a message
// that names the archive, the entry and what is wrong.

#include <cstring>
#include <map>

#include <gmock/gmock.h>

#include "protocol/assets/tar_reader.h"
#include "tests/assets/asset_test_util.h"
#include "tests/assets/tar_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::HasSubstr;

Imported<std::vector<TarEntry>> read(const std::string& archive, const TarLimits& limits = {}) {
    return read_tar(bytes_of(archive), "upload.tar", limits);
}

std::string text_of(const TarEntry& e) {
    return {reinterpret_cast<const char*>(e.bytes.data()), e.bytes.size()};
}

/// The refusal of `archive`, with the archive's name checked.
protocol::Problem refusal(const std::string& archive, const TarLimits& limits = {}) {
    auto r = read(archive, limits);
    EXPECT_FALSE(r.has_value());
    if (r.has_value()) return {};
    EXPECT_EQ(r.error().file, "upload.tar");
    return r.error();
}

class TarWrittenByTar : public ::testing::TestWithParam<const char*> {};

TEST_P(TarWrittenByTar, EveryRegularFileIsReadBackWithItsBytesAndDirectoriesAreSkipped) {
    ScratchDir dir;
    const std::string big(70000, 'x');  // several blocks, not a multiple of 512
    dir.write("model/cube.obj", "v 0 0 0\n");
    dir.write("model/tex/a.png", "png bytes");
    dir.write("model/empty.txt", "");
    dir.write("model/big.bin", big);
    const std::string archive = run_tar(dir.path(), GetParam(), "model");
    ASSERT_FALSE(archive.empty()) << "tar failed";
    auto r = read(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    std::map<std::string, std::string> files;
    for (const TarEntry& e : r.value()) files[e.path] = text_of(e);
    EXPECT_EQ(files.size(), 4u);
    EXPECT_EQ(files["model/cube.obj"], "v 0 0 0\n");
    EXPECT_EQ(files["model/tex/a.png"], "png bytes");
    EXPECT_EQ(files["model/empty.txt"], "");
    EXPECT_EQ(files["model/big.bin"], big);
}

TEST_P(TarWrittenByTar, LongNamesAreReadWhole) {
    ScratchDir dir;
    // 180 bytes: past ustar's 100-byte name field, inside its 155 + 100 with the prefix.
    const std::string long_dir = std::string(120, 'd');
    const std::string name = long_dir + "/" + std::string(59, 'f') + ".png";
    dir.write(name, "long");
    const std::string archive = run_tar(dir.path(), GetParam(), "'" + name + "'");
    ASSERT_FALSE(archive.empty()) << "tar failed";
    auto r = read(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    ASSERT_EQ(r.value().size(), 1u);
    EXPECT_EQ(r.value()[0].path, name);
    EXPECT_EQ(text_of(r.value()[0]), "long");
}

INSTANTIATE_TEST_SUITE_P(Formats, TarWrittenByTar,
                         ::testing::Values("--format=gnu", "--format=ustar", "--format=pax"));

TEST(TarReader, DotSlashNamesAreNormalised) {
    ScratchDir dir;
    dir.write("a/b.png", "b");
    const std::string archive = run_tar(dir.path(), "", "./a");
    ASSERT_FALSE(archive.empty());
    auto r = read(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    ASSERT_EQ(r.value().size(), 1u);
    EXPECT_EQ(r.value()[0].path, "a/b.png");
    auto crafted = read(tar_file(".//x/./y.obj", "y") + tar_end());
    ASSERT_TRUE(crafted.has_value()) << crafted.error().detail;
    EXPECT_EQ(crafted.value()[0].path, "x/y.obj");
}

TEST(TarReader, AnEmptyArchiveHoldsNoFiles) {
    auto r = read(tar_end());
    ASSERT_TRUE(r.has_value());
    EXPECT_TRUE(r.value().empty());
}

TEST(TarReader, ABadHeaderChecksumIsRefused) {
    std::string archive = tar_file("a.obj", "v 0 0 0\n") + tar_end();
    archive[0] = 'b';  // the name changes, the stored checksum does not
    const protocol::Problem e = refusal(archive);
    EXPECT_EQ(e.element, "header at byte 0");
    EXPECT_THAT(e.detail, HasSubstr("checksum mismatch"));
}

TEST(TarReader, BytesThatAreNotTarAreRefused) {
    const protocol::Problem e = refusal(std::string(2048, 'v'));
    EXPECT_THAT(e.detail, HasSubstr("checksum"));
}

TEST(TarReader, ATruncatedArchiveIsRefused) {
    const std::string whole = tar_file("a.obj", std::string(1000, 'v')) + tar_end();
    // Inside the data, inside the first header, and just before the end-of-archive block.
    EXPECT_THAT(refusal(whole.substr(0, 700)).detail, HasSubstr("truncated"));
    EXPECT_THAT(refusal(whole.substr(0, 300)).detail, HasSubstr("inside a header"));
    const protocol::Problem no_end = refusal(whole.substr(0, 512 + 1024));
    EXPECT_THAT(no_end.detail, HasSubstr("without its end-of-archive block"));
}

TEST(TarReader, ASizePastTheEndOfTheBodyIsRefused) {
    std::string archive = tar_header("a.obj", 1ull << 32) + tar_padded("v") + tar_end();
    const protocol::Problem e = refusal(archive);
    EXPECT_EQ(e.element, "entry 'a.obj'");
    EXPECT_THAT(e.detail, HasSubstr("runs past the end of the archive"));
}

TEST(TarReader, ASizeThatIsNotOctalIsRefused) {
    std::string archive = tar_file("a.obj", "v") + tar_end();
    std::memcpy(archive.data() + 124, "0000000009 ", 11);
    tar_fix_checksum(archive, 0);
    EXPECT_THAT(refusal(archive).detail, HasSubstr("size field is not an octal number"));
}

TEST(TarReader, DotDotAndAbsolutePathsAreRefused) {
    const protocol::Problem up = refusal(tar_file("model/../../etc/passwd", "x") + tar_end());
    EXPECT_EQ(up.element, "entry 'model/../../etc/passwd'");
    EXPECT_THAT(up.detail, HasSubstr("'..'"));
    EXPECT_THAT(refusal(tar_file("a/..", "x") + tar_end()).detail, HasSubstr("'..'"));
    const protocol::Problem abs = refusal(tar_file("/etc/passwd", "x") + tar_end());
    EXPECT_EQ(abs.element, "entry '/etc/passwd'");
    EXPECT_THAT(abs.detail, HasSubstr("absolute"));
}

TEST(TarReader, ASymlinkWrittenByTarIsRefusedNamingItsTarget) {
    ScratchDir dir;
    dir.write("m/cube.obj", "v 0 0 0\n");
    std::filesystem::create_symlink("/etc/passwd", dir.path() / "m" / "cube.mtl");
    const std::string archive = run_tar(dir.path(), "", "m");
    ASSERT_FALSE(archive.empty());
    const protocol::Problem e = refusal(archive);
    EXPECT_EQ(e.type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(e.element, "entry 'm/cube.mtl'");
    EXPECT_THAT(e.detail, HasSubstr("symbolic link to '/etc/passwd'"));
}

TEST(TarReader, HardLinksDevicesAndFifosAreRefused) {
    EXPECT_THAT(refusal(tar_header("b.obj", 0, '1', "a.obj") + tar_end()).detail,
                HasSubstr("hard link to 'a.obj'"));
    EXPECT_THAT(refusal(tar_header("null", 0, '3') + tar_end()).detail, HasSubstr("device file"));
    EXPECT_THAT(refusal(tar_header("pipe", 0, '6') + tar_end()).detail, HasSubstr("FIFO"));
    EXPECT_THAT(refusal(tar_header("odd", 0, 'Z') + tar_end()).detail, HasSubstr("entry type 'Z'"));
}

TEST(TarReader, TwoEntriesWithTheSameNameAreRefused) {
    const protocol::Problem e =
        refusal(tar_file("a/b.png", "1") + tar_file("./a//b.png", "2") + tar_end());
    EXPECT_EQ(e.element, "entry 'a/b.png'");
    EXPECT_THAT(e.detail, HasSubstr("appears twice"));
}

TEST(TarReader, EntryCountAndTotalSizeAreBounded) {
    std::string many;
    for (int i = 0; i < 5; ++i) many += tar_file("f" + std::to_string(i), "x");
    many += tar_end();
    TarLimits limits;
    limits.max_entries = 4;
    const protocol::Problem count = refusal(many, limits);
    EXPECT_EQ(count.type, protocol::ProblemType::TooLarge);
    EXPECT_THAT(count.detail, HasSubstr("more than 4 entries"));
    limits = {};
    limits.max_total_bytes = 3;
    const protocol::Problem bytes = refusal(many, limits);
    EXPECT_EQ(bytes.type, protocol::ProblemType::TooLarge);
    EXPECT_EQ(bytes.element, "entry 'f3'");
}

TEST(TarReader, ALongNameWithNoEntryAfterItIsRefused) {
    const std::string name(150, 'n');
    const std::string archive =
        tar_header("././@LongLink", name.size() + 1, 'L') + tar_padded(name + '\0') + tar_end();
    EXPECT_THAT(refusal(archive).detail, HasSubstr("with no entry after it"));
}

TEST(TarReader, AMalformedPaxHeaderIsRefused) {
    const std::string records = "99 path=a.obj\n";  // its length is not 99
    const protocol::Problem e =
        refusal(tar_header("pax", records.size(), 'x') + tar_padded(records) + tar_end());
    EXPECT_THAT(e.detail, HasSubstr("malformed pax"));
}

TEST(TarReader, NamesInMessagesArePrintable) {
    const protocol::Problem e = refusal(tar_file("/\x01\xff.obj", "x") + tar_end());
    EXPECT_EQ(e.element, "entry '/??.obj'");
}

}  // namespace
}  // namespace strata::assets::test
