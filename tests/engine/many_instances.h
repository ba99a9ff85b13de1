#pragma once
// Scenes of thousands of instances of a few small meshes spread over a grid, and random batches
// that move, add, remove, hide, show and re-mask them (with the odd mesh wobble, which refits a
// BLAS) in the same batch: what the incremental TLAS's tiers, stale copies and merges see.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "engine/engine.h"

namespace strata::test {

class ManyInstances {
public:
    explicit ManyInstances(uint64_t seed) : m_rng(seed) {}

    /// Meshes, `instances` instances on a grid and a camera looking over them.
    EditBatch initial_batch(int instances);
    /// `edits` random instance edits (moves, adds, removes, hides, shows, masks), sometimes a
    /// mesh wobble.
    EditBatch mixed_batch(int edits, bool allow_mesh_edits = true);
    /// `count` moves of random live instances.
    EditBatch moves(int count);
    /// A random ray mask for a launch (usually all bits).
    uint32_t ray_mask() { return chance(0.75) ? 0xFFFFFFFFu : (chance(0.5) ? 0x1u : 0x2u); }
    std::size_t live() const { return m_live.size(); }
    /// Mask edits leave motion keys alone from now on (scenes that must stay without keys).
    void without_motion_keys() { m_keys = false; }

private:
    struct Live {
        std::string id;
        bool visible = true;
    };
    Affine placement(int cell);
    Affine random_placement() { return placement(integer(0, m_cells - 1)); }
    float uniform(float lo, float hi) {
        return std::uniform_real_distribution<float>(lo, hi)(m_rng);
    }
    int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(m_rng); }
    bool chance(double p) { return std::bernoulli_distribution(p)(m_rng); }

    std::mt19937_64 m_rng;
    std::vector<Live> m_live;
    std::vector<std::string> m_meshes;
    std::vector<std::vector<Vec3>> m_shapes;  ///< each mesh's first positions
    int m_cells = 1;
    int m_next = 0;
    bool m_keys = true;  ///< mask edits may set or clear motion keys
};

}  // namespace strata::test
