#pragma once
// Small builders shared by the engine tests.

#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"

namespace strata::test {

inline AddMesh mesh_edit(const std::string& id, MeshData data, BuildOptions build = {}) {
    return add_mesh_edit(id, std::move(data), build);
}

inline AddInstance instance_edit(const std::string& id, const std::string& mesh,
                                 Vec3 at = Vec3(0.0f)) {
    AddInstance e;
    e.id = id;
    e.mesh = mesh;
    e.transform = Affine::translation(at);
    return e;
}

inline Light point_light(Vec3 at, float intensity) {
    Light l;
    l.kind = LightKind::Point;
    l.position = at;
    l.intensity = intensity;
    return l;
}

/// Engine::create for the engine tests. STRATA_TEST_ARRAY_MIN_INSTANCES in the environment
/// overrides the TLAS policy's array_min_instances (CTest runs the suite again with 0: every
/// static tier an instance array).
inline Result<std::unique_ptr<Engine>> create_engine(EngineConfig config = {}) {
    if (const char* v = std::getenv("STRATA_TEST_ARRAY_MIN_INSTANCES"))
        config.accel.tlas_policy.array_min_instances = uint32_t(std::strtoul(v, nullptr, 10));
    return Engine::create(config);
}

/// Whether the suite runs with every static tier an instance array (create_engine).
inline bool arrays_forced() {
    const char* v = std::getenv("STRATA_TEST_ARRAY_MIN_INSTANCES");
    return v && std::strtoul(v, nullptr, 10) == 0;
}

inline std::unique_ptr<Engine> make_engine() {
    auto engine = create_engine();
    EXPECT_TRUE(engine.has_value()) << (engine.has_value() ? "" : engine.error().describe());
    return std::move(engine.value());
}

/// An engine with TLAS strategy `tlas`; null (a recorded failure) when it cannot be made.
inline std::unique_ptr<Engine> make_engine(TlasKind tlas) {
    EngineConfig config;
    config.accel.tlas = tlas;
    auto created = create_engine(config);
    if (!created.has_value()) {
        ADD_FAILURE() << created.error().describe();
        return nullptr;
    }
    return std::move(created.value());
}

/// Applies a batch that must succeed.
template <class... Edits>
uint64_t apply_ok(Engine& engine, Edits&&... edits) {
    EditBatch batch;
    (batch.edits.emplace_back(std::forward<Edits>(edits)), ...);
    auto r = engine.apply(std::move(batch));
    EXPECT_TRUE(r.has_value()) << (r.has_value() ? "" : r.error().describe());
    return r.has_value() ? r.value().version : 0;
}

inline RebuildReport commit_ok(Engine& engine) {
    auto r = engine.commit();
    EXPECT_TRUE(r.has_value()) << (r.has_value() ? "" : r.error().describe());
    return r.has_value() ? r.value() : RebuildReport{};
}

/// Names a test instantiated over both TLAS strategies after its strategy.
inline std::string strategy_name(const ::testing::TestParamInfo<TlasKind>& info) {
    return info.param == TlasKind::Incremental ? "incremental" : "embree";
}

/// Applies `edit` alone, expecting it refused with its error at `field`.
inline void expect_refused(Engine& engine, Edit edit, const std::string& field) {
    EditBatch b;
    b.edits.push_back(std::move(edit));
    auto r = engine.apply(std::move(b));
    ASSERT_FALSE(r.has_value()) << field;
    EXPECT_EQ(r.error().field, field) << r.error().describe();
}

inline std::vector<std::string> ids(const std::vector<MeshBuildEntry>& entries) {
    std::vector<std::string> out;
    for (const auto& e : entries) out.push_back(e.mesh);
    return out;
}

}  // namespace strata::test
