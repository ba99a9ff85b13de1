#pragma once
// The scene's history: an entry per applied version (what kind of batch, when, the client's
// message, how many edits of each kind), and the undo and redo stacks.
//
// Undo takes back the newest batch still on the undo stack by applying its inverse
// (inverse_batch.h) as a new version; redo applies the inverse of that undo, which is the batch
// again. The stacks are a function of the applied batches alone, each tagged with its BatchInfo:
//   - an edit batch pushes its inverse on the undo stack and empties the redo stack;
//   - an undo of version v pops v from the undo stack and pushes the undo's own inverse (which
//     redoes v) on the redo stack;
//   - a redo of version v pops v from the redo stack and pushes the redo's inverse (which undoes
//     it) on the undo stack, under the redo's own version.
// So a journal replayed after a restart, or a shared log followed by replicas, rebuilds the same
// stacks, back to the scene the replay started from (a snapshot: its history is not kept).
//
// Bounded: at most `max_undo` batches on each stack and `max_bytes` held by both; the oldest undo
// entries go first (an inverse larger than the whole budget empties the undo stack: what came
// before it cannot be undone without it), then the oldest redo entries.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/scene/edits.h"

namespace strata {

struct HistoryLimits {
    std::size_t max_entries = 10000;    ///< versions listed by history()
    std::size_t max_undo = 100;         ///< batches on each of the undo and redo stacks
    uint64_t max_bytes = 256ull << 20;  ///< held by the inverse batches of both stacks
};

/// One applied version.
struct HistoryEntry {
    uint64_t version = 0;
    BatchInfo info;
    uint32_t edits = 0;
    /// Edits per kind: (Edit variant index, count), in index order.
    std::vector<std::pair<uint8_t, uint32_t>> ops;
};

/// A page of history() and where the stacks stand.
struct HistoryPage {
    std::vector<HistoryEntry> entries;  ///< newest first
    /// Of each entry: whether an undo would take it back now or after undoing newer ones.
    std::vector<bool> undoable;
    uint64_t oldest = 0;  ///< the oldest version the history still lists (0: none)
    std::size_t undo_depth = 0;
    std::size_t redo_depth = 0;
    uint64_t next_undo = 0;   ///< the version POST /v1/undo takes back (0: none)
    uint64_t next_redo = 0;   ///< the version POST /v1/redo redoes (0: none)
    uint64_t held_bytes = 0;  ///< by both stacks
};

/// A history as data: what a snapshot keeps of it (engine/durable/history_file.h), so that undo
/// reaches past the snapshot after a restart.
struct HistoryState {
    /// A batch on a stack, with the version it undoes (undo stack) or redoes (redo stack).
    /// Shared with the history, immutable: taking the state copies pointers, not batches (a
    /// snapshot takes it under the scene lock).
    struct Step {
        uint64_t version = 0;
        std::shared_ptr<const EditBatch> batch;
    };
    std::vector<HistoryEntry> entries;  ///< oldest first
    std::vector<Step> undo;             ///< oldest first: the next to undo is the last
    std::vector<Step> redo;             ///< the next to redo is the last
};

/// Edit counts of a batch, per kind (for HistoryEntry::ops).
std::vector<std::pair<uint8_t, uint32_t>> count_ops(const EditBatch& batch);

/// About what an edit batch holds in memory, arrays and strings included.
uint64_t approx_bytes(const EditBatch& batch);

class EditHistory {
public:
    explicit EditHistory(const HistoryLimits& limits = {}) : m_limits(limits) {}

    /// Records version `version`, produced by a batch with `info` and `ops`, whose inverse is
    /// `inverse` (see the stack rules above).
    void record(uint64_t version, const BatchInfo& info,
                std::vector<std::pair<uint8_t, uint32_t>> ops, EditBatch&& inverse);

    /// The batch an undo applies now (a copy of the top inverse, tagged Undo with its target),
    /// or nullopt when the undo stack is empty.
    std::optional<EditBatch> undo_batch() const;
    /// The same for redo.
    std::optional<EditBatch> redo_batch() const;

    /// Up to `limit` entries older than version `before` (0: from the newest), newest first.
    HistoryPage page(std::size_t limit, uint64_t before) const;

    /// Forgets everything (the scene was replaced).
    void clear();

    /// Everything it holds, as data.
    HistoryState state() const;
    /// Replaces what it holds with `state` (within this history's limits: the oldest entries
    /// and steps beyond them go).
    void restore(HistoryState&& state);

private:
    struct Step {
        uint64_t version = 0;  ///< the version it undoes (undo stack) or redoes (redo stack)
        std::shared_ptr<const EditBatch> batch;  ///< never null
        uint64_t bytes = 0;
    };
    void push_undo(Step&& step);
    void push_redo(Step&& step);
    void trim();
    static std::optional<EditBatch> tagged(const std::deque<Step>& stack, BatchKind kind);

    HistoryLimits m_limits;
    std::deque<HistoryEntry> m_entries;
    std::deque<Step> m_undo;  ///< newest at the back
    std::deque<Step> m_redo;  ///< next to redo at the back
    uint64_t m_bytes = 0;
};

}  // namespace strata
