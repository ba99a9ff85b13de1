// The importers' sandbox (protocol/assets/sandbox.h) with real child processes: a result comes
// back whole; a child that crashes, hangs, spins, allocates too much, is killed mid-parse or
// makes a forbidden system call is a 422 naming the file, and this process goes on; the result's
// bytes are checked as untrusted.

#include <atomic>
#include <csignal>
#include <cstdlib>
#include <thread>

#include <fcntl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gmock/gmock.h>

#include "protocol/assets/sandbox.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets {
namespace {

using ::testing::HasSubstr;
using test::bytes_of;
using test::read_file;

SandboxLimits fast(uint32_t deadline_ms = 5000) {
    SandboxLimits l;
    l.deadline_ms = deadline_ms;
    l.cpu_seconds = 5;
    l.memory_mb = 256;
    return l;
}

/// The detail of a refusal, having checked it is a 422 invalid-asset naming `file`.
std::string refusal(const Imported<ImportOutcome>& r, const std::string& file = "m.obj") {
    EXPECT_FALSE(r.has_value());
    if (r.has_value()) return "";
    EXPECT_EQ(r.error().type, protocol::ProblemType::InvalidAsset) << r.error().detail;
    EXPECT_EQ(r.error().file, file);
    EXPECT_THAT(r.error().detail, HasSubstr(file + ": "));
    return r.error().detail;
}

ImportOutcome sample_outcome() {
    ImportOutcome o;
    o.format = AssetFormat::Gltf;
    o.model = "dir/m.gltf";
    AssetMesh m;
    m.name = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {0, 1}};
    m.material = 0;
    o.asset.meshes.push_back(m);
    AssetMaterial mat;
    mat.name = "red";
    mat.material.base_color = {0.9f, 0.1f, 0.1f};
    mat.material.roughness = 0.25f;
    mat.material.base_color_sampler = {TextureWrap::Mirror, TextureFilter::Nearest};
    mat.textures[0] = 0;
    o.asset.materials.push_back(mat);
    o.asset.textures.push_back({"tex", "image/png", {1, 2, 3, 0, 255}, "t.png"});
    AssetNode root;
    root.name = "root";
    root.local = Affine::translation({1, 2, 3});
    AssetNode leaf;
    leaf.parent = 0;
    leaf.meshes = {0};
    o.asset.nodes = {root, leaf};
    o.asset.warnings = {"animations: 2 left out"};
    return o;
}

TEST(Sandbox, AnImportersResultComesBackWhole) {
    const ImportOutcome sent = sample_outcome();
    auto r = run_sandboxed([&]() -> Imported<ImportOutcome> { return sent; }, "m.gltf", fast());
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    const ImportOutcome& got = r.value();
    EXPECT_EQ(got.format, AssetFormat::Gltf);
    EXPECT_EQ(got.model, sent.model);
    ASSERT_EQ(got.asset.meshes.size(), 1u);
    EXPECT_EQ(got.asset.meshes[0].positions, sent.asset.meshes[0].positions);
    EXPECT_EQ(got.asset.meshes[0].triangles, sent.asset.meshes[0].triangles);
    EXPECT_EQ(got.asset.meshes[0].normals, sent.asset.meshes[0].normals);
    EXPECT_EQ(got.asset.meshes[0].uvs, sent.asset.meshes[0].uvs);
    EXPECT_EQ(got.asset.meshes[0].material, 0);
    EXPECT_EQ(got.asset.materials[0].material, sent.asset.materials[0].material);
    EXPECT_EQ(got.asset.materials[0].name, "red");
    EXPECT_EQ(got.asset.textures[0].bytes, sent.asset.textures[0].bytes);
    EXPECT_EQ(got.asset.textures[0].uri, "t.png");
    EXPECT_EQ(got.asset.nodes[0].local, sent.asset.nodes[0].local);
    EXPECT_EQ(got.asset.nodes[1].parent, 0);
    EXPECT_EQ(got.asset.nodes[1].meshes, std::vector<int>{0});
    EXPECT_EQ(got.asset.warnings, sent.asset.warnings);
}

TEST(Sandbox, AnImportersRefusalComesBackWithItsFileAndElement) {
    auto r = run_sandboxed(
        []() -> Imported<ImportOutcome> {
            return ErrorSink("bad.ply").invalid("header", "no vertex element");
        },
        "bad.ply", fast());
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(r.error().file, "bad.ply");
    EXPECT_EQ(r.error().element, "header");
    EXPECT_EQ(r.error().detail, "bad.ply: header: no vertex element");
}

TEST(Sandbox, ARealImportRunsInTheChild) {
    const std::string bunny = read_file(STRATA_MODELS_DIR "/stanford-bunny.obj");
    ASSERT_FALSE(bunny.empty());
    auto r = run_sandboxed(
        [&]() -> Imported<ImportOutcome> {
            auto a = import_asset(AssetFormat::Obj, bytes_of(bunny), "bunny.obj", {});
            if (!a) return Unexpected(a.error());
            return ImportOutcome{std::move(a.value()), AssetFormat::Obj, std::nullopt};
        },
        "bunny.obj", fast());
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    EXPECT_EQ(r.value().asset.triangle_count(), 69451u);
}

TEST(Sandbox, ACrashingImporterIsA422AndThisProcessGoesOn) {
    const std::string why = refusal(run_sandboxed(
        []() -> Imported<ImportOutcome> {
            std::raise(SIGSEGV);
            return ImportOutcome{};
        },
        "m.obj", fast()));
    EXPECT_THAT(why, HasSubstr("crashed (SIGSEGV)"));
    EXPECT_THAT(why, HasSubstr("nothing was imported"));
    EXPECT_THAT(refusal(run_sandboxed(
                    []() -> Imported<ImportOutcome> {
                        std::abort();
                    },
                    "m.obj", fast())),
                HasSubstr("crashed (SIGABRT)"));
}

TEST(Sandbox, AFileThatKillsAssimpItselfIsA422) {
    // Found by assimp_import_fuzzer: a mutated COB file on which Debian's assimp 5.2 throws
    // through noexcept code, so std::terminate aborts whatever process parses it.
    const std::string cob = read_file(STRATA_ASSET_TEST_DATA_DIR "/assimp-terminates.cob");
    ASSERT_FALSE(cob.empty());
    EXPECT_THAT(refusal(run_sandboxed(
                            [&]() -> Imported<ImportOutcome> {
                                auto a = import_asset(AssetFormat::Cob, bytes_of(cob), "m.cob", {});
                                if (!a) return Unexpected(a.error());
                                return ImportOutcome{std::move(a.value()), AssetFormat::Cob,
                                                     std::nullopt};
                            },
                            "m.cob", fast()),
                        "m.cob"),
                HasSubstr("crashed (SIGABRT)"));
}

TEST(Sandbox, AHangingImporterIsStoppedAtTheDeadline) {
    const auto start = std::chrono::steady_clock::now();
    const std::string why = refusal(run_sandboxed(
        []() -> Imported<ImportOutcome> {
            for (std::atomic<int> n{0};;) n.fetch_add(1, std::memory_order_relaxed);
        },
        "m.obj", fast(300)));
    EXPECT_THAT(why, HasSubstr("ran past its deadline of 300 ms"));
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(4));
}

TEST(Sandbox, AnImporterOverItsCpuTimeIsStopped) {
    SandboxLimits l = fast(20000);
    l.cpu_seconds = 1;
    EXPECT_THAT(refusal(run_sandboxed(
                    []() -> Imported<ImportOutcome> {
                        for (std::atomic<int> n{0};;) n.fetch_add(1, std::memory_order_relaxed);
                    },
                    "m.obj", l)),
                HasSubstr("more than its 1 s of CPU time"));
}

TEST(Sandbox, AnImporterOverItsMemoryIsRefused) {
    if (!SANDBOX_FILTERS) GTEST_SKIP() << "sanitizer build: its allocator reports the failure";
    SandboxLimits l = fast();
    l.memory_mb = 64;
    auto r = run_sandboxed(
        []() -> Imported<ImportOutcome> {
            std::vector<char> big(std::size_t(512) << 20, 1);
            ImportOutcome o;
            o.asset.warnings.push_back(std::to_string(big[12345]));
            return o;
        },
        "m.obj", l);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().type, protocol::ProblemType::TooLarge);
    EXPECT_THAT(r.error().detail, HasSubstr("m.obj: the importer needed more than its 64 MiB"));
}

TEST(Sandbox, AChildKilledMidParseIsA422NamingTheFile) {
    const std::string bunny = read_file(STRATA_MODELS_DIR "/stanford-bunny.obj");
    ASSERT_FALSE(bunny.empty());
    std::atomic<pid_t> child{0};
    SandboxLimits l = fast();
    l.on_start = [&](pid_t pid) {
        child = pid;
        kill(pid, SIGKILL);
    };
    const std::string why = refusal(
        run_sandboxed(
            [&]() -> Imported<ImportOutcome> {
                auto a = import_asset(AssetFormat::Obj, bytes_of(bunny), "bunny.obj", {});
                if (!a) return Unexpected(a.error());
                return ImportOutcome{std::move(a.value()), AssetFormat::Obj, std::nullopt};
            },
            "bunny.obj", l),
        "bunny.obj");
    EXPECT_THAT(why, HasSubstr("killed (SIGKILL)"));
    EXPECT_GT(child.load(), 0);
    EXPECT_NE(kill(child.load(), 0), 0) << "the child was not reaped";
}

TEST(Sandbox, TheChildCanOpenNoFileAndWriteToNoOtherDescriptor) {
    if (!SANDBOX_FILTERS) GTEST_SKIP() << "sanitizer build: no seccomp filter";
    auto opened = run_sandboxed(
        []() -> Imported<ImportOutcome> {
            const int fd = open("/etc/hostname", O_RDONLY);
            ImportOutcome o;
            o.asset.warnings.push_back(std::to_string(fd) + " " + std::to_string(errno));
            return o;
        },
        "m.obj", fast());
    ASSERT_TRUE(opened.has_value()) << opened.error().detail;
    EXPECT_EQ(opened.value().asset.warnings[0], "-1 " + std::to_string(EACCES));
    EXPECT_THAT(refusal(run_sandboxed(
                    []() -> Imported<ImportOutcome> {
                        (void)!socket(AF_INET, SOCK_STREAM, 0);
                        return ImportOutcome{};
                    },
                    "m.obj", fast())),
                HasSubstr("system call its sandbox forbids"));
    // A socket the server holds is closed in the child, and writing to it is refused.
    int pair[2];
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, pair), 0);
    const int server_side = pair[0];
    EXPECT_FALSE(run_sandboxed(
                     [&]() -> Imported<ImportOutcome> {
                         (void)!write(server_side, "leak", 4);
                         return ImportOutcome{};
                     },
                     "m.obj", fast())
                     .has_value());
    char got[8];
    EXPECT_EQ(recv(pair[1], got, sizeof got, MSG_DONTWAIT), -1);
    close(pair[0]);
    close(pair[1]);
}

TEST(AssetWire, EveryTruncationOrDamageIsAnErrorNotACrash) {
    const std::string bytes = encode_outcome(sample_outcome());
    ASSERT_TRUE(decode_outcome(bytes).has_value());
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(decode_outcome(std::string_view(bytes).substr(0, n)).has_value()) << n;
    EXPECT_FALSE(decode_outcome(bytes + "x").has_value());
    std::string huge = bytes;
    huge[13] = '\xff';  // the mesh count's high bytes (magic 4, kind 1, format 1, model flag...)
    auto r = decode_outcome(huge);
    EXPECT_FALSE(r.has_value() && r.value().has_value() &&
                 r.value().value().asset.meshes.size() > 1);
}

/// An outcome of a points mesh and a curve mesh (two linear strands), both coloured.
ImportOutcome points_and_curves_outcome() {
    ImportOutcome o;
    AssetMesh points;
    points.name = "pts";
    points.kind = MeshKind::Points;
    points.positions = {{0, 0, 0}, {1, 0, 0}};
    points.radii = {0.5f, 0.25f};
    points.colors = {{1, 0, 0}, {0, 1, 0}};
    AssetMesh curves;
    curves.kind = MeshKind::Curves;
    curves.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}};
    curves.radii = {0.1f, 0.1f, 0.2f, 0.2f, 0.2f};
    curves.strands = {2, 3};
    o.asset.meshes = {points, curves};
    AssetNode node;
    node.meshes = {0, 1};
    o.asset.nodes = {node};
    return o;
}

TEST(AssetWire, PointsAndCurvesComeBackWithTheirKindRadiiAndStrands) {
    const ImportOutcome sent = points_and_curves_outcome();
    const std::string bytes = encode_outcome(sent);
    auto r = decode_outcome(bytes);
    ASSERT_TRUE(r.has_value()) << r.error();
    ASSERT_TRUE(r.value().has_value());
    const Asset& got = r.value().value().asset;
    ASSERT_EQ(got.meshes.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(got.meshes[i].kind, sent.asset.meshes[i].kind);
        EXPECT_EQ(got.meshes[i].positions, sent.asset.meshes[i].positions);
        EXPECT_EQ(got.meshes[i].radii, sent.asset.meshes[i].radii);
        EXPECT_EQ(got.meshes[i].strands, sent.asset.meshes[i].strands);
        EXPECT_EQ(got.meshes[i].colors, sent.asset.meshes[i].colors);
    }
    EXPECT_TRUE(validate_asset(got, ErrorSink("m.ply")).has_value());
    // Every truncation fails cleanly, and so does a kind byte outside MeshKind: magic 4, kind 1,
    // format 1, no model 1, mesh count 8, the name "pts" 4 + 3, then the mesh's kind.
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(decode_outcome(std::string_view(bytes).substr(0, n)).has_value()) << n;
    ASSERT_EQ(bytes[22], char(MeshKind::Points));
    std::string bad = bytes;
    bad[22] = 3;
    auto damaged = decode_outcome(bad);
    ASSERT_FALSE(damaged.has_value());
    EXPECT_THAT(damaged.error(), HasSubstr("enum value 3 out of range"));
}

TEST(AssetWire, ADecodedPointsOrCurveMeshThatBreaksTheRulesFailsValidation) {
    const ErrorSink sink("m.ply");
    const auto problem = [&](auto&& damage) {
        ImportOutcome o = points_and_curves_outcome();
        damage(o.asset);
        auto r = decode_outcome(encode_outcome(o));
        EXPECT_TRUE(r.has_value() && r.value().has_value());
        auto valid = validate_asset(r.value().value().asset, sink);
        EXPECT_FALSE(valid.has_value());
        return valid.has_value() ? std::string() : valid.error().detail;
    };
    EXPECT_THAT(problem([](Asset& a) {
                    a.meshes[1].strands = {2, 2};
                }),
                HasSubstr("the strands hold 4 control vertices but the mesh has 5"));
    EXPECT_THAT(problem([](Asset& a) {
                    a.meshes[1].strands = {1, 4};
                }),
                HasSubstr("strand 0 has 1 control vertices"));
    EXPECT_THAT(problem([](Asset& a) { a.meshes[0].radii[1] = -1.0f; }),
                HasSubstr("radius 1 is not a finite number > 0"));
    EXPECT_THAT(problem([](Asset& a) { a.meshes[0].radii.pop_back(); }),
                HasSubstr("has 1 radii for 2 vertices"));
    EXPECT_THAT(problem([](Asset& a) {
                    a.meshes[0].triangles = {{0, 1, 1}};
                }),
                HasSubstr("is a points mesh: it takes no triangles"));
    EXPECT_THAT(problem([](Asset& a) { a.meshes[0].strands = {2}; }),
                HasSubstr("is a points mesh: strands are for curve meshes"));
    EXPECT_THAT(problem([](Asset& a) { a.meshes[1].normals.assign(5, Vec3(0, 0, 1)); }),
                HasSubstr("is a curve mesh: normals, texture coordinates and tangents are for "
                          "triangle meshes"));
    EXPECT_THAT(problem([](Asset& a) {
                    a.meshes[0].kind = MeshKind::Triangles;
                    a.meshes[0].triangles = {{0, 1, 1}};
                }),
                HasSubstr("radii and strands are for points and curves"));
}

TEST(Sandbox, TurnedOffItRunsTheImporterInThisProcess) {
    SandboxLimits l;
    l.enabled = false;
    const pid_t self = getpid();
    auto r = run_sandboxed(
        [&]() -> Imported<ImportOutcome> {
            ImportOutcome o;
            o.asset.warnings.push_back(std::to_string(getpid() == self));
            return o;
        },
        "m.obj", l);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r.value().asset.warnings, std::vector<std::string>{"1"});
}

}  // namespace
}  // namespace strata::assets
