#pragma once
// The top level, behind an interface so its strategy can be replaced. The commit tells a strategy
// which instances changed (TlasDelta) and asks for an update, or for a full rebuild; launches
// trace through it. EmbreeTlas keeps one Embree instance geometry per instance slot; a
// partitioned strategy can later rebuild only the parts that changed.

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/accel/ray.h"
#include "engine/core/handle.h"
#include "engine/core/result.h"
#include "engine/scene/types.h"

namespace strata {

class Scene;
class BlasStore;
class EmbreeDevice;

/// Instances to revisit in an update.
struct TlasDelta {
    /// Added, removed, moved, hidden or re-masked instances (removed ones by stale handle).
    std::vector<InstanceHandle> changed;
    /// Live instances whose mesh's BLAS was rebuilt or refit: their bounds changed.
    std::vector<InstanceHandle> blas_changed;

    bool empty() const { return changed.empty() && blas_changed.empty(); }
};

class TlasStrategy {
public:
    virtual ~TlasStrategy() = default;

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

    /// Closest hit for one ray (inst_id = instance slot).
    virtual void intersect1(RayHit1& ray, bool coherent) const = 0;
    /// Closest hits for the active lanes of a packet.
    virtual void intersect16(const ValidMask16& valid, RayHit16& rays, bool coherent) const = 0;
    /// Any hit for a packet of shadow rays: tfar becomes -inf on a hit.
    virtual void occluded16(const ValidMask16& valid, Ray16& rays) const = 0;
};

/// The Embree top-level scene over instance geometries attached by slot id.
std::unique_ptr<TlasStrategy> make_embree_tlas(EmbreeDevice& device, BuildPreference prefer,
                                               bool watertight);

}  // namespace strata
