#pragma once
// The Embree device an engine builds and traces with: an error callback that turns Embree errors
// into engine Errors and a memory monitor that attributes Embree's allocations to the BLAS or the
// TLAS according to the phase the commit is in.
//
// Several engines may share one Embree device (SharedEmbree: a server's scenes, so that their
// identical meshes share one BLAS, blas_pool.h). Each engine then has its own EmbreeDevice, a
// view of the shared one with its own categories and errors. Embree reports allocations per
// device, not per scene, so a view that enters a memory phase (set_category, MemoryScope) holds
// the shared device's phase lock until it leaves it: commits of engines on one device take turns
// in their Embree phases, and every allocation made meanwhile is that view's. Renders take no
// lock. A thread's own category (set_thread_category: background TLAS builds) names its view.

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "engine/core/result.h"

struct RTCDeviceTy;

namespace strata {

enum class MemoryCategory : int { Blas = 0, Tlas = 1, Other = 2 };

class BlasPool;
class EmbreeDevice;

/// One Embree device that several engines' views share, with the pool of BLASes they share.
class SharedEmbree {
public:
    /// Creates the device; `config` is Embree's device configuration string (may be empty).
    static Result<std::shared_ptr<SharedEmbree>> create(const std::string& config);
    ~SharedEmbree();
    SharedEmbree(const SharedEmbree&) = delete;
    SharedEmbree& operator=(const SharedEmbree&) = delete;

    RTCDeviceTy* get() const { return m_device; }
    /// The BLASes its views share; null for a device that one engine has to itself.
    BlasPool* pool() const { return m_pool.get(); }

private:
    friend class EmbreeDevice;
    SharedEmbree() = default;
    static void on_error(void* self, int code, const char* message);
    static bool on_memory(void* self, long bytes, bool post);
    /// The view with `serial`, or null (under m_views_mutex).
    EmbreeDevice* view(uint64_t serial) const;

    RTCDeviceTy* m_device = nullptr;
    std::unique_ptr<BlasPool> m_pool;
    std::mutex m_phase_mutex;               ///< held by the view in a memory phase
    std::atomic<EmbreeDevice*> m_current{};  ///< that view
    mutable std::mutex m_views_mutex;
    std::map<uint64_t, EmbreeDevice*> m_views;  ///< by serial
    std::atomic<int64_t> m_unattributed{0};     ///< bytes no view was in a phase for
};

class EmbreeDevice {
public:
    /// A device of its own; `config` is Embree's device configuration string (may be empty).
    static Result<std::unique_ptr<EmbreeDevice>> create(const std::string& config);
    /// A view of `shared`, whose BLASes it may share with the other views (blas_pool.h).
    static std::unique_ptr<EmbreeDevice> view(std::shared_ptr<SharedEmbree> shared);
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDeviceTy* get() const { return m_shared->get(); }
    /// The pool of BLASes shared with other views; null when the device is this engine's own.
    BlasPool* pool() const { return m_pooled ? m_shared->pool() : nullptr; }

    /// Attributes Embree allocations from now on to `c`: a phase other than Other holds the
    /// shared device's phase lock (see above) until Other ends it. The commit thread's only.
    void set_category(MemoryCategory c);
    /// Attributes this device's Embree allocations made on the calling thread to `c` whatever
    /// the device's category is (background TLAS builds run beside commits); -1 ends the
    /// override. The override names this view, so a thread that keeps one (a TBB worker that
    /// left an arena unobserved) never misattributes another view's memory.
    void set_thread_category(int c) const;
    /// Moves `bytes` from category `from` to `to`: memory that is freed later under `to` (a BLAS
    /// the store let go of while a TLAS copy still references it).
    void transfer(MemoryCategory from, MemoryCategory to, int64_t bytes) {
        m_bytes[int(from)].fetch_sub(bytes, std::memory_order_relaxed);
        m_bytes[int(to)].fetch_add(bytes, std::memory_order_relaxed);
    }
    /// Moves `bytes` of category `c` to view `to` of the same device: memory it will free.
    void transfer_to(EmbreeDevice& to, MemoryCategory c, int64_t bytes) {
        m_bytes[int(c)].fetch_sub(bytes, std::memory_order_relaxed);
        to.m_bytes[int(c)].fetch_add(bytes, std::memory_order_relaxed);
    }
    /// Counts `bytes` (negative: fewer) that Strata holds for category `c` beside Embree's own
    /// allocations (an instance array's table).
    void account(MemoryCategory c, int64_t bytes) {
        m_bytes[int(c)].fetch_add(bytes, std::memory_order_relaxed);
    }
    /// Bytes held for category `c`: Embree's, and what account() added.
    int64_t bytes(MemoryCategory c) const { return m_bytes[int(c)].load(std::memory_order_relaxed); }

    /// The first Embree error since the last call, if any (and clears it). A build cancelled on
    /// purpose (a progress monitor returning false) is not an error and is not kept.
    std::optional<Error> take_error();
    /// take_error() as a Status whose message starts with `what`.
    Status status(const char* what);

private:
    friend class SharedEmbree;
    EmbreeDevice(std::shared_ptr<SharedEmbree> shared, bool pooled);
    void keep_error(Error e);

    std::shared_ptr<SharedEmbree> m_shared;
    bool m_pooled = false;
    uint64_t m_serial = 0;  ///< unique per process (addresses are reused)
    std::atomic<int> m_category{int(MemoryCategory::Other)};
    std::unique_lock<std::mutex> m_phase;  ///< the shared device's phase lock, while in a phase
    std::atomic<int64_t> m_bytes[3] = {};
    std::mutex m_error_mutex;
    std::optional<Error> m_error;
};

/// RAII scope that sets the device's memory category and restores Other on exit.
class MemoryScope {
public:
    MemoryScope(EmbreeDevice& d, MemoryCategory c) : m_device(d) { d.set_category(c); }
    ~MemoryScope() { m_device.set_category(MemoryCategory::Other); }
    MemoryScope(const MemoryScope&) = delete;
    MemoryScope& operator=(const MemoryScope&) = delete;

private:
    EmbreeDevice& m_device;
};

}  // namespace strata
