// The incremental TLAS: what a commit costs grows with the instances it changes, not with the
// instances the scene holds.
//
//   static tier   an Embree scene over (almost) every visible instance: instance geometries
//                 attached by slot, or in big scenes an instance array (instance_array.h) whose
//                 primitive i is slot i. It is rebuilt rarely: in the background by a merge, or
//                 in the commit itself under the fallback policy (TlasPolicy).
//   dynamic tier  a small Embree scene over the instances added or edited since the static
//                 tier was built, by dense index (m_dyn maps it to the slot; dynamic_tier.h).
//                 Every update rebuilds it, at a cost proportional to its size.
//   stale copies  an instance edited since the static build still sits in the static tier at its
//                 old place. Rays skip it through an intersection-context filter that reads a
//                 per-slot byte; the filter is installed only while stale copies exist.
//
// A ray traces the static tier, then the dynamic one with tfar already clamped to the first hit;
// shadow rays likewise (a ray occluded by the static tier skips the dynamic one). Hits report
// the instance slot whichever tier they came from.
//
// A background merge (tlas_merge.h) builds the next static tier with the edits applied; the first
// commit after it finishes swaps it in, and the instances whose last edit it covers leave the
// dynamic tier. Commits and launches are serialised, so a launch traces exactly one version.

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <thread>
#include <vector>

#include "engine/accel/blas_store.h"
#include "engine/accel/dynamic_tier.h"
#include "engine/accel/embree_device.h"
#include "engine/accel/embree_trace.h"
#include "engine/accel/instance_array.h"
#include "engine/accel/instance_transform.h"
#include "engine/accel/tlas.h"
#include "engine/accel/tlas_merge.h"
#include "engine/scene/scene.h"

namespace strata {

namespace {

using embree_trace::deactivate_unused_lanes;
using embree_trace::filter_context;
using embree_trace::FilterContext;


/// Sets the calling thread's memory category to the TLAS for a scope: background merges are
/// released from the commit thread, whatever phase it is in.
class TlasMemoryScope {
public:
    explicit TlasMemoryScope(const EmbreeDevice& d) : m_device(d) {
        d.set_thread_category(int(MemoryCategory::Tlas));
    }
    ~TlasMemoryScope() { m_device.set_thread_category(-1); }

private:
    const EmbreeDevice& m_device;
};

/// The hit fields of one ray (ng .. inst_id are contiguous in RayHit1).
struct SavedHit1 {
    float ng[3], u, v;
    uint32_t prim_id, geom_id, inst_id;
};
static_assert(sizeof(SavedHit1) == offsetof(RayHit1, inst_id) + 4 - offsetof(RayHit1, ng_x));

class IncrementalTlas final : public TlasStrategy {
public:
    IncrementalTlas(EmbreeDevice& device, BuildPreference prefer, bool watertight,
                    const TlasPolicy& policy)
        : m_device(device),
          m_policy(policy),
          m_static_setup{prefer == BuildPreference::FastTrace ? RTC_BUILD_QUALITY_MEDIUM
                                                              : RTC_BUILD_QUALITY_LOW,
                         RTC_SCENE_FLAG_DYNAMIC | (watertight ? RTC_SCENE_FLAG_ROBUST : 0)},
          // Rebuilt at every update and kept small: build speed first (dynamic_tier.h).
          m_dyn(device.get(), {RTC_BUILD_QUALITY_LOW, m_static_setup.flags},
                policy.dynamic_medium_max) {
        m_static = new_scene(m_static_setup);
        // Empty committed scenes are traceable; launches may come before any instance exists.
        rtcCommitScene(m_static);
    }

    ~IncrementalTlas() override {
        m_merge.reset();
        reap_retired(true);
        release_everything();
        rtcReleaseScene(m_static);
        m_table.reset();  // after the scene that reads it
        account_table();
    }

    const char* name() const override { return "incremental"; }

    bool holds(InstanceHandle h) const override {
        return h.index < m_slots.size() && m_slots[h.index].held &&
               m_slots[h.index].generation == h.generation;
    }

    uint64_t instance_count() const override { return m_held; }

    Status update(const Scene& scene, const BlasStore& blas, const TlasDelta& delta) override {
        MemoryScope memory(m_device, MemoryCategory::Tlas);
        sweep_lod(blas);
        ++m_serial;
        // Step: choose the path. The dynamic tier must stay a small fraction of the scene (every
        // update rebuilds it); small scenes keep none, since a full build there is cheap.
        const double instances = double(scene.instances().size());
        const double limit = m_policy.max_dynamic_fraction * instances;
        auto over_limit = [&] {
            return double(m_dyn.size() + delta.changed.size() + delta.blas_changed.size()) > limit;
        };
        const char* sync_reason = nullptr;
        if (instances < double(m_policy.min_instances)) {
            sync_reason = "small_scene";
        } else if (over_limit()) {
            // A merge under way takes the dynamic tier as it was when the merge started. Waiting
            // for it costs the rest of its build; the fallback below would cancel it and build
            // the whole static tier again (tests/bench/NOTES.md has both measured).
            finish_merge_now();
            if (over_limit())
                sync_reason = m_static_count == 0 ? "first_build" : "dynamic_tier_full";
        }

        if (sync_reason) {
            fold_into_static(scene, blas, delta);
            m_report.static_rebuild = sync_reason;
            return m_device.status("rebuilding the static TLAS tier");
        }

        // Step: edits go to the dynamic tier; their static copies become stale.
        for (InstanceHandle h : delta.changed) edit_dynamic(scene, blas, h);
        for (InstanceHandle h : delta.blas_changed) {
            // The static copy's bounds came from the old BLAS: treat it as an edit.
            if (holds(h)) edit_dynamic(scene, blas, h);
        }
        swap_finished_merge();
        finish_commit();
        return m_device.status("updating the TLAS");
    }

    Status rebuild(const Scene& scene, const BlasStore& blas) override {
        MemoryScope memory(m_device, MemoryCategory::Tlas);
        sweep_lod(blas);
        ++m_serial;
        rebuild_static(scene, blas);
        commit_static();
        m_dyn.commit();
        m_static_serial = m_serial;
        m_report.static_rebuild = "requested";
        return m_device.status("rebuilding the TLAS");
    }

    void before_blas_changes() override {
        // A running merge reads BLAS bounds; a finished one no longer reads anything.
        if (m_merge && !m_merge->done()) cancel_merge();
    }

    bool maintain() override {
        if (m_merge && !m_merge->done()) return false;
        // A finished merge is swapped in; with none running, one starts if edits wait for it
        // (a merge cancelled by a BLAS change is restarted here).
        swap_finished_merge();
        finish_commit();
        return m_report.merge_swapped;
    }

    TlasTiers tiers_report() override {
        TlasTiers t = m_report;
        t.strategy = "incremental";
        t.static_instances = m_static_count;
        t.dynamic_instances = m_dyn.size();
        t.stale_copies = m_stale_count;
        t.dynamic_slots = m_dyn.scene_slots();
        t.dynamic_quality = m_dyn.quality_name();
        t.dynamic_array = m_dyn.is_array();
        t.static_array = m_array;
        t.merge_running = m_merge && !m_merge->done();
        m_report = TlasTiers{};
        return t;
    }

    void wait_for_background() override {
        if (m_merge) m_merge->join();
        reap_retired(true);
    }

    void trace1(RayHit1& ray, bool coherent, const TraceOptions& options) const override {
        FilterContext context = static_context(coherent, options);
        rtcIntersect1(m_static, &context.ctx, reinterpret_cast<RTCRayHit*>(&ray));
        if (m_dyn.empty()) return;

        SavedHit1 saved;
        std::memcpy(&saved, &ray.ng_x, sizeof saved);
        ray.inst_id = INVALID_ID;
        FilterContext dynamic = dynamic_context(coherent, options);
        rtcIntersect1(m_dyn.scene(), &dynamic.ctx, reinterpret_cast<RTCRayHit*>(&ray));
        if (ray.inst_id == INVALID_ID) {
            std::memcpy(&ray.ng_x, &saved, sizeof saved);
        } else {
            ray.inst_id = m_dyn.entries()[ray.inst_id].slot;
        }
    }

    void trace16(const ValidMask16& valid, RayHit16& rays, bool coherent,
                 const TraceOptions& options) const override {
        deactivate_unused_lanes(valid, rays);
        FilterContext context = static_context(coherent, options);
        rtcIntersect16(valid.lanes, m_static, &context.ctx, reinterpret_cast<RTCRayHit16*>(&rays));
        if (m_dyn.empty()) return;

        // Lanes the dynamic tier leaves alone keep their static hit (or miss).
        RayHit16 saved;
        constexpr std::size_t HIT_BEGIN = offsetof(RayHit16, ng_x);
        constexpr std::size_t HIT_BYTES = sizeof(RayHit16) - HIT_BEGIN;
        std::memcpy(reinterpret_cast<char*>(&saved) + HIT_BEGIN,
                    reinterpret_cast<const char*>(&rays) + HIT_BEGIN, HIT_BYTES);
        for (uint32_t i = 0; i < 16; ++i) rays.inst_id[i] = INVALID_ID;
        FilterContext dynamic = dynamic_context(coherent, options);
        rtcIntersect16(valid.lanes, m_dyn.scene(), &dynamic.ctx,
                       reinterpret_cast<RTCRayHit16*>(&rays));
        for (uint32_t i = 0; i < 16; ++i) {
            if (!valid.lanes[i]) {
                rays.inst_id[i] = saved.inst_id[i];
            } else if (rays.inst_id[i] != INVALID_ID) {
                rays.inst_id[i] = m_dyn.entries()[rays.inst_id[i]].slot;
            } else {
                rays.ng_x[i] = saved.ng_x[i];
                rays.ng_y[i] = saved.ng_y[i];
                rays.ng_z[i] = saved.ng_z[i];
                rays.u[i] = saved.u[i];
                rays.v[i] = saved.v[i];
                rays.prim_id[i] = saved.prim_id[i];
                rays.geom_id[i] = saved.geom_id[i];
                rays.inst_id[i] = saved.inst_id[i];
            }
        }
    }

    void trace_occluded16(const ValidMask16& valid, Ray16& rays,
                          const TraceOptions& options) const override {
        deactivate_unused_lanes(valid, rays);
        FilterContext context = static_context(false, options);
        rtcOccluded16(valid.lanes, m_static, &context.ctx, reinterpret_cast<RTCRay16*>(&rays));
        if (m_dyn.empty()) return;

        // Occluded lanes have tfar = -inf, so Embree's stream path already reads them as done.
        ValidMask16 open;
        bool any = false;
        for (uint32_t i = 0; i < 16; ++i) {
            open.lanes[i] =
                valid.lanes[i] && rays.tfar[i] != -std::numeric_limits<float>::infinity() ? -1 : 0;
            any |= open.lanes[i] != 0;
        }
        if (!any) return;
        FilterContext dynamic = dynamic_context(false, options);
        rtcOccluded16(open.lanes, m_dyn.scene(), &dynamic.ctx, reinterpret_cast<RTCRay16*>(&rays));
    }

private:
    /// The static tier's context: skips stale copies (while there are any) and applies the
    /// options.
    FilterContext static_context(bool coherent, const TraceOptions& options) const {
        return filter_context(coherent, *this, options, m_stale_count ? m_stale.data() : nullptr);
    }
    /// The dynamic tier's: applies the options, its instance ids read as slots through m_dyn.
    FilterContext dynamic_context(bool coherent, const TraceOptions& options) const {
        FilterContext c = filter_context(coherent, *this, options);
        c.slots = reinterpret_cast<const char*>(m_dyn.entries().data()) + offsetof(DynEntry, slot);
        c.slot_stride = sizeof(DynEntry);
        return c;
    }

    /// What the TLAS knows of one instance slot.
    struct Slot {
        uint32_t generation = 0;  ///< of the instance held
        bool held = false;
        bool keyed = false;    ///< the instance held has motion keys (counted in m_keyed)
        bool touched = false;  ///< listed in m_touched
        int32_t dyn = -1;      ///< index in the dynamic tier, -1 none
        uint64_t edited = 0;   ///< commit serial of the last edit
    };

    RTCScene new_scene(const TlasSceneSetup& setup) {
        RTCScene s = rtcNewScene(m_device.get());
        rtcSetSceneBuildQuality(s, RTCBuildQuality(setup.quality));
        rtcSetSceneFlags(s, RTCSceneFlags(setup.flags));
        return s;
    }

    void grow(uint32_t slot) {
        if (slot < m_slots.size()) return;
        m_slots.resize(slot + 1);
        m_stale.resize(slot + 1, 0);
    }

    RTCGeometry static_geometry(uint32_t slot) const {
        return slot < m_static_geoms.size() ? m_static_geoms[slot] : nullptr;
    }

    /// Whether the static tier holds a copy of the instance in `slot`.
    bool in_static(uint32_t slot) const {
        if (!m_array) return static_geometry(slot) != nullptr;
        return slot < m_table->size() && (*m_table)[slot].blas != nullptr;
    }

    /// Whether a full build of the static tier for `scene` makes an instance array.
    bool want_array(const Scene& scene) const {
        return scene.instances().size() >= m_policy.array_min_instances && m_keyed == 0;
    }

    void set_stale(uint32_t slot, bool stale) {
        if (bool(m_stale[slot]) == stale) return;
        m_stale[slot] = stale;
        if (stale) {
            ++m_stale_count;
        } else {
            --m_stale_count;
        }
    }

    /// Records an edit of `slot` since the static build: its static copy (if any) is stale.
    void touch(uint32_t slot) {
        Slot& s = m_slots[slot];
        s.edited = m_serial;
        if (!s.touched) {
            s.touched = true;
            m_touched.push_back(slot);
        }
        set_stale(slot, in_static(slot));
    }

    void hold(uint32_t slot, uint32_t generation, bool keyed) {
        Slot& s = m_slots[slot];
        if (!s.held) ++m_held;
        s.held = true;
        s.generation = generation;
        m_keyed += uint64_t(keyed) - uint64_t(s.keyed);
        s.keyed = keyed;
    }

    void drop(uint32_t slot) {
        Slot& s = m_slots[slot];
        if (s.held) --m_held;
        if (s.keyed) --m_keyed;
        s.held = false;
        s.keyed = false;
    }

    /// Brings the dynamic tier in line with the scene for `h` (the update path).
    void edit_dynamic(const Scene& scene, const BlasStore& blas, InstanceHandle h) {
        grow(h.index);
        Slot& s = m_slots[h.index];
        const auto inst = scene.instance(h);
        if (!inst) {
            if (!(s.held && s.generation == h.generation)) return;
            touch(h.index);
            remove_dynamic(h.index);
            drop(h.index);
            return;
        }
        const InstanceRecord& r = *inst.value();
        touch(h.index);
        hold(h.index, h.generation, !r.rare->world_motion.empty());
        if (r.world_visible) {
            put_dynamic(h.index, r, blas);
        } else {
            remove_dynamic(h.index);
        }
    }

    void put_dynamic(uint32_t slot, const InstanceRecord& r, const BlasStore& blas) {
        STRATA_CHECK(blas.scene(r.mesh.index) != nullptr);
        RTCScene blas_scene = instanced_scene(m_device, blas, slot, r);
        Slot& s = m_slots[slot];
        if (s.dyn < 0) s.dyn = int32_t(m_dyn.add(slot));
        m_dyn.set(uint32_t(s.dyn), blas_scene, r.world.m, r.rare->world_motion,
                  r.rare->world_interpolation, r.mask);
    }

    /// Takes `slot` out of the dynamic tier; the last entry moves into its index.
    void remove_dynamic(uint32_t slot) {
        Slot& s = m_slots[slot];
        if (s.dyn < 0) return;
        const auto id = uint32_t(s.dyn);
        m_dyn.remove(id);
        if (id < m_dyn.size()) m_slots[m_dyn.entries()[id].slot].dyn = int32_t(id);
        s.dyn = -1;
    }

    void attach_static(uint32_t slot, RTCGeometry g) {
        if (slot >= m_static_geoms.size()) m_static_geoms.resize(slot + 1, nullptr);
        STRATA_CHECK(m_static_geoms[slot] == nullptr);
        m_static_geoms[slot] = g;
        rtcAttachGeometryByID(m_static, g, slot);
        ++m_static_count;
    }

    /// Writes the instance in `slot` into the array.
    void put_static_entry(uint32_t slot, const InstanceEntry& e) {
        if (slot >= m_table->size()) m_table->resize(std::size_t(slot) + 1);
        m_static_count += uint64_t(e.blas != nullptr) - uint64_t((*m_table)[slot].blas != nullptr);
        (*m_table)[slot] = e;
    }

    void release_static(uint32_t slot) {
        if (m_array) {
            if (in_static(slot)) put_static_entry(slot, {});
            return;
        }
        RTCGeometry g = static_geometry(slot);
        if (!g) return;
        rtcDetachGeometry(m_static, slot);
        rtcReleaseGeometry(g);
        m_static_geoms[slot] = nullptr;
        --m_static_count;
    }

    /// Moves the dynamic tier into the static one and drops the stale copies, leaving every
    /// static geometry current; the caller commits. No merge may read the table meanwhile.
    void absorb_dynamic_tier() {
        cancel_merge();
        for (uint32_t slot : m_touched) {
            if (m_stale[slot]) release_static(slot);
            set_stale(slot, false);
            m_slots[slot].touched = false;
        }
        m_touched.clear();
        for (uint32_t id = 0; id < m_dyn.size(); ++id) {
            const DynEntry& d = m_dyn.entries()[id];
            if (m_array) {
                put_static_entry(d.slot, instance_entry(d.blas, d.transform, d.mask));
            } else {
                attach_static(d.slot, m_dyn.take_geometry(id));  // our reference moves over
            }
            m_slots[d.slot].dyn = -1;
        }
        m_dyn.clear();
    }

    /// Brings the static tier in line with the scene for `h`, editing geometries in place (the
    /// fallback and rebuild paths: no merge is running and the caller commits the static tier).
    void edit_static(const Scene& scene, const BlasStore& blas, InstanceHandle h) {
        grow(h.index);
        Slot& s = m_slots[h.index];
        const auto inst = scene.instance(h);
        if (s.held && (!inst || s.generation != h.generation)) {
            if (!inst && s.generation != h.generation) return;  // an older handle: nothing to do
            release_static(h.index);
            drop(h.index);
        }
        if (!inst) return;
        const InstanceRecord& r = *inst.value();
        hold(h.index, h.generation, !r.rare->world_motion.empty());
        s.edited = m_serial;
        if (!r.world_visible) {
            release_static(h.index);
            return;
        }
        STRATA_CHECK(blas.scene(r.mesh.index) != nullptr);
        RTCScene blas_scene = instanced_scene(m_device, blas, h.index, r);
        if (m_array) {
            put_static_entry(h.index, instance_entry(blas_scene, r.world.m, r.mask));
            return;
        }
        RTCGeometry g = static_geometry(h.index);
        if (!g) {
            g = rtcNewGeometry(m_device.get(), RTC_GEOMETRY_TYPE_INSTANCE);
            attach_static(h.index, g);
        }
        set_instance(g, blas_scene, r.world.m.data(), r.rare->world_motion,
                     r.rare->world_interpolation, r.mask);
    }

    /// The fallback: folds both tiers into the static one, applies `delta` to it in place and
    /// rebuilds it now, like the embree strategy does. When the scene's size or its motion keys
    /// call for the other kind of static tier, that is built afresh from the scene instead.
    void fold_into_static(const Scene& scene, const BlasStore& blas, const TlasDelta& delta) {
        if (want_array(scene) != m_array) {
            rebuild_static(scene, blas);
        } else {
            absorb_dynamic_tier();
            for (InstanceHandle h : delta.changed) edit_static(scene, blas, h);
            for (InstanceHandle h : delta.blas_changed) {
                if (holds(h)) edit_static(scene, blas, h);
            }
            // The edits may have brought motion keys in or taken the last ones out.
            if (want_array(scene) != m_array) rebuild_static(scene, blas);
        }
        commit_static();
        m_dyn.commit();
        m_static_serial = m_serial;
    }

    /// Builds the static tier from scratch from `scene`, as an instance array when want_array()
    /// says so, emptying the dynamic tier; the caller commits it (commit_static).
    void rebuild_static(const Scene& scene, const BlasStore& blas) {
        const bool array = want_array(scene);
        cancel_merge();
        release_everything();
        rtcReleaseScene(m_static);
        m_array = array;
        if (m_array) {
            m_table = std::make_shared<InstanceTable>();
            m_table->reserve(scene.instances().size());
            m_static = new_instance_array_scene(m_device.get(), m_static_setup, *m_table);
        } else {
            m_table.reset();
            m_static = new_scene(m_static_setup);
        }
        scene.instances().for_each(
            [&](InstanceHandle h, const InstanceRecord&) { edit_static(scene, blas, h); });
        // Motion keys showed up while writing the array: geometries instead.
        if (m_array && m_keyed) rebuild_static(scene, blas);
    }

    void commit_static() {
        if (m_array && m_static_count == 0) InstanceTable().swap(*m_table);  // frees its buffer
        if (m_array) update_instance_array_scene(m_static, *m_table);
        rtcCommitScene(m_static);
        account_table();
    }

    /// Counts the arrays' tables (the static tier's, the dynamic tier's) as TLAS memory (a
    /// replaced table is counted out when its successor comes in, though its thread may free it
    /// a little later).
    void account_table() {
        const auto bytes = int64_t(m_table ? m_table->capacity() * sizeof(InstanceEntry) : 0) +
                           m_dyn.table_bytes();
        m_device.account(MemoryCategory::Tlas, bytes - m_table_bytes);
        m_table_bytes = bytes;
    }

    /// Commits the dynamic tier if it changed and starts a merge if there is work for one.
    void finish_commit() {
        if (m_dyn.needs_commit()) {
            m_dyn.commit();
            account_table();
        }
        if (!m_policy.background_merge || m_merge || m_touched.empty()) return;
        // An array holds no motion keys: keyed instances stay in the dynamic tier until it
        // fills and the fallback builds geometries.
        if (m_array && m_keyed) return;
        std::vector<MergeEntry> entries;
        entries.reserve(m_touched.size());
        for (uint32_t slot : m_touched) {
            MergeEntry e;
            e.slot = slot;
            const Slot& s = m_slots[slot];
            if (s.dyn >= 0) {
                const DynEntry& d = m_dyn.entries()[std::size_t(s.dyn)];
                e.blas = d.blas;
                e.transform = d.transform;
                e.keys = d.keys;
                e.interpolation = d.interpolation;
                e.mask = d.mask;
            }
            entries.push_back(e);
        }
        if (m_array) {
            m_merge = std::make_unique<TlasMerge>(m_device, m_arena, m_static_setup,
                                                  std::shared_ptr<const InstanceTable>(m_table),
                                                  std::move(entries), m_serial);
        } else {
            m_merge = std::make_unique<TlasMerge>(m_device, m_arena, m_static_setup,
                                                  m_static_geoms, std::move(entries), m_serial);
        }
    }

    void cancel_merge() {
        if (!m_merge) return;
        TlasMemoryScope memory(m_device);
        if (!m_merge->done()) m_report.merge_cancelled = true;
        m_merge.reset();
    }

    /// Waits for the merge under way, if any, and swaps it in.
    void finish_merge_now() {
        if (!m_merge) return;
        m_merge->join();
        swap_finished_merge();
    }

    /// Swaps in a finished merge: its static tier replaces the current one, and the instances
    /// not edited since the merge started leave the dynamic tier.
    void swap_finished_merge() {
        if (!m_merge || !m_merge->done()) return;
        TlasMemoryScope memory(m_device);
        m_merge->join();
        if (!m_merge->succeeded()) {
            m_merge.reset();
            return;
        }
        const uint64_t serial = m_merge->serial();
        if (m_array) {
            swap_in_array();
        } else {
            swap_in_geometries();
        }
        m_static_serial = serial;

        // Step: instances the new static tier covers leave the dynamic tier.
        for (const MergeEntry& e : m_merge->entries()) {
            Slot& s = m_slots[e.slot];
            if (s.edited <= serial) {
                remove_dynamic(e.slot);
                set_stale(e.slot, false);
                s.touched = false;
            } else {
                set_stale(e.slot, in_static(e.slot));
            }
        }
        m_touched.erase(std::remove_if(m_touched.begin(), m_touched.end(),
                                       [&](uint32_t slot) { return !m_slots[slot].touched; }),
                        m_touched.end());
        m_report.merge_swapped = true;
        m_report.merge_build_ms = m_merge->build_ms();
        m_merge.reset();
    }

    /// The merge's static tier of geometries replaces the current one. Geometries of unedited
    /// instances are shared with the old table (one reference between them); the ones the
    /// merge replaced or dropped go with the old scene. Releasing that scene drops a reference
    /// per instance and frees its BVH: O(all instances), so a thread of its own does it.
    void swap_in_geometries() {
        std::vector<RTCGeometry> geoms;
        RTCScene scene = m_merge->take_scene(geoms);
        std::vector<RTCGeometry> replaced;
        for (const MergeEntry& e : m_merge->entries()) {
            RTCGeometry old = static_geometry(e.slot);
            RTCGeometry now = geoms[e.slot];
            m_static_count += uint64_t(now != nullptr) - uint64_t(old != nullptr);
            if (old && old != now) replaced.push_back(old);
        }
        retire(m_static, std::move(replaced), std::move(m_static_geoms), nullptr);
        m_static = scene;
        m_static_geoms = std::move(geoms);
        if (m_static_geoms.size() > m_slots.size()) grow(uint32_t(m_static_geoms.size() - 1));
    }

    /// The merge's instance array replaces the current one (the old scene and table are
    /// released on a thread of their own, as above).
    void swap_in_array() {
        std::shared_ptr<InstanceTable> table;
        RTCScene scene = m_merge->take_scene(table);
        for (const MergeEntry& e : m_merge->entries())
            m_static_count += uint64_t(e.blas != nullptr) - uint64_t(in_static(e.slot));
        retire(m_static, {}, {}, std::move(m_table));
        m_static = scene;
        m_table = std::move(table);
        account_table();
        if (m_table->size() > m_slots.size()) grow(uint32_t(m_table->size() - 1));
    }

    /// Releases a replaced static tier on a thread of its own. The commit never waits for one:
    /// finished ones are joined at the next swap, the rest when the TLAS goes or a test waits.
    void retire(RTCScene scene, std::vector<RTCGeometry> geoms, std::vector<RTCGeometry> table,
                std::shared_ptr<InstanceTable> array) {
        reap_retired(false);
        auto done = std::make_shared<std::atomic<bool>>(false);
        std::thread t([&device = m_device, scene, done, geoms = std::move(geoms),
                       table = std::move(table), array = std::move(array)]() mutable {
            {
                TlasMemoryScope memory(device);
                for (RTCGeometry g : geoms) rtcReleaseGeometry(g);
                rtcReleaseScene(scene);
            }
            array.reset();  // after the scene that read it
            done->store(true, std::memory_order_release);
            (void)table;  // freed here too
        });
        m_retiring.push_back({std::move(t), std::move(done)});
    }

    /// Joins the release threads that finished (all of them with `all`).
    void reap_retired(bool all) {
        for (auto it = m_retiring.begin(); it != m_retiring.end();) {
            if (all || it->done->load(std::memory_order_acquire)) {
                it->thread.join();
                it = m_retiring.erase(it);
            } else {
                ++it;
            }
        }
    }

    void release_everything() {
        m_dyn.clear();
        if (!m_array) {
            for (uint32_t slot = 0; slot < m_static_geoms.size(); ++slot) release_static(slot);
        }
        m_static_geoms.clear();
        if (m_table) m_table->clear();
        m_slots.clear();
        m_stale.clear();
        m_touched.clear();
        m_held = m_static_count = m_stale_count = m_keyed = 0;
    }

    EmbreeDevice& m_device;
    TlasPolicy m_policy;
    TlasSceneSetup m_static_setup;
    DynamicTier m_dyn;

    std::vector<Slot> m_slots;  ///< by instance slot
    uint64_t m_held = 0;
    uint64_t m_serial = 0;  ///< commits that changed the TLAS

    RTCScene m_static = nullptr;
    std::vector<RTCGeometry> m_static_geoms;  ///< by slot; read by a running merge
    bool m_array = false;  ///< the static tier is an instance array over m_table, not geometries
    std::shared_ptr<InstanceTable> m_table;  ///< by slot (array); read by a running merge
    int64_t m_table_bytes = 0;               ///< of m_table, counted as TLAS memory
    uint64_t m_keyed = 0;                    ///< held instances with motion keys
    uint64_t m_static_count = 0;
    uint64_t m_static_serial = 0;  ///< the edits the static tier covers
    std::vector<uint8_t> m_stale;  ///< by slot; read by the static tier's filter
    uint64_t m_stale_count = 0;
    std::vector<uint32_t> m_touched;  ///< slots edited since the static build

    MergeArena m_arena{m_device};  ///< before m_merge: outlives every merge
    std::unique_ptr<TlasMerge> m_merge;
    struct Retiring {
        std::thread thread;
        std::shared_ptr<std::atomic<bool>> done;
    };
    std::vector<Retiring> m_retiring;  ///< releasing static tiers that merges replaced
    TlasTiers m_report;                ///< this commit's flags
};

}  // namespace

std::unique_ptr<TlasStrategy> make_incremental_tlas(EmbreeDevice& device, BuildPreference prefer,
                                                    bool watertight, const TlasPolicy& policy) {
    return std::make_unique<IncrementalTlas>(device, prefer, watertight, policy);
}

}  // namespace strata
