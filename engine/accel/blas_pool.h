#pragma once
// BLASes shared between engines whose meshes are identical (the scenes of one server: ten users
// opening copies of one city hold one copy of each of its BLASes). The engines' devices are
// views of one SharedEmbree (embree_device.h), whose pool this is.
//
// Copy on write. A whole (not clustered, not compacted) BLAS a store builds on a pooled device is
// published here under a key of its content: positions, triangles, build options and scene
// flags. A store about to build a BLAS for a mesh of exactly that content (checked byte for byte
// against the published BLAS's own Embree buffers) holds the published one instead. A published
// BLAS never changes: a store whose mesh changes takes its record out first, and builds a copy
// of its own (the report says "unshared") when another engine holds it, or ever held it: that
// engine's TLAS may still reference it (a stale static-tier copy) and trace it at any time.
//
// Memory. A shared BLAS's bytes are counted once, by its owner, the view that built it; when the
// owner lets go while others hold it, its bytes move to one of them, so the view that frees it
// last is the one that counts it.

#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "engine/accel/refit_policy.h"
#include "engine/scene/types.h"

struct RTCSceneTy;
struct RTCGeometryTy;

namespace strata {

class EmbreeDevice;
struct MeshRecord;

/// One published BLAS.
struct SharedBlas {
    RTCSceneTy* scene = nullptr;        ///< each holder retains it once
    RTCGeometryTy* geometry = nullptr;  ///< its one triangle geometry (holders retain it too)
    uint64_t key = 0;
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    BuildOptions options;
    int scene_flags = 0;
    BuildBaseline baseline;  ///< as built
    int64_t bytes = 0;       ///< its Embree memory, counted by `owner`
    EmbreeDevice* owner = nullptr;
    std::vector<EmbreeDevice*> holders;  ///< one entry per holding record
    bool held_by_others = false;         ///< another engine than its builder held it once
};

/// What a pool holds now (GET /metrics: strata_shared_blas_*).
struct SharedBlasStats {
    uint64_t count = 0;   ///< BLASes published
    uint64_t holds = 0;   ///< holds by engines that did not build them: builds avoided now
    uint64_t bytes = 0;   ///< the published BLASes' Embree memory
};

/// The key a mesh's content is published under (a sample of it: matches are checked in full).
uint64_t shared_blas_key(const MeshRecord& mesh, int scene_flags);

class BlasPool {
public:
    /// A published BLAS of exactly `mesh`'s content, options and `scene_flags` that `view`
    /// does not hold yet, now held by `view` too (the caller retains its Embree objects); null
    /// when there is none.
    std::shared_ptr<SharedBlas> hold(const MeshRecord& mesh, int scene_flags, uint64_t key,
                                     EmbreeDevice& view);
    /// Publishes `blas`, built and held by its owner.
    void publish(const std::shared_ptr<SharedBlas>& blas);
    /// `view` lets go of `blas` (one of its holds). Its owner's bytes move to another holder
    /// when `view` owned it; the last holder takes it out of the pool. Returns the bytes `view`
    /// still counts for it: all of them when it was the last holder, else none.
    int64_t release(const std::shared_ptr<SharedBlas>& blas, EmbreeDevice& view);
    /// The bytes `view` counts for `blas`: all of them for its owner, none for the others.
    int64_t bytes_for(const SharedBlas& blas, const EmbreeDevice& view) const;
    /// Whether `blas` may not change in place for `view`: another view holds it or held it.
    bool frozen(const SharedBlas& blas, const EmbreeDevice& view) const;
    /// Takes `blas`, which only `view` ever held, out of the pool before its content changes;
    /// false (nothing done) when it is frozen.
    bool withdraw(const std::shared_ptr<SharedBlas>& blas, const EmbreeDevice& view);

    /// BLASes published now.
    std::size_t size() const;
    SharedBlasStats stats() const;

private:
    void erase(const SharedBlas& blas);

    mutable std::mutex m_mutex;
    std::unordered_multimap<uint64_t, std::shared_ptr<SharedBlas>> m_by_key;
};

}  // namespace strata
