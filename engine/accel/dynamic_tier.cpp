#include "engine/accel/dynamic_tier.h"

#include <algorithm>
#include <utility>

#include <embree3/rtcore.h>

#include "engine/accel/instance_transform.h"

namespace strata {

DynamicTier::DynamicTier(RTCDevice device, TlasSceneSetup setup, uint32_t medium_max)
    : m_device(device), m_setup(setup), m_medium_max(medium_max) {
    m_setup.quality = quality_for_size();
    m_scene = new_scene();
    rtcCommitScene(m_scene);  // empty committed scenes are traceable
}

DynamicTier::~DynamicTier() {
    clear();
    rtcReleaseScene(m_scene);
}

RTCScene DynamicTier::new_scene() const {
    if (m_array) return new_instance_array_scene(m_device, m_setup, m_table);
    RTCScene s = rtcNewScene(m_device);
    rtcSetSceneBuildQuality(s, RTCBuildQuality(m_setup.quality));
    rtcSetSceneFlags(s, RTCSceneFlags(m_setup.flags));
    return s;
}

uint32_t DynamicTier::add(uint32_t slot) {
    DynEntry e;
    e.slot = slot;
    m_entries.push_back(std::move(e));
    if (m_array) m_table.emplace_back();
    m_dirty = true;
    return uint32_t(m_entries.size() - 1);
}

void DynamicTier::set(uint32_t id, RTCScene blas, const std::array<float, 12>& transform,
                      const std::vector<Affine>& keys, MotionInterpolation interpolation,
                      uint32_t mask) {
    DynEntry& e = m_entries[id];
    m_keyed += uint64_t(!keys.empty()) - uint64_t(!e.keys.empty());
    e.blas = blas;
    e.transform = transform;
    e.keys = keys;
    e.interpolation = interpolation;
    e.mask = mask;
    write(id);  // an array entry with keys is written as one without: commit() changes form
    m_dirty = true;
}

/// Brings entry `id`'s table entry or instance geometry in line with it.
void DynamicTier::write(uint32_t id) {
    DynEntry& e = m_entries[id];
    if (m_array) {
        m_table[id] = instance_entry(e.blas, e.transform, e.mask);
        return;
    }
    if (!e.geometry) {
        e.geometry = new_geometry(e);
        rtcAttachGeometryByID(m_scene, e.geometry, id);
        m_peak = std::max(m_peak, m_entries.size());
        return;
    }
    set_instance(e.geometry, e.blas, e.transform.data(), e.keys, e.interpolation, e.mask);
}

RTCGeometry DynamicTier::new_geometry(const DynEntry& e) const {
    RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_INSTANCE);
    set_instance(g, e.blas, e.transform.data(), e.keys, e.interpolation, e.mask);
    return g;
}

void DynamicTier::remove(uint32_t id) {
    const auto last = uint32_t(m_entries.size() - 1);
    m_keyed -= uint64_t(!m_entries[id].keys.empty());
    if (!m_array) {
        rtcDetachGeometry(m_scene, id);
        rtcReleaseGeometry(m_entries[id].geometry);
        if (id != last) {
            rtcDetachGeometry(m_scene, last);
            rtcAttachGeometryByID(m_scene, m_entries[last].geometry, id);
        }
    }
    if (id != last) {
        m_entries[id] = std::move(m_entries[last]);
        if (m_array) m_table[id] = m_table[last];
    }
    m_entries.pop_back();
    if (m_array) m_table.pop_back();
    m_dirty = true;
}

RTCGeometry DynamicTier::take_geometry(uint32_t id) {
    DynEntry& e = m_entries[id];
    if (!e.geometry) return new_geometry(e);
    rtcDetachGeometry(m_scene, id);
    return std::exchange(e.geometry, nullptr);
}

void DynamicTier::clear() {
    for (uint32_t id = 0; id < m_entries.size(); ++id) {
        if (!m_entries[id].geometry) continue;
        rtcDetachGeometry(m_scene, id);
        rtcReleaseGeometry(m_entries[id].geometry);
    }
    m_entries.clear();
    InstanceTable().swap(m_table);  // frees its buffer, counted as TLAS memory
    m_keyed = 0;
    m_dirty = true;
}

/// Rebuilds the scene in the other form: geometries when `array` is false.
void DynamicTier::set_form(bool array) {
    if (array == m_array) return;
    for (DynEntry& e : m_entries) {
        if (e.geometry) rtcReleaseGeometry(std::exchange(e.geometry, nullptr));
    }
    rtcReleaseScene(m_scene);  // it releases the geometries it held
    m_array = array;
    m_table.assign(array ? m_entries.size() : 0, InstanceEntry{});
    m_peak = 0;
    m_scene = new_scene();
    for (uint32_t id = 0; id < m_entries.size(); ++id) write(id);
    m_dirty = true;
}

/// A tier of geometries that has drained far below its peak moves to a fresh scene, leaving
/// behind the empty slots each commit would walk.
void DynamicTier::renew_if_sparse() {
    if (!sparse()) return;
    RTCScene fresh = new_scene();
    for (uint32_t id = 0; id < m_entries.size(); ++id)
        rtcAttachGeometryByID(fresh, m_entries[id].geometry, id);
    rtcReleaseScene(m_scene);
    m_scene = fresh;
    m_peak = m_entries.size();
    m_dirty = true;
}

/// Arrays build fastest at LOW. Geometries: MEDIUM up to m_medium_max, LOW past twice that, and
/// in between the quality the scene has.
int DynamicTier::quality_for_size() const {
    if (m_array) return RTC_BUILD_QUALITY_LOW;
    if (m_entries.size() <= m_medium_max) return RTC_BUILD_QUALITY_MEDIUM;
    if (m_entries.size() > 2 * std::size_t(m_medium_max)) return RTC_BUILD_QUALITY_LOW;
    return m_setup.quality;
}

void DynamicTier::commit() {
    set_form(m_keyed == 0);
    renew_if_sparse();
    if (const int quality = quality_for_size(); quality != m_setup.quality) {
        m_setup.quality = quality;
        rtcSetSceneBuildQuality(m_scene, RTCBuildQuality(quality));
    }
    if (m_array) update_instance_array_scene(m_scene, m_table);
    rtcCommitScene(m_scene);
    m_dirty = false;
}

const char* DynamicTier::quality_name() const {
    return m_setup.quality == RTC_BUILD_QUALITY_MEDIUM ? "medium" : "low";
}

}  // namespace strata
