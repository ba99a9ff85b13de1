#pragma once
// Level-of-detail choice while tracing (engine/scene/lod.h has the rule). An instance under an
// LOD group instances, in place of its mesh's BLAS, a wrapper scene holding one Embree user
// geometry whose box is the BLAS's. A ray that enters the wrapper is already in the instance's
// object space (Embree applied the instance transform); the wrapper's callbacks test the
// instance's bands from the eye the intersect context carries (FilterContext::lod_eye; without
// one, the ray's origin taken back to world space) and, when they hold, trace the BLAS with the
// same intersect context, so the hit carries the instance's id and the mesh's own primitive, and
// the context's filter (stale copies, hit tests) applies as for any instance. A ray that fails
// the bands costs one box test. Nothing is rebuilt when the camera moves.

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/lod.h"
#include "engine/scene/types.h"

struct RTCSceneTy;

namespace strata {

class BlasStore;
class EmbreeDevice;
struct InstanceRecord;

class LodScenes {
public:
    explicit LodScenes(EmbreeDevice& device);
    ~LodScenes();
    LodScenes(const LodScenes&) = delete;
    LodScenes& operator=(const LodScenes&) = delete;

    /// The scene an instance geometry for `r` (instance slot `slot`) instances: its mesh's
    /// BLAS, or under an LOD group that BLAS's wrapper, brought in line with the BLAS; records
    /// what the wrapper's rays need to know of the instance. Commits only (not while tracing).
    RTCSceneTy* instanced_scene(const BlasStore& blas, uint32_t slot, const InstanceRecord& r);
    /// Lets go of the BLASes of removed meshes (a wrapper keeps its BLAS alive until then).
    void sweep(const BlasStore& blas);
    /// Whether the instance in `slot` is drawn for a ray whose eye is world point `eye`, or,
    /// when `eye` is null, the ray's own origin (`org` in the instance's object space, at ray
    /// time `time`).
    bool selects(uint32_t slot, const Vec3* eye, const Vec3& org, float time) const;

    /// A wrapper scene and what its callbacks read (lod_scenes.cpp).
    struct Wrapper;

private:
    /// What a wrapper's rays need of one instance.
    struct Instance {
        Affine world;
        std::vector<Affine> keys;  ///< world-space motion keys; empty: none
        MotionInterpolation interpolation = MotionInterpolation::Linear;
        LodBands bands;
    };

    Wrapper& wrapper(uint32_t mesh_slot);

    EmbreeDevice& m_device;
    std::unordered_map<uint32_t, std::unique_ptr<Wrapper>> m_wrappers;  ///< by mesh slot
    std::unordered_map<uint32_t, Instance> m_instances;                 ///< by instance slot
};

}  // namespace strata
