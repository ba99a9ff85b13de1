// Packing runs of single instance edits into bulk edits (bulk_packing.h).

#include "engine/scene/bulk_packing.h"

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace strata {

namespace {

/// Whether `e` can join a bulk add whose items have `parent`, `visible` and (`with_material`)
/// a material: only the fields a bulk add carries per edit or per item may differ.
bool joins(const AddInstance& e, const std::optional<std::string>& parent, bool visible,
           bool with_material) {
    static const AddInstance defaults{};
    return e.parent == parent && e.visible == visible &&
           e.material.has_value() == with_material && e.mask == defaults.mask &&
           e.user_id == defaults.user_id && e.name.empty() && e.motion.empty();
}

/// Appends one item to a per-item array that may still hold one value for its `n` items.
void push_item(std::vector<std::string>& v, std::size_t n, std::string&& value) {
    if (v.size() == 1) {
        if (v[0] == value) return;
        v.assign(n, v[0]);
    }
    v.push_back(std::move(value));
}

AddInstances bulk_of(AddInstance&& e) {
    AddInstances bulk;
    bulk.ids.list.push_back(std::move(e.id));
    bulk.meshes.push_back(std::move(e.mesh));
    if (e.material) bulk.materials.push_back(std::move(*e.material));
    bulk.transforms.push_back(e.transform);
    bulk.parent = std::move(e.parent);
    bulk.visible = e.visible;
    return bulk;
}

/// The decimal number `digits` spells in canonical form (no sign, no leading zero but "0" itself,
/// below 10^19), or nullopt.
std::optional<uint64_t> canonical_number(std::string_view digits) {
    if (digits.empty() || digits.size() > 19 || (digits[0] == '0' && digits.size() > 1))
        return std::nullopt;
    uint64_t n = 0;
    for (char c : digits) {
        if (c < '0' || c > '9') return std::nullopt;
        n = n * 10 + uint64_t(c - '0');
    }
    return n;
}

/// When the listed ids are, in some order (ascending when `ascending`), exactly `prefix` followed
/// by each number of [first, first + n), rewrites them as that range and returns, for each
/// position of the range, the list position it came from; otherwise leaves them and returns
/// nothing.
std::optional<std::vector<uint32_t>> to_range(BulkIds& ids, bool ascending) {
    const std::vector<std::string>& list = ids.list;
    if (list.size() < 2) return std::nullopt;
    std::size_t cut = list[0].size();
    while (cut > 0 && list[0][cut - 1] >= '0' && list[0][cut - 1] <= '9') --cut;
    const std::string_view prefix = std::string_view(list[0]).substr(0, cut);
    std::vector<uint64_t> numbers(list.size());
    uint64_t lo = std::numeric_limits<uint64_t>::max();
    uint64_t hi = 0;
    for (std::size_t i = 0; i < list.size(); ++i) {
        const std::string_view id = list[i];
        if (id.substr(0, cut) != prefix) return std::nullopt;
        const std::optional<uint64_t> n = canonical_number(id.substr(cut));
        if (!n) return std::nullopt;
        if (ascending && i > 0 && *n != numbers[i - 1] + 1) return std::nullopt;
        numbers[i] = *n;
        lo = std::min(lo, *n);
        hi = std::max(hi, *n);
    }
    if (hi - lo + 1 != list.size()) return std::nullopt;
    constexpr uint32_t NONE = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> order(list.size(), NONE);
    for (std::size_t i = 0; i < list.size(); ++i) {
        uint32_t& slot = order[numbers[i] - lo];
        if (slot != NONE) return std::nullopt;  // an id listed twice
        slot = static_cast<uint32_t>(i);
    }
    BulkIds range;
    range.prefix = std::string(prefix);
    range.first = lo;
    range.count = list.size();
    ids = std::move(range);
    return order;
}

/// `v` in range order, when it holds one value per item.
template <class T>
void permute(std::vector<T>& v, const std::vector<uint32_t>& order) {
    if (v.size() != order.size()) return;
    std::vector<T> out;
    out.reserve(v.size());
    for (uint32_t i : order) out.push_back(std::move(v[i]));
    v = std::move(out);
}

}  // namespace

void append_add_instance(EditBatch& out, AddInstance&& e) {
    Edit* last = out.edits.empty() ? nullptr : &out.edits.back();
    if (auto* one = last ? std::get_if<AddInstance>(last) : nullptr;
        one && joins(*one, e.parent, e.visible, e.material.has_value()) &&
        joins(e, one->parent, one->visible, one->material.has_value())) {
        *last = bulk_of(std::move(*one));
    }
    auto* bulk = last ? std::get_if<AddInstances>(last) : nullptr;
    if (!bulk || bulk->ids.list.size() >= MAX_BULK_ITEMS ||
        !joins(e, bulk->parent, bulk->visible, !bulk->materials.empty())) {
        out.edits.emplace_back(std::move(e));
        return;
    }
    const std::size_t n = bulk->ids.list.size();
    bulk->ids.list.push_back(std::move(e.id));
    push_item(bulk->meshes, n, std::move(e.mesh));
    if (e.material) push_item(bulk->materials, n, std::move(*e.material));
    bulk->transforms.push_back(e.transform);
}

void compact_ids(Edit& e, IdOrder order_rule) {
    const bool keep = order_rule == IdOrder::Kept;
    if (auto* add = std::get_if<AddInstances>(&e)) {
        if (auto order = to_range(add->ids, keep)) {
            permute(add->meshes, *order);
            permute(add->materials, *order);
            permute(add->transforms, *order);
        }
    } else if (auto* update = std::get_if<UpdateInstances>(&e)) {
        if (auto order = to_range(update->ids, keep)) permute(update->transforms, *order);
    } else if (auto* remove = std::get_if<RemoveInstances>(&e)) {
        to_range(remove->ids, keep);
    }
}

}  // namespace strata
