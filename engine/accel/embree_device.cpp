#include "engine/accel/embree_device.h"

#include <embree3/rtcore.h>

namespace strata {

namespace {
/// set_thread_category's override: the device it is for and its category (-1 none).
struct ThreadCategory {
    uint64_t device = 0;
    int category = -1;
};
thread_local ThreadCategory t_category;
std::atomic<uint64_t> g_device_serial{0};
}  // namespace

void EmbreeDevice::set_thread_category(int c) const { t_category = {m_serial, c}; }

Result<std::unique_ptr<EmbreeDevice>> EmbreeDevice::create(const std::string& config) {
    std::unique_ptr<EmbreeDevice> d(new EmbreeDevice());
    d->m_serial = ++g_device_serial;
    d->m_device = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!d->m_device) {
        const RTCError code = rtcGetDeviceError(nullptr);
        return failure(ErrorCode::Internal,
                       "cannot create the Embree device (error " + std::to_string(int(code)) + ")");
    }
    rtcSetDeviceErrorFunction(
        d->m_device,
        [](void* self, RTCError code, const char* msg) { on_error(self, int(code), msg); },
        d.get());
    rtcSetDeviceMemoryMonitorFunction(
        d->m_device,
        [](void* self, ssize_t bytes, bool post) { return on_memory(self, bytes, post); }, d.get());
    return d;
}

EmbreeDevice::~EmbreeDevice() {
    if (m_device) rtcReleaseDevice(m_device);
}

void EmbreeDevice::on_error(void* self, int code, const char* message) {
    auto* d = static_cast<EmbreeDevice*>(self);
    if (code == RTC_ERROR_CANCELLED) return;
    std::lock_guard lock(d->m_error_mutex);
    if (!d->m_error) {
        d->m_error =
            make_error(ErrorCode::Internal, std::string("Embree error ") + std::to_string(code) +
                                                ": " + (message ? message : "(no message)"));
    }
}

bool EmbreeDevice::on_memory(void* self, long bytes, bool /*post*/) {
    auto* d = static_cast<EmbreeDevice*>(self);
    // Embree's documented usage: accumulate every call's signed byte count (allocations positive,
    // frees and undone allocations negative), whether it comes before or after the event.
    const ThreadCategory t = t_category;
    const int c = t.device == d->m_serial && t.category >= 0
                      ? t.category
                      : d->m_category.load(std::memory_order_relaxed);
    d->m_bytes[c].fetch_add(bytes, std::memory_order_relaxed);
    return true;
}

std::optional<Error> EmbreeDevice::take_error() {
    std::lock_guard lock(m_error_mutex);
    std::optional<Error> e;
    e.swap(m_error);
    return e;
}

Status EmbreeDevice::status(const char* what) {
    if (auto e = take_error()) {
        e->message = std::string(what) + ": " + e->message;
        return Unexpected(*e);
    }
    return {};
}

}  // namespace strata
