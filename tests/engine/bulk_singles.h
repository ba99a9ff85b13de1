#pragma once
// The single edits a bulk instance edit stands for (edits.h: AddInstances, UpdateInstances,
// RemoveInstances): what the bulk tests and the edit-batch fuzzer apply beside the bulk edit to
// check that both paths leave the same scene.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/scene/edits.h"

namespace strata::test {

/// Whether a bulk edit's arrays fit its ids (what its rule checks first); a misshapen bulk edit
/// has no single-edit twin.
template <class E>
bool well_shaped(const E& e) {
    if (!e.ids.list.empty() && e.ids.count != 0) return false;
    if (e.ids.size() > 4096) return false;  // no range that only the budget refuses
    if (e.ids.list.empty() && e.ids.first + e.ids.count < e.ids.first) return false;
    const std::size_t n = e.ids.size();
    if (n == 0) return false;  // the rule still checks the mesh, material and parent it names
    if constexpr (requires { e.meshes; }) {
        if (e.meshes.size() != n && e.meshes.size() != 1) return false;
        if (e.materials.size() != n && e.materials.size() > 1) return false;
    }
    if constexpr (requires { e.visible.has_value(); }) {
        if (e.transforms.empty() && !e.visible) return false;
    }
    if constexpr (requires { e.transforms; }) {
        if (!e.transforms.empty() && e.transforms.size() != n) return false;
    }
    return true;
}

inline std::vector<Edit> singles(const AddInstances& e) {
    std::vector<Edit> out;
    for (std::size_t i = 0; i < e.ids.size(); ++i) {
        AddInstance a;
        a.id = e.ids.at(i);
        a.mesh = e.meshes.size() == 1 ? e.meshes[0] : e.meshes[i];
        if (!e.materials.empty())
            a.material = e.materials.size() == 1 ? e.materials[0] : e.materials[i];
        if (!e.transforms.empty()) a.transform = e.transforms[i];
        a.visible = e.visible;
        a.parent = e.parent;
        out.emplace_back(std::move(a));
    }
    return out;
}
inline std::vector<Edit> singles(const UpdateInstances& e) {
    std::vector<Edit> out;
    for (std::size_t i = 0; i < e.ids.size(); ++i) {
        UpdateInstance u;
        u.instance = e.ids.at(i);
        if (!e.transforms.empty()) u.transform = e.transforms[i];
        u.visible = e.visible;
        out.emplace_back(std::move(u));
    }
    return out;
}
inline std::vector<Edit> singles(const RemoveInstances& e) {
    std::vector<Edit> out;
    for (std::size_t i = 0; i < e.ids.size(); ++i) out.emplace_back(RemoveInstance{e.ids.at(i)});
    return out;
}

/// `edits` with every bulk edit replaced by its single edits, or nullopt when a bulk edit is
/// misshapen (its rule refuses it before any item).
inline std::optional<std::vector<Edit>> with_singles(const std::vector<Edit>& edits) {
    std::vector<Edit> out;
    for (const Edit& edit : edits) {
        const bool ok = std::visit(
            [&](const auto& e) {
                if constexpr (requires { e.ids; }) {
                    if (!well_shaped(e)) return false;
                    for (Edit& s : singles(e)) out.push_back(std::move(s));
                } else {
                    out.push_back(e);
                }
                return true;
            },
            edit);
        if (!ok) return std::nullopt;
    }
    return out;
}

}  // namespace strata::test
