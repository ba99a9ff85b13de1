#include "engine/accel/tlas_merge.h"

#include <algorithm>

#include <embree3/rtcore.h>
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include "engine/accel/instance_transform.h"
#include "engine/core/timer.h"

namespace strata {

namespace {

/// Attributes every Embree allocation made by a thread working in the merge's arena to the TLAS,
/// whatever phase the commit running beside it is in.
class TlasMemoryObserver final : public tbb::task_scheduler_observer {
public:
    TlasMemoryObserver(tbb::task_arena& arena, const EmbreeDevice& device)
        : tbb::task_scheduler_observer(arena), m_device(device) {
        observe(true);
    }
    ~TlasMemoryObserver() override { observe(false); }
    void on_scheduler_entry(bool) override {
        m_device.set_thread_category(int(MemoryCategory::Tlas));
    }
    void on_scheduler_exit(bool) override { m_device.set_thread_category(-1); }

private:
    const EmbreeDevice& m_device;
};

bool keep_going(void* cancel, double) {
    return !static_cast<const std::atomic<bool>*>(cancel)->load(std::memory_order_relaxed);
}

}  // namespace

struct MergeArena::Impl {
    // Low priority: the arena gets worker threads only when launches and commits (normal
    // priority) leave some idle.
    tbb::task_arena arena{tbb::task_arena::automatic, 1, tbb::task_arena::priority::low};
    std::unique_ptr<TlasMemoryObserver> observer;
};

MergeArena::MergeArena(const EmbreeDevice& device) : m_impl(std::make_unique<Impl>()) {
    m_impl->arena.initialize();
    m_impl->observer = std::make_unique<TlasMemoryObserver>(m_impl->arena, device);
}

MergeArena::~MergeArena() {
    // Workers still inside keep a TLAS override for this device only (embree_device.cpp), and
    // the device is not used past its TLAS.
    m_impl->observer.reset();
}

void MergeArena::execute_function(const std::function<void()>& f) { m_impl->arena.execute(f); }

TlasMerge::TlasMerge(EmbreeDevice& device, MergeArena& arena, TlasSceneSetup setup,
                     const std::vector<RTCGeometryTy*>& static_geoms,
                     std::vector<MergeEntry> entries, uint64_t serial)
    : m_device(device),
      m_arena(arena),
      m_setup(setup),
      m_entries(std::move(entries)),
      m_serial(serial) {
    start([this, &static_geoms] { return make_geometries(static_geoms); });
}

TlasMerge::TlasMerge(EmbreeDevice& device, MergeArena& arena, TlasSceneSetup setup,
                     std::shared_ptr<const InstanceTable> table, std::vector<MergeEntry> entries,
                     uint64_t serial)
    : m_device(device),
      m_arena(arena),
      m_setup(setup),
      m_entries(std::move(entries)),
      m_serial(serial),
      m_from(std::move(table)) {
    start([this] { return make_array(*m_from); });
}

void TlasMerge::start(std::function<RTCSceneTy*()> make) {
    m_thread = std::thread([this, make = std::move(make)] {
        m_device.set_thread_category(int(MemoryCategory::Tlas));
        Stopwatch clock;
        build(make());
        m_build_ms = clock.ms();
        m_device.set_thread_category(-1);
        m_done.store(true, std::memory_order_release);
    });
}

TlasMerge::~TlasMerge() {
    cancel();
    join();
    discard();
}

void TlasMerge::join() {
    if (m_thread.joinable()) m_thread.join();
}

RTCScene TlasMerge::make_geometries(const std::vector<RTCGeometryTy*>& static_geoms) {
    // Step: the new geometry table, with new geometries for the edited instances.
    RTCDevice device = m_device.get();
    m_geoms = static_geoms;
    uint32_t max_slot = 0;
    for (const MergeEntry& e : m_entries) max_slot = std::max(max_slot, e.slot);
    if (!m_entries.empty() && max_slot >= m_geoms.size()) m_geoms.resize(max_slot + 1, nullptr);
    m_created.reserve(m_entries.size());
    for (const MergeEntry& e : m_entries) {
        if (!e.blas) {
            m_geoms[e.slot] = nullptr;
            continue;
        }
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        set_instance(g, e.blas, e.transform.data(), e.keys, e.interpolation, e.mask);
        m_created.push_back(g);
        m_geoms[e.slot] = g;
    }

    // Step: attach by slot (a hit's instID is the slot).
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTCBuildQuality(m_setup.quality));
    rtcSetSceneFlags(scene, RTCSceneFlags(m_setup.flags));
    for (uint32_t slot = 0; slot < m_geoms.size(); ++slot) {
        if ((slot & 4095) == 0 && m_cancel.load(std::memory_order_relaxed)) break;
        if (m_geoms[slot]) rtcAttachGeometryByID(scene, m_geoms[slot], slot);
    }
    return scene;
}

RTCScene TlasMerge::make_array(const InstanceTable& from) {
    m_table = std::make_shared<InstanceTable>(from);
    for (const MergeEntry& e : m_entries) {
        if (e.slot >= m_table->size()) m_table->resize(std::size_t(e.slot) + 1);
        (*m_table)[e.slot] = e.blas ? instance_entry(e.blas, e.transform, e.mask) : InstanceEntry{};
    }
    return new_instance_array_scene(m_device.get(), m_setup, *m_table);
}

void TlasMerge::build(RTCScene scene) {
    // Cancellable throughout; only the build runs inside the low-priority arena.
    rtcSetSceneProgressMonitorFunction(scene, keep_going, &m_cancel);
    if (!m_cancel.load(std::memory_order_relaxed)) m_arena.execute([&] { rtcCommitScene(scene); });
    rtcSetSceneProgressMonitorFunction(scene, nullptr, nullptr);
    // A cancelled build leaves the scene unusable; any other failure reports through the device.
    if (m_cancel.load(std::memory_order_relaxed)) {
        rtcReleaseScene(scene);
    } else {
        m_scene = scene;
    }
}

RTCSceneTy* TlasMerge::take_scene(std::vector<RTCGeometryTy*>& geoms) {
    RTCSceneTy* scene = m_scene;
    m_scene = nullptr;
    geoms = std::move(m_geoms);
    m_geoms.clear();
    m_created.clear();  // now owned through `geoms`
    return scene;
}

RTCSceneTy* TlasMerge::take_scene(std::shared_ptr<InstanceTable>& table) {
    RTCSceneTy* scene = m_scene;
    m_scene = nullptr;
    table = std::move(m_table);
    return scene;
}

void TlasMerge::discard() {
    if (m_scene) rtcReleaseScene(m_scene);
    m_scene = nullptr;
    for (RTCGeometry g : m_created) rtcReleaseGeometry(g);
    m_created.clear();
    m_geoms.clear();
}

}  // namespace strata
