#pragma once
// A TLAS instance scene without an Embree geometry per instance. Embree 3 has no instance
// arrays: each RTC_GEOMETRY_TYPE_INSTANCE is an object of its own, about 280 bytes with its
// transforms. Here one user geometry holds every instance: primitive i is the instance in slot
// i, read from a table of 64-byte entries. Its callbacks take the rays into the instance's space
// exactly as Embree's instance kernels do (the same inverse, the same multiply-adds, so the same
// hits to the bit) and trace the instance's BLAS with a copy of the caller's intersect context
// whose instance id is the slot, so hits, the context's filter (stale copies, hit tests) and LOD
// wrappers see what Embree's own instances give them. An entry holds no reference on its BLAS:
// the incremental TLAS never enters an entry whose BLAS may be gone (it is a stale copy).
// tests/bench/NOTES.md has both kinds measured.

#include <array>
#include <cstdint>
#include <vector>

struct RTCDeviceTy;
struct RTCSceneTy;

namespace strata {

struct TlasSceneSetup;

/// One instance of an array: the scene it instances and what takes rays into its space.
struct InstanceEntry {
    RTCSceneTy* blas = nullptr;  ///< null: no instance in this slot
    /// The inverse of its world transform as Embree computes it for an instance geometry: the
    /// linear part's columns, then the translation.
    std::array<float, 12> to_object{};
    uint32_t mask = 0;  ///< rays whose mask shares no bit with it pass through
};

/// The entry of an instance of `blas` with world transform `world` (3x4 row-major).
InstanceEntry instance_entry(RTCSceneTy* blas, const std::array<float, 12>& world,
                             uint32_t mask);

/// Entries by instance slot. A scene made over a table reads it while it builds and traces: it
/// changes only between a trace and the next commit of that scene.
using InstanceTable = std::vector<InstanceEntry>;

/// A new scene of `setup` holding one user geometry over `table` (which must outlive it),
/// uncommitted.
RTCSceneTy* new_instance_array_scene(RTCDeviceTy* device, const TlasSceneSetup& setup,
                                     const InstanceTable& table);

/// Brings the user geometry of an array scene in line with its table's size after the table
/// changed (the caller commits the scene).
void update_instance_array_scene(RTCSceneTy* scene, const InstanceTable& table);

}  // namespace strata
