#pragma once
// Packing runs of single instance edits into bulk edits (AddInstances and friends), for batches
// the engine writes itself: inverses in the undo history (inverse_batch.h) and snapshots
// (SceneImage::to_batch). A bulk edit applies its items in order, with the rules of the single
// edits, so a packed batch has the same effect as the one it packs.

#include "engine/scene/edits.h"

namespace strata {

/// Appends `e` to `out`, joining it to the AddInstance or AddInstances at the end of `out` when
/// the fields a bulk add carries per edit or per item are all it differs in (up to
/// MAX_BULK_ITEMS items).
void append_add_instance(EditBatch& out, AddInstance&& e);

/// Whether a bulk edit's items may be reordered to make its ids a numbered range.
enum class IdOrder : uint8_t {
    Kept,  ///< the order decides slots and child order, which must be kept (snapshots)
    Free,  ///< any order has the same effect that matters (inverses)
};

/// Rewrites the listed ids of a bulk edit (`e` of another kind is left alone) as a numbered range
/// `{prefix, first, count}` when they are exactly one: in any order with IdOrder::Free (per-item
/// arrays reordered to match), in ascending order only with IdOrder::Kept. A million ids then
/// take a few bytes.
void compact_ids(Edit& e, IdOrder order);

}  // namespace strata
