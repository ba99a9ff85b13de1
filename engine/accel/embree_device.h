#pragma once
// The Embree device: created once per engine, with an error callback that turns Embree errors
// into engine Errors and a memory monitor that attributes Embree's allocations to the BLAS or the
// TLAS according to the phase the commit is in.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "engine/core/result.h"

struct RTCDeviceTy;

namespace strata {

enum class MemoryCategory : int { Blas = 0, Tlas = 1, Other = 2 };

class EmbreeDevice {
public:
    /// Creates a device; `config` is Embree's device configuration string (may be empty).
    static Result<std::unique_ptr<EmbreeDevice>> create(const std::string& config);
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDeviceTy* get() const { return m_device; }

    /// Attributes Embree allocations from now on to `c` (commits are serialised, so one global
    /// category is exact).
    void set_category(MemoryCategory c) { m_category.store(int(c), std::memory_order_relaxed); }
    /// Attributes this device's Embree allocations made on the calling thread to `c` whatever
    /// the device's category is (background TLAS builds run beside commits); -1 ends the
    /// override. The override names this device, so a thread that keeps one (a TBB worker that
    /// left an arena unobserved) never misattributes another device's memory.
    void set_thread_category(int c) const;
    /// Moves `bytes` from category `from` to `to`: memory that is freed later under `to` (a BLAS
    /// the store let go of while a TLAS copy still references it).
    void transfer(MemoryCategory from, MemoryCategory to, int64_t bytes) {
        m_bytes[int(from)].fetch_sub(bytes, std::memory_order_relaxed);
        m_bytes[int(to)].fetch_add(bytes, std::memory_order_relaxed);
    }
    /// Bytes Embree currently holds for category `c`.
    int64_t bytes(MemoryCategory c) const { return m_bytes[int(c)].load(std::memory_order_relaxed); }

    /// The first Embree error since the last call, if any (and clears it). A build cancelled on
    /// purpose (a progress monitor returning false) is not an error and is not kept.
    std::optional<Error> take_error();
    /// take_error() as a Status whose message starts with `what`.
    Status status(const char* what);

private:
    EmbreeDevice() = default;
    static void on_error(void* self, int code, const char* message);
    static bool on_memory(void* self, long bytes, bool post);

    RTCDeviceTy* m_device = nullptr;
    uint64_t m_serial = 0;  ///< unique per process (addresses are reused)
    std::atomic<int> m_category{int(MemoryCategory::Other)};
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
