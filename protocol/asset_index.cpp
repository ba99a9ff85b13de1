#include "protocol/asset_index.h"

#include <algorithm>
#include <unordered_map>

#include "protocol/framing.h"

namespace strata::protocol {

namespace {

/// Finds the asset that owns an id: the asset ids by their text, pointing into the scene's
/// group records (valid while the scene is read).
class Owners {
public:
    /// Every asset of `s`, or only `only` (and the longer asset ids below it, which own their
    /// part of its prefix) when given.
    Owners(const Scene& s, std::optional<std::string_view> only) {
        s.groups().for_each([&](GroupHandle h, const GroupRecord& g) {
            if (g.asset.empty()) return;
            if (only && g.id != *only && !below(g.id, *only)) return;
            m_ids.emplace(std::string_view(g.id), h);
        });
        m_only = only;
    }

    bool empty() const { return m_ids.empty(); }

    /// The asset group that owns `id`: the longest asset id that is `id` itself (an asset's own
    /// group) or a prefix of it followed by '.'; null when none. With `only`, objects of other
    /// assets are skipped before any lookup.
    GroupHandle owner(std::string_view id) const {
        if (m_only && id != *m_only && !below(id, *m_only)) return {};
        if (const auto it = m_ids.find(id); it != m_ids.end()) return it->second;
        for (std::size_t dot = id.rfind('.'); dot != std::string_view::npos && dot > 0;
             dot = id.rfind('.', dot - 1)) {
            if (const auto it = m_ids.find(id.substr(0, dot)); it != m_ids.end())
                return it->second;
        }
        return {};
    }

    const std::unordered_map<std::string_view, GroupHandle>& ids() const { return m_ids; }

private:
    /// True when `id` begins with `prefix` and a '.'.
    static bool below(std::string_view id, std::string_view prefix) {
        return id.size() > prefix.size() && id[prefix.size()] == '.' &&
               id.substr(0, prefix.size()) == prefix;
    }

    std::unordered_map<std::string_view, GroupHandle> m_ids;
    std::optional<std::string_view> m_only;
};

/// Sorts every object of the scene into the asset that owns it.
std::map<std::string, AssetContents> collect(const Scene& s, std::optional<std::string_view> only) {
    const Owners owners(s, only);
    std::map<std::string, AssetContents> out;
    if (owners.empty()) return out;
    std::unordered_map<uint32_t, AssetContents*> by_slot;  // asset group slot -> its contents
    for (const auto& [id, h] : owners.ids()) {
        AssetContents& a = out[std::string(id)];
        a.group = h;
        a.groups.push_back(h);
        by_slot[h.index] = &a;
    }
    const auto place = [&](std::string_view id, auto handle, auto member) {
        const GroupHandle g = owners.owner(id);
        if (g.is_null()) return;
        (by_slot.at(g.index)->*member).push_back(handle);
    };
    s.textures().for_each([&](TextureHandle h, const TextureRecord& r) {
        place(r.id, h, &AssetContents::textures);
    });
    s.materials().for_each([&](MaterialHandle h, const MaterialRecord& r) {
        place(r.id, h, &AssetContents::materials);
    });
    s.meshes().for_each(
        [&](MeshHandle h, const MeshRecord& r) { place(r.id, h, &AssetContents::meshes); });
    s.groups().for_each([&](GroupHandle h, const GroupRecord& r) {
        if (!r.asset.empty() && owners.ids().count(r.id) != 0) return;  // listed first already
        place(r.id, h, &AssetContents::groups);
    });
    s.instances().for_each([&](InstanceHandle h, const InstanceRecord& r) {
        place(r.id, h, &AssetContents::instances);
    });
    if (only) {
        for (auto it = out.begin(); it != out.end();)
            it = it->first == *only ? std::next(it) : out.erase(it);
    }
    return out;
}

/// Groups from the root down to `g`, `g` included.
uint32_t depth_of(const Scene& s, GroupHandle g) {
    uint32_t depth = 0;
    for (; !g.is_null(); g = s.groups().at(g).parent) ++depth;
    return depth;
}

template <class H, class Records>
Json ids_of(const std::vector<H>& handles, const Records& records) {
    Json out = Json::array();
    for (H h : handles) out.push_back(records.at(h).id);
    return out;
}

}  // namespace

std::map<std::string, AssetContents> scene_assets(const Scene& s) {
    return collect(s, std::nullopt);
}

std::optional<AssetContents> find_asset(const Scene& s, std::string_view id) {
    const auto g = s.group(s.find_group(id));
    if (!g || g.value()->asset.empty()) return std::nullopt;
    auto all = collect(s, id);
    return std::move(all.begin()->second);
}

Json asset_to_json(const Scene& s, const AssetContents& a, bool ids) {
    const GroupRecord& g = s.groups().at(a.group);
    InstanceBounds world(s);
    Bounds3 bounds;
    for (InstanceHandle h : a.instances) bounds.extend(world(s.instances().at(h)));
    Json out = {{"id", g.id}, {"file", g.asset}};
    if (!g.name.empty()) out["name"] = g.name;
    out["counts"] = {{"textures", a.textures.size()},   {"materials", a.materials.size()},
                     {"meshes", a.meshes.size()},       {"groups", a.groups.size()},
                     {"instances", a.instances.size()}};
    out["bounds"] = bounds_to_json(bounds);
    if (ids) {
        out["textures"] = ids_of(a.textures, s.textures());
        out["materials"] = ids_of(a.materials, s.materials());
        out["meshes"] = ids_of(a.meshes, s.meshes());
        out["groups"] = ids_of(a.groups, s.groups());
        out["instances"] = ids_of(a.instances, s.instances());
    }
    return out;
}

std::vector<Edit> removal_edits(const Scene& s, const AssetContents& a,
                                std::vector<std::string>& edit_ids) {
    std::vector<Edit> edits;
    const auto add = [&](Edit&& e, const std::string& id) {
        edits.push_back(std::move(e));
        edit_ids.push_back(id);
    };
    // Instances in bulk edits (one per MAX_BULK_ITEMS).
    for (std::size_t begin = 0; begin < a.instances.size(); begin += MAX_BULK_ITEMS) {
        const std::size_t end = std::min<std::size_t>(a.instances.size(), begin + MAX_BULK_ITEMS);
        RemoveInstances e;
        for (std::size_t i = begin; i < end; ++i)
            e.ids.list.push_back(s.instances().at(a.instances[i]).id);
        const std::string label = end - begin == 1 ? e.ids.list.front() : "its instances";
        add(std::move(e), label);
    }
    // Deepest first, so that each group is empty when its turn comes; the asset's own group
    // (shallowest of its groups unless moved below one of them) goes last.
    std::vector<std::pair<uint32_t, GroupHandle>> groups;
    for (GroupHandle h : a.groups)
        if (!(h == a.group)) groups.emplace_back(depth_of(s, h), h);
    std::stable_sort(groups.begin(), groups.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    groups.emplace_back(0, a.group);
    for (const auto& [depth, h] : groups) {
        const std::string& id = s.groups().at(h).id;
        add(RemoveGroup{id, false}, id);
    }
    for (MeshHandle h : a.meshes) add(RemoveMesh{s.meshes().at(h).id}, s.meshes().at(h).id);
    for (MaterialHandle h : a.materials)
        add(RemoveMaterial{s.materials().at(h).id}, s.materials().at(h).id);
    for (TextureHandle h : a.textures)
        add(RemoveTexture{s.textures().at(h).id}, s.textures().at(h).id);
    return edits;
}

}  // namespace strata::protocol
