#pragma once
// A generator of random, valid edit batches mixing every edit kind, with removals and re-adds,
// on scenes where many instances share few meshes. It keeps its own model of what exists so
// every batch it makes is valid.

#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "engine/scene/edits.h"

namespace strata::test {

class RandomEdits {
public:
    explicit RandomEdits(uint64_t seed) : m_rng(seed) {}

    /// A starting scene: `meshes` meshes shared by `instances` instances.
    EditBatch initial_batch(int meshes, int instances);

    /// A batch of 1..max_edits random edits.
    EditBatch next_batch(int max_edits);

    /// A random ray mask for a launch (usually all bits).
    uint32_t ray_mask();

private:
    struct MeshInfo {
        uint32_t vertices = 0;
        int instances = 0;
        MeshKind kind = MeshKind::Triangles;
        CurveBasis basis = CurveBasis::Linear;
        uint32_t keys = 0;  ///< motion positions per vertex (vertex keys after the first)
    };
    /// `k` vertex keys per vertex near each of `around`, vertex after vertex.
    std::vector<Vec3> random_keys(const std::vector<Vec3>& around, uint32_t k);
    /// Sometimes vertex keys for a new mesh `e` (1 to 3 after its positions).
    void maybe_keys(AddMesh& e);
    /// Points or curves: positions, radii and (curves) strands, in `e`.
    void random_points(AddMesh& e);
    void random_curves(AddMesh& e, CurveBasis basis);
    /// An update of one of `instances`: some of its fields, motion keys among them.
    UpdateInstance random_update_instance(const std::vector<std::string>& instances);
    /// A camera somewhere around the scene, sometimes with its shutter open.
    SetCamera random_camera();
    /// A new shape for mesh `id` of its kind, as a topology change.
    ReplaceMeshTopology random_topology(const std::string& id);

    void add_edit(EditBatch& b);
    void add_mesh(EditBatch& b);
    void add_instance(EditBatch& b, const std::vector<std::string>& meshes);
    AddMesh random_mesh(const std::string& id);
    Affine random_transform();
    std::string pick(const std::vector<std::string>& v);
    std::vector<std::string> mesh_ids() const;
    std::vector<std::string> instance_ids() const;
    std::string fresh(const char* prefix);
    float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(m_rng); }
    int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(m_rng); }
    bool chance(double p) { return std::bernoulli_distribution(p)(m_rng); }
    Vec3 colour() { return {uniform(0, 1), uniform(0, 1), uniform(0, 1)}; }

    std::mt19937_64 m_rng;
    std::map<std::string, MeshInfo> m_meshes;
    std::map<std::string, std::string> m_instances;  ///< instance -> mesh
    std::vector<std::string> m_materials;
    std::map<std::string, std::vector<Vec3>> m_positions;  ///< current positions per mesh
    int m_counter = 0;
};

}  // namespace strata::test
