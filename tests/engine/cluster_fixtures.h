#pragma once
// Meshes and engines the clustered-BLAS tests share (cluster_blas_test.cpp,
// cluster_splice_test.cpp).

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "tests/engine/test_util.h"

namespace strata::test {

/// A bumpy grid whose triangles are listed in random order: the client's numbering is not the
/// clusters' order.
inline MeshData bumpy_grid(uint32_t nx, uint32_t nz, uint32_t seed) {
    MeshData m = make_plane(Vec3(8.0f, 0.0f, 8.0f), nx, nz);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> bump(-0.05f, 0.05f);
    for (Vec3& p : m.positions)
        p.y = 0.3f * std::sin(p.x * 1.7f) * std::cos(p.z * 1.3f) + bump(rng);
    std::shuffle(m.triangles.begin(), m.triangles.end(), rng);
    return m;
}

inline EngineConfig clustered_config(uint32_t min_triangles) {
    EngineConfig c;
    c.accel.clusters.min_triangles = min_triangles;
    c.accel.clusters.min_size = 16;
    c.accel.clusters.size_factor = 2.0;
    return c;
}

inline std::unique_ptr<Engine> make(const EngineConfig& config) {
    auto e = test::create_engine(config);
    EXPECT_TRUE(e.has_value());
    return std::move(e.value());
}

inline EditBatch batch_of(std::vector<Edit> edits) {
    EditBatch b;
    b.edits = std::move(edits);
    return b;
}

/// An engine (clusters from 1,024 triangles) holding mesh "g", a 100x100-quad bumpy grid
/// (101x101 vertices, 20,000 triangles), instanced once and committed.
struct GridScene {
    std::unique_ptr<Engine> engine;
    std::vector<Vec3> positions;  ///< the grid's vertices, as the engine holds them
    RebuildReport added;          ///< the first commit's report
};

inline GridScene committed_grid(uint32_t seed) {
    GridScene g;
    g.engine = make(clustered_config(1024));
    MeshData grid = bumpy_grid(100, 100, seed);
    g.positions = grid.positions;
    test::apply_ok(*g.engine, test::mesh_edit("g", std::move(grid)),
                   test::instance_edit("i", "g"));
    g.added = test::commit_ok(*g.engine);
    return g;
}

}  // namespace strata::test
