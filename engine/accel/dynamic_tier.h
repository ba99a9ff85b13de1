#pragma once
// The incremental TLAS's dynamic tier: an Embree scene over the instances edited since the
// static tier was built, rebuilt at every update, so its build is what an edit of one instance
// costs while a merge runs. Entry i of the tier is its primitive or geometry i, and rays that hit
// it report i as their instance id (the TLAS maps it to the slot).
//
// Two forms, chosen at each commit:
//   array       one user geometry over a table of entries (instance_array.h), built at LOW
//               quality. Embree builds a few hundred to a few thousand of these two to three
//               times faster than as many instance geometries, whose build pays per geometry.
//   geometries  one Embree instance geometry per entry, when an entry has motion keys (an
//               array holds none); quality by size (TlasPolicy::dynamic_medium_max).
// tests/bench/NOTES.md has both measured.

#include <array>
#include <cstdint>
#include <vector>

#include "engine/accel/instance_array.h"
#include "engine/accel/tlas_merge.h"
#include "engine/core/math.h"
#include "engine/scene/types.h"

struct RTCDeviceTy;
struct RTCGeometryTy;
struct RTCSceneTy;

namespace strata {

/// One instance of the dynamic tier, with the state a merge copies.
struct DynEntry {
    uint32_t slot = 0;
    RTCSceneTy* blas = nullptr;
    std::array<float, 12> transform{};
    std::vector<Affine> keys;  ///< world-space motion keys; empty: none
    MotionInterpolation interpolation = MotionInterpolation::Linear;
    uint32_t mask = 0;
    RTCGeometryTy* geometry = nullptr;  ///< its instance geometry (the geometries form only)
};

class DynamicTier {
public:
    /// `setup`'s flags are the scene's; `medium_max` is TlasPolicy::dynamic_medium_max.
    DynamicTier(RTCDeviceTy* device, TlasSceneSetup setup, uint32_t medium_max);
    ~DynamicTier();
    DynamicTier(const DynamicTier&) = delete;
    DynamicTier& operator=(const DynamicTier&) = delete;

    RTCSceneTy* scene() const { return m_scene; }
    const std::vector<DynEntry>& entries() const { return m_entries; }
    std::size_t size() const { return m_entries.size(); }
    bool empty() const { return m_entries.empty(); }
    /// Whether the scene needs a commit: an entry changed, or a drained scene of geometries
    /// should move to a fresh one.
    bool needs_commit() const { return m_dirty || sparse(); }

    /// Appends an entry for `slot` (set() gives it its instance) and returns its index.
    uint32_t add(uint32_t slot);
    /// Gives entry `id` its instance: `blas` at `transform` (3x4 row-major) or at motion keys
    /// `keys`, seen by rays whose mask shares a bit with `mask`.
    void set(uint32_t id, RTCSceneTy* blas, const std::array<float, 12>& transform,
             const std::vector<Affine>& keys, MotionInterpolation interpolation, uint32_t mask);
    /// Removes entry `id`; the last entry moves into its index (the caller renumbers its slot).
    void remove(uint32_t id);
    /// Entry `id`'s instance geometry, committed, for the static tier to attach: the caller
    /// holds the reference from here on. The tier is clear()ed afterwards.
    RTCGeometryTy* take_geometry(uint32_t id);
    /// Drops every entry.
    void clear();

    /// Commits the scene in the form its entries allow, at the quality for its size.
    void commit();

    bool is_array() const { return m_array; }
    /// "low" or "medium": the quality of the last commit.
    const char* quality_name() const;
    /// Geometry slots of the Embree scene (the array's primitives), which each commit walks.
    std::size_t scene_slots() const { return m_array ? m_entries.size() : m_peak; }
    /// Bytes of the array's table.
    int64_t table_bytes() const { return int64_t(m_table.capacity() * sizeof(InstanceEntry)); }

private:
    RTCSceneTy* new_scene() const;
    void write(uint32_t id);
    RTCGeometryTy* new_geometry(const DynEntry& e) const;
    void set_form(bool array);
    bool sparse() const {
        return !m_array && m_peak > SPARSE_FACTOR * m_entries.size() + SPARSE_SLACK;
    }
    void renew_if_sparse();
    int quality_for_size() const;

    RTCDeviceTy* m_device;
    TlasSceneSetup m_setup;
    uint32_t m_medium_max;
    bool m_array = true;
    std::vector<DynEntry> m_entries;
    InstanceTable m_table;  ///< by entry (the array form); read by the scene's geometry
    RTCSceneTy* m_scene = nullptr;
    uint64_t m_keyed = 0;    ///< entries with motion keys
    std::size_t m_peak = 0;  ///< the most geometries the scene has held at once
    bool m_dirty = false;
    /// The geometries form moves to a fresh scene when its scene has more than SPARSE_FACTOR
    /// times its geometries plus SPARSE_SLACK slots: Embree never shrinks a scene's geometry
    /// table and walks all of it at each commit (a walk of 1,024 empty slots costs microseconds).
    static constexpr std::size_t SPARSE_FACTOR = 4, SPARSE_SLACK = 1024;
};

}  // namespace strata
