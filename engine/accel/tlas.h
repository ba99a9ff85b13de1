#pragma once
// The top level, behind an interface so its strategy can be replaced. The commit tells a strategy
// which instances changed (TlasDelta) and asks for an update, or for a full rebuild; launches
// trace through it. Two strategies:
//   - embree: one Embree instance scene over every instance; any change rebuilds its whole BVH
//     (O(instances) per commit). Kept as the reference.
//   - incremental (default): a static tier rebuilt rarely (in the background) and a small dynamic
//     tier that holds what changed since, so a commit costs O(changed instances); see
//     incremental_tlas.cpp.

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "engine/accel/ray.h"
#include "engine/core/handle.h"
#include "engine/core/result.h"
#include "engine/scene/types.h"

struct RTCSceneTy;

namespace strata {

class Scene;
class BlasStore;
class EmbreeDevice;
class LodScenes;
struct InstanceRecord;

/// Instances to revisit in an update.
struct TlasDelta {
    /// Added, removed, moved, hidden or re-masked instances (removed ones by stale handle).
    std::vector<InstanceHandle> changed;
    /// Live instances whose mesh's BLAS was rebuilt or refit: their bounds changed.
    std::vector<InstanceHandle> blas_changed;

    bool empty() const { return changed.empty() && blas_changed.empty(); }
};

/// What a trace applies besides the rays: a hit test, and the eye level-of-detail groups
/// measure from (TlasStrategy::intersect1).
struct TraceOptions {
    const HitTest* test = nullptr;
    const Vec3* lod_eye = nullptr;
};

/// Which TLAS strategy an engine uses.
enum class TlasKind : uint8_t { Incremental, Embree };

/// Wire and command-line name of a strategy: "incremental" or "embree".
const char* tlas_kind_name(TlasKind k);
/// The strategy named `name`, if any.
std::optional<TlasKind> parse_tlas_kind(std::string_view name);

/// When the incremental strategy gives up on its dynamic tier and rebuilds the static one in the
/// commit itself (see protocol/README.md, "What an instance edit costs").
struct TlasPolicy {
    /// Scenes with fewer instances than this keep no dynamic tier: every update rebuilds the
    /// whole instance BVH, which takes well under a millisecond at this size and traces fastest.
    uint32_t min_instances = 1024;
    /// The commit rebuilds the static tier when the dynamic tier would hold more than this
    /// fraction of the instances (each commit rebuilds the dynamic tier, so it must stay small).
    double max_dynamic_fraction = 0.10;
    /// Rebuild the static tier with the edits applied in the background and swap it in at the
    /// next commit after it finishes. Off: the dynamic tier drains only through the fallback.
    bool background_merge = true;
    /// A static tier of at least this many instances is built as an instance array
    /// (instance_array.h: 64 bytes an instance instead of an Embree geometry, and faster rays
    /// past tens of thousands of instances), unless an instance has motion keys; smaller ones
    /// are Embree instance geometries, which trace faster there (tests/bench/NOTES.md).
    uint32_t array_min_instances = 65536;
    /// A dynamic tier of instance geometries (while one of its instances has motion keys;
    /// otherwise it is an instance array, dynamic_tier.h) of at most this many instances is
    /// built at MEDIUM quality (one SAH build), one of more than twice as many at LOW (Embree's
    /// two-level builder), and one in between keeps the quality it has. MEDIUM is the faster
    /// build of a few hundred instances and LOW of thousands on many threads; each rebuilds every
    /// instance of the tier at every update (tests/bench/NOTES.md). 0: always LOW.
    uint32_t dynamic_medium_max = 1024;
};

/// What the TLAS looks like after a commit, for the rebuild report.
struct TlasTiers {
    const char* strategy = "embree";
    uint64_t static_instances = 0;   ///< in the static tier (embree: every visible instance)
    uint64_t dynamic_instances = 0;  ///< in the dynamic tier (edited since the static build)
    uint64_t stale_copies = 0;       ///< static-tier copies of edited instances, skipped by rays
    /// Geometry slots of the dynamic tier's Embree scene, which each update walks: at least
    /// dynamic_instances, at most a bounded multiple of it once the tier has drained.
    uint64_t dynamic_slots = 0;
    /// The build quality of the dynamic tier's last commit (TlasPolicy::dynamic_medium_max):
    /// "medium" or "low"; "" for a strategy without one.
    const char* dynamic_quality = "";
    bool dynamic_array = false;  ///< the dynamic tier is an instance array (dynamic_tier.h)
    bool static_array = false;  ///< the static tier is an instance array (TlasPolicy)
    /// Why this commit rebuilt the static tier itself: "" (it did not), "requested",
    /// "small_scene", "dynamic_tier_full" or "first_build".
    const char* static_rebuild = "";
    bool merge_swapped = false;    ///< a background merge was swapped in at this commit
    double merge_build_ms = 0.0;   ///< its background build time (wall)
    bool merge_cancelled = false;  ///< a running merge was abandoned at this commit
    bool merge_running = false;    ///< a merge is building in the background after the commit
};

class TlasStrategy {
public:
    TlasStrategy();
    virtual ~TlasStrategy();

    /// Short name for logs and reports.
    virtual const char* name() const = 0;
    /// True when the TLAS holds something for exactly this instance handle.
    virtual bool holds(InstanceHandle h) const = 0;
    /// Number of instances the TLAS holds.
    virtual uint64_t instance_count() const = 0;

    /// Brings the TLAS in line with the scene for the instances in `delta`.
    virtual Status update(const Scene& scene, const BlasStore& blas, const TlasDelta& delta) = 0;
    /// Discards the TLAS and builds it again from every instance of the scene.
    virtual Status rebuild(const Scene& scene, const BlasStore& blas) = 0;
    /// Called by a commit before it rebuilds or refits BLASes that instances may reference, so
    /// no background work reads them while they change.
    virtual void before_blas_changes() {}
    /// Called by a commit that has no TLAS work: a strategy may finish background work here
    /// (commits and launches are serialised, so no launch is tracing). Returns whether it did.
    virtual bool maintain() { return false; }
    /// The tiers as they are now; `tiers_report()` also clears the per-commit flags.
    virtual TlasTiers tiers_report() { return {}; }
    /// Waits for background work to finish (tests and benchmarks).
    virtual void wait_for_background() {}

    /// Closest hit for one ray: inst_id is the instance slot, prim_id the triangle in the
    /// mesh's own numbering (also for clustered BLASes), geom_id 0. Hits `test` refuses are
    /// passed through. Level-of-detail groups choose their level by their distance from
    /// `lod_eye` (engine/scene/lod.h): the launch's camera, so that every ray of a frame sees
    /// the level the camera sees; null: from the ray's own origin.
    void intersect1(RayHit1& ray, bool coherent, const HitTest* test = nullptr,
                    const Vec3* lod_eye = nullptr) const {
        trace1(ray, coherent, {test, lod_eye});
        if (m_blas && blas_clustered()) to_mesh_triangles(ray);
    }
    /// Closest hits for the active lanes of a packet, numbered as intersect1's.
    void intersect16(const ValidMask16& valid, RayHit16& rays, bool coherent,
                     const HitTest* test = nullptr, const Vec3* lod_eye = nullptr) const {
        trace16(valid, rays, coherent, {test, lod_eye});
        if (m_blas && blas_clustered()) to_mesh_triangles(valid, rays);
    }
    /// Any hit for a packet of shadow rays: tfar becomes -inf on a hit.
    void occluded16(const ValidMask16& valid, Ray16& rays, const HitTest* test = nullptr,
                    const Vec3* lod_eye = nullptr) const {
        trace_occluded16(valid, rays, {test, lod_eye});
    }

    /// The mesh's own triangle index of a hit on the instance in `slot` at BLAS geometry `geom`,
    /// primitive `prim` (what HitTest::keep is told).
    uint32_t mesh_triangle(uint32_t slot, uint32_t geom, uint32_t prim) const;

protected:
    virtual void trace1(RayHit1& ray, bool coherent, const TraceOptions& options) const = 0;
    virtual void trace16(const ValidMask16& valid, RayHit16& rays, bool coherent,
                         const TraceOptions& options) const = 0;
    virtual void trace_occluded16(const ValidMask16& valid, Ray16& rays,
                                  const TraceOptions& options) const = 0;

    /// Records which mesh's BLAS the instance in `slot` references (every strategy calls it
    /// when it points an instance at a BLAS), so hits on clustered BLASes can be renumbered.
    void note_blas(const BlasStore& blas, uint32_t slot, uint32_t mesh_slot) {
        m_blas = &blas;
        if (slot >= m_instance_mesh.size()) m_instance_mesh.resize(slot + 1, 0);
        m_instance_mesh[slot] = mesh_slot;
    }
    /// The scene the geometry of instance `r` in `slot` instances: its mesh's BLAS, or under a
    /// level-of-detail group that BLAS's wrapper (lod_scenes.h). Notes the BLAS (note_blas).
    RTCSceneTy* instanced_scene(EmbreeDevice& device, const BlasStore& blas, uint32_t slot,
                                const InstanceRecord& r);
    /// Called at the start of each update and rebuild: lets wrappers drop removed BLASes.
    void sweep_lod(const BlasStore& blas);

private:
    bool blas_clustered() const;
    void to_mesh_triangles(RayHit1& ray) const;
    void to_mesh_triangles(const ValidMask16& valid, RayHit16& rays) const;

    const BlasStore* m_blas = nullptr;
    std::vector<uint32_t> m_instance_mesh;  ///< by instance slot: the mesh slot of its BLAS
    std::unique_ptr<LodScenes> m_lod;
};

/// The Embree top-level scene over instance geometries attached by slot id.
std::unique_ptr<TlasStrategy> make_embree_tlas(EmbreeDevice& device, BuildPreference prefer,
                                               bool watertight);

/// The two-tier incremental TLAS (incremental_tlas.cpp). Both strategies trace BLASes built with
/// Embree's context-filter flag (BlasStore's `context_filter`): the incremental one skips stale
/// copies through it, and both apply HitTests through it.
std::unique_ptr<TlasStrategy> make_incremental_tlas(EmbreeDevice& device, BuildPreference prefer,
                                                    bool watertight, const TlasPolicy& policy);

}  // namespace strata
