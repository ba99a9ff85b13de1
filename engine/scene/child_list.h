#pragma once
// The child lists of the scene graph (Children in scene.h): removal swaps the last child into the
// hole and fixes its `child_slot`, and its undo puts both back exactly, so a refused batch leaves
// every list in its old order (the order /v1/scene/groups/{id}/children pages through).

#include <cstdint>
#include <vector>

#include "engine/core/handle.h"

namespace strata {

/// Removes child number `slot` of `list`; the last child takes its place.
template <class H, class Records>
void detach_child(std::vector<H>& list, Records& records, uint32_t slot) {
    const H last = list.back();
    list[slot] = last;
    records.at(last).child_slot = slot;
    list.pop_back();
}

/// Undoes detach_child(list, records, slot) of `h` (the caller restores `h`'s own child_slot).
template <class H, class Records>
void undo_detach_child(std::vector<H>& list, Records& records, H h, uint32_t slot) {
    if (slot == list.size()) {
        list.push_back(h);
        return;
    }
    const H moved = list[slot];
    records.at(moved).child_slot = static_cast<uint32_t>(list.size());
    list.push_back(moved);
    list[slot] = h;
}

}  // namespace strata
