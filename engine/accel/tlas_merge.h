#pragma once
// A background build of the incremental TLAS's next static tier: the current static tier with
// the edits since its build applied, built on a thread of its own in a low-priority TBB arena, so
// it never holds up edits, commits or launches. The commit that finds it finished swaps it in
// (incremental_tlas.cpp). A static tier of instance geometries gets new geometries for moved and
// re-added instances (removed and hidden ones are left out) in a new Embree instance scene; an
// instance array (instance_array.h) gets a copy of its table with the edits written in.
//
// What it reads while it runs is never written meanwhile: the static tier's geometry table,
// geometries and instance table only change when a merge is swapped in or after it was cancelled
// and joined, and BLASes are only rebuilt or refit after TlasStrategy::before_blas_changes
// cancelled it.

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

#include "engine/accel/embree_device.h"
#include "engine/accel/instance_array.h"
#include "engine/core/math.h"
#include "engine/scene/types.h"

struct RTCSceneTy;
struct RTCGeometryTy;

namespace strata {

/// How a TLAS instance scene is built (shared by both tiers and the merge).
struct TlasSceneSetup {
    int quality = 0;  ///< RTCBuildQuality
    int flags = 0;    ///< RTCSceneFlags
};

/// One instance as the merge must build it.
struct MergeEntry {
    uint32_t slot = 0;
    RTCSceneTy* blas = nullptr;  ///< nullptr: the instance is gone or hidden, leave it out
    std::array<float, 12> transform{};
    std::vector<Affine> keys;  ///< world-space motion keys; empty: none
    MotionInterpolation interpolation = MotionInterpolation::Linear;
    uint32_t mask = 0;
};

/// The low-priority TBB arena merges build in, observed so that every thread working in it
/// attributes its Embree allocations to the TLAS. It outlives the merges: a worker that leaves
/// the arena after its build returned still has its category reset (an observer removed while
/// workers are inside never tells them they left).
class MergeArena {
public:
    explicit MergeArena(const EmbreeDevice& device);
    ~MergeArena();
    MergeArena(const MergeArena&) = delete;
    MergeArena& operator=(const MergeArena&) = delete;

    /// Runs `f` in the arena and waits for it.
    template <typename F>
    void execute(F&& f) {
        execute_function(std::function<void()>(std::forward<F>(f)));
    }

private:
    void execute_function(const std::function<void()>& f);
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

class TlasMerge {
public:
    /// Starts building in `arena`. `static_geoms` (by slot) must stay unchanged until join()
    /// returns.
    TlasMerge(EmbreeDevice& device, MergeArena& arena, TlasSceneSetup setup,
              const std::vector<RTCGeometryTy*>& static_geoms, std::vector<MergeEntry> entries,
              uint64_t serial);
    /// The same for a static tier that is an instance array over `table` (entries with motion
    /// keys cannot be written into one: the caller starts no such merge).
    TlasMerge(EmbreeDevice& device, MergeArena& arena, TlasSceneSetup setup,
              std::shared_ptr<const InstanceTable> table, std::vector<MergeEntry> entries,
              uint64_t serial);
    /// Cancels, joins and releases whatever was built and not taken.
    ~TlasMerge();
    TlasMerge(const TlasMerge&) = delete;
    TlasMerge& operator=(const TlasMerge&) = delete;

    /// True once the build has ended (finished, failed or cancelled); join() will not wait.
    bool done() const { return m_done.load(std::memory_order_acquire); }
    /// Asks the build to stop as soon as it can (Embree's progress monitor checks it).
    void cancel() { m_cancel.store(true, std::memory_order_relaxed); }
    /// Waits for the build to end.
    void join();

    /// After join(): whether a complete scene was built.
    bool succeeded() const { return m_scene != nullptr; }
    /// The commit serial whose edits the build covers.
    uint64_t serial() const { return m_serial; }
    const std::vector<MergeEntry>& entries() const { return m_entries; }
    double build_ms() const { return m_build_ms; }
    /// Takes the built scene and its geometry table (one reference per geometry: those shared
    /// with the old table carry no new reference, so the caller releases the ones it replaces).
    RTCSceneTy* take_scene(std::vector<RTCGeometryTy*>& geoms);
    /// Takes the built instance-array scene and its table.
    RTCSceneTy* take_scene(std::shared_ptr<InstanceTable>& table);

private:
    void start(std::function<RTCSceneTy*()> make);
    RTCSceneTy* make_geometries(const std::vector<RTCGeometryTy*>& static_geoms);
    RTCSceneTy* make_array(const InstanceTable& from);
    void build(RTCSceneTy* scene);
    void discard();

    EmbreeDevice& m_device;
    MergeArena& m_arena;
    TlasSceneSetup m_setup;
    std::vector<MergeEntry> m_entries;
    uint64_t m_serial;
    std::atomic<bool> m_cancel{false};
    std::atomic<bool> m_done{false};
    RTCSceneTy* m_scene = nullptr;
    std::vector<RTCGeometryTy*> m_geoms;    ///< by slot: the new static tier
    std::vector<RTCGeometryTy*> m_created;  ///< geometries the merge created (ours to release)
    std::shared_ptr<const InstanceTable> m_from;  ///< the array merged from (array merges)
    std::shared_ptr<InstanceTable> m_table;       ///< the new static tier's (array merges)
    double m_build_ms = 0.0;
    std::thread m_thread;
};

}  // namespace strata
