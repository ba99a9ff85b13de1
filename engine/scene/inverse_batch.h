#pragma once
// The inverse of an applied batch: the edits that take it back, for the undo history
// (edit_history.h). Built from the batch's undo log (undo_log.h) right after the batch applied,
// against the scene it left: each record that says what a change overwrote becomes the edit that
// writes it back (an added object is removed, a removed one added again with everything it held,
// an update sets the old values), in reverse order, so the inverse walks back through the same
// states and every rule it meets passes.
//
// Applied to the scene the batch left, the inverse gives a scene equal to the one before it,
// object for object and field for field. What it does not give back: slots and handles (an object
// added again gets a new handle), the order of a group's children where an object left and came
// back (it joins at the end, as after a snapshot), and dirty bits (the inverse marks what it
// changes, and the next commit does that work).

#include "engine/scene/edits.h"

namespace strata {

class Scene;
struct UndoLog;

/// The inverse of the batch whose undo log is `log`, on the scene `scene` that batch left. Takes
/// the log's arrays (a removed mesh's vertices move into its add_mesh, copied only while shared).
EditBatch inverse_batch(UndoLog&& log, const Scene& scene);

}  // namespace strata
