#include "engine/accel/embree_device.h"

#include <embree3/rtcore.h>

#include "engine/accel/blas_pool.h"

namespace strata {

namespace {
/// set_thread_category's override: the view it is for and its category (-1 none).
struct ThreadCategory {
    uint64_t view = 0;
    int category = -1;
};
thread_local ThreadCategory t_category;
std::atomic<uint64_t> g_view_serial{0};
}  // namespace

Result<std::shared_ptr<SharedEmbree>> SharedEmbree::create(const std::string& config) {
    std::shared_ptr<SharedEmbree> d(new SharedEmbree());
    d->m_device = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!d->m_device) {
        const RTCError code = rtcGetDeviceError(nullptr);
        return failure(ErrorCode::Internal,
                       "cannot create the Embree device (error " + std::to_string(int(code)) + ")");
    }
    d->m_pool = std::make_unique<BlasPool>();
    rtcSetDeviceErrorFunction(
        d->m_device,
        [](void* self, RTCError code, const char* msg) { on_error(self, int(code), msg); },
        d.get());
    rtcSetDeviceMemoryMonitorFunction(
        d->m_device,
        [](void* self, ssize_t bytes, bool post) { return on_memory(self, bytes, post); }, d.get());
    return d;
}

SharedEmbree::~SharedEmbree() {
    if (m_device) rtcReleaseDevice(m_device);
}

EmbreeDevice* SharedEmbree::view(uint64_t serial) const {
    const auto it = m_views.find(serial);
    return it == m_views.end() ? nullptr : it->second;
}

void SharedEmbree::on_error(void* self, int code, const char* message) {
    auto* d = static_cast<SharedEmbree*>(self);
    if (code == RTC_ERROR_CANCELLED) return;
    const Error e =
        make_error(ErrorCode::Internal, std::string("Embree error ") + std::to_string(code) +
                                            ": " + (message ? message : "(no message)"));
    // The view in a phase made it; outside phases (a trace) every view hears of it.
    std::lock_guard lock(d->m_views_mutex);
    if (EmbreeDevice* current = d->m_current.load(std::memory_order_acquire))
        return current->keep_error(e);
    for (const auto& [serial, view] : d->m_views) view->keep_error(e);
}

bool SharedEmbree::on_memory(void* self, long bytes, bool /*post*/) {
    auto* d = static_cast<SharedEmbree*>(self);
    // Embree's documented usage: accumulate every call's signed byte count (allocations positive,
    // frees and undone allocations negative), whether it comes before or after the event.
    const ThreadCategory t = t_category;
    if (t.category >= 0) {
        std::lock_guard lock(d->m_views_mutex);
        if (EmbreeDevice* v = d->view(t.view)) {
            v->m_bytes[t.category].fetch_add(bytes, std::memory_order_relaxed);
            return true;
        }
    }
    if (EmbreeDevice* v = d->m_current.load(std::memory_order_acquire)) {
        v->m_bytes[v->m_category.load(std::memory_order_relaxed)].fetch_add(
            bytes, std::memory_order_relaxed);
        return true;
    }
    // Outside every phase: a view of its own device counts it as Other, as before.
    std::lock_guard lock(d->m_views_mutex);
    if (d->m_views.size() == 1 && !d->m_views.begin()->second->m_pooled) {
        d->m_views.begin()->second->m_bytes[int(MemoryCategory::Other)].fetch_add(
            bytes, std::memory_order_relaxed);
        return true;
    }
    d->m_unattributed.fetch_add(bytes, std::memory_order_relaxed);
    return true;
}

EmbreeDevice::EmbreeDevice(std::shared_ptr<SharedEmbree> shared, bool pooled)
    : m_shared(std::move(shared)), m_pooled(pooled), m_serial(++g_view_serial) {
    std::lock_guard lock(m_shared->m_views_mutex);
    m_shared->m_views.emplace(m_serial, this);
}

EmbreeDevice::~EmbreeDevice() {
    set_category(MemoryCategory::Other);
    std::lock_guard lock(m_shared->m_views_mutex);
    m_shared->m_views.erase(m_serial);
}

Result<std::unique_ptr<EmbreeDevice>> EmbreeDevice::create(const std::string& config) {
    auto shared = SharedEmbree::create(config);
    if (!shared) return Unexpected(shared.error());
    return std::unique_ptr<EmbreeDevice>(new EmbreeDevice(std::move(shared.value()), false));
}

std::unique_ptr<EmbreeDevice> EmbreeDevice::view(std::shared_ptr<SharedEmbree> shared) {
    return std::unique_ptr<EmbreeDevice>(new EmbreeDevice(std::move(shared), true));
}

void EmbreeDevice::set_category(MemoryCategory c) {
    if (c == MemoryCategory::Other) {
        m_category.store(int(c), std::memory_order_relaxed);
        if (m_phase.owns_lock()) {
            m_shared->m_current.store(nullptr, std::memory_order_release);
            m_phase.unlock();
        }
        return;
    }
    if (!m_phase.owns_lock()) {
        m_phase = std::unique_lock(m_shared->m_phase_mutex);
        m_shared->m_current.store(this, std::memory_order_release);
    }
    m_category.store(int(c), std::memory_order_relaxed);
}

void EmbreeDevice::set_thread_category(int c) const { t_category = {m_serial, c}; }

void EmbreeDevice::keep_error(Error e) {
    std::lock_guard lock(m_error_mutex);
    if (!m_error) m_error = std::move(e);
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
