// The scene's history and its undo and redo stacks (edit_history.h).

#include "engine/scene/edit_history.h"

#include <algorithm>
#include <array>
#include <unordered_set>

namespace strata {

namespace {

template <class T>
uint64_t bytes_of(const std::vector<T>& v) {
    return v.size() * sizeof(T);
}
template <class T>
uint64_t bytes_of(const std::optional<std::vector<T>>& v) {
    return v ? bytes_of(*v) : 0;
}

uint64_t strings_bytes(const std::vector<std::string>& v) {
    uint64_t bytes = bytes_of(v);
    for (const std::string& s : v) bytes += s.capacity() > 15 ? s.capacity() : 0;
    return bytes;
}
uint64_t ids_bytes(const BulkIds& ids) {
    return strings_bytes(ids.list) + ids.prefix.size();
}

/// The bytes of a mesh edit's optional vertex attributes.
template <class E>
uint64_t attribute_bytes(const E& e) {
    uint64_t bytes = 0;
    for_each_vertex_attribute([&](auto a) { bytes += bytes_of(decltype(a)::of(e)); });
    return bytes;
}

/// The heap bytes of one edit beyond its struct: its arrays and its encoded image.
struct ArrayBytes {
    uint64_t operator()(const AddMesh& e) const {
        return bytes_of(e.positions) + bytes_of(e.triangles) + bytes_of(e.strands) +
               attribute_bytes(e);
    }
    uint64_t operator()(const UpdateMeshPositions& e) const {
        return bytes_of(e.positions) + attribute_bytes(e);
    }
    uint64_t operator()(const UpdateMeshVertices& e) const {
        return bytes_of(e.vertices) + bytes_of(e.positions);
    }
    uint64_t operator()(const ReplaceMeshTriangles& e) const { return bytes_of(e.triangles); }
    uint64_t operator()(const ReplaceMeshTopology& e) const {
        return bytes_of(e.positions) + bytes_of(e.triangles) + bytes_of(e.strands) +
               attribute_bytes(e);
    }
    uint64_t operator()(const AddTexture& e) const { return e.data.size(); }
    uint64_t operator()(const AddInstances& e) const {
        return ids_bytes(e.ids) + bytes_of(e.transforms) + strings_bytes(e.meshes) +
               strings_bytes(e.materials);
    }
    uint64_t operator()(const UpdateInstances& e) const {
        return ids_bytes(e.ids) + bytes_of(e.transforms);
    }
    uint64_t operator()(const RemoveInstances& e) const { return ids_bytes(e.ids); }
    uint64_t operator()(const AddInstance& e) const { return bytes_of(e.motion); }
    uint64_t operator()(const UpdateInstance& e) const { return bytes_of(e.motion); }
    template <class E>
    uint64_t operator()(const E&) const {
        return 0;
    }
};

}  // namespace

std::vector<std::pair<uint8_t, uint32_t>> count_ops(const EditBatch& batch) {
    std::array<uint32_t, std::variant_size_v<Edit>> counts{};
    for (const Edit& e : batch.edits) ++counts[e.index()];
    std::vector<std::pair<uint8_t, uint32_t>> out;
    for (std::size_t i = 0; i < counts.size(); ++i)
        if (counts[i]) out.emplace_back(uint8_t(i), counts[i]);
    return out;
}

uint64_t approx_bytes(const EditBatch& batch) {
    // Ids and names are short; a fixed allowance per edit covers them.
    constexpr uint64_t PER_EDIT = sizeof(Edit) + 64;
    uint64_t bytes = sizeof(EditBatch) + batch.info.message.size();
    for (const Edit& e : batch.edits) bytes += PER_EDIT + std::visit(ArrayBytes{}, e);
    return bytes;
}

void EditHistory::record(uint64_t version, const BatchInfo& info,
                         std::vector<std::pair<uint8_t, uint32_t>> ops, EditBatch&& inverse) {
    HistoryEntry entry{version, info, 0, std::move(ops)};
    for (const auto& [kind, n] : entry.ops) entry.edits += n;
    m_entries.push_back(std::move(entry));
    while (m_entries.size() > m_limits.max_entries) m_entries.pop_front();

    Step step{version, std::make_shared<const EditBatch>(std::move(inverse)), 0};
    step.bytes = approx_bytes(*step.batch);
    switch (info.kind) {
        case BatchKind::Edits:
            for (const Step& s : m_redo) m_bytes -= s.bytes;
            m_redo.clear();
            push_undo(std::move(step));
            break;
        case BatchKind::Undo:
            // A history that starts later (a replica that began from a snapshot) may lack the
            // target: the undo then only adds its redo.
            if (!m_undo.empty() && m_undo.back().version == info.target) {
                m_bytes -= m_undo.back().bytes;
                m_undo.pop_back();
            }
            step.version = info.target;
            push_redo(std::move(step));
            break;
        case BatchKind::Redo:
            if (!m_redo.empty() && m_redo.back().version == info.target) {
                m_bytes -= m_redo.back().bytes;
                m_redo.pop_back();
            }
            push_undo(std::move(step));
            break;
    }
}

namespace {

/// Pushes `step` on `stack`, counting its bytes in `bytes`; false when it is too big to keep.
/// A stack is taken from the top: what lies below a step that is not kept cannot be reached, so
/// the whole stack goes then.
template <class Stack, class Step>
bool push_step(Stack& stack, Step&& step, const HistoryLimits& limits, uint64_t& bytes) {
    if (limits.max_undo == 0 || step.bytes > limits.max_bytes) {
        for (const auto& s : stack) bytes -= s.bytes;
        stack.clear();
        return false;
    }
    bytes += step.bytes;
    stack.push_back(std::forward<Step>(step));
    return true;
}

}  // namespace

void EditHistory::push_undo(Step&& step) {
    if (push_step(m_undo, std::move(step), m_limits, m_bytes)) trim();
}

void EditHistory::push_redo(Step&& step) {
    if (push_step(m_redo, std::move(step), m_limits, m_bytes)) trim();
}

void EditHistory::trim() {
    while (m_undo.size() > m_limits.max_undo ||
           (m_bytes > m_limits.max_bytes && m_undo.size() > 1)) {
        m_bytes -= m_undo.front().bytes;
        m_undo.pop_front();
    }
    while (m_redo.size() > m_limits.max_undo || (m_bytes > m_limits.max_bytes && !m_redo.empty())) {
        m_bytes -= m_redo.front().bytes;
        m_redo.pop_front();
    }
}

std::optional<EditBatch> EditHistory::tagged(const std::deque<Step>& stack, BatchKind kind) {
    if (stack.empty()) return std::nullopt;
    EditBatch batch;
    batch.edits = stack.back().batch->edits;
    batch.info.kind = kind;
    batch.info.target = stack.back().version;
    return batch;
}

std::optional<EditBatch> EditHistory::undo_batch() const {
    return tagged(m_undo, BatchKind::Undo);
}

std::optional<EditBatch> EditHistory::redo_batch() const {
    return tagged(m_redo, BatchKind::Redo);
}

HistoryPage EditHistory::page(std::size_t limit, uint64_t before) const {
    HistoryPage page;
    page.oldest = m_entries.empty() ? 0 : m_entries.front().version;
    page.undo_depth = m_undo.size();
    page.redo_depth = m_redo.size();
    page.next_undo = m_undo.empty() ? 0 : m_undo.back().version;
    page.next_redo = m_redo.empty() ? 0 : m_redo.back().version;
    page.held_bytes = m_bytes;
    std::unordered_set<uint64_t> on_stack;
    for (const Step& s : m_undo) on_stack.insert(s.version);
    // Versions grow along the deque: start at the newest entry older than `before`.
    auto end = m_entries.end();
    if (before != 0)
        end = std::lower_bound(m_entries.begin(), m_entries.end(), before,
                               [](const HistoryEntry& e, uint64_t v) { return e.version < v; });
    for (auto it = end; it != m_entries.begin() && page.entries.size() < limit;) {
        --it;
        page.entries.push_back(*it);
        page.undoable.push_back(on_stack.count(it->version) != 0);
    }
    return page;
}

void EditHistory::clear() {
    m_entries.clear();
    m_undo.clear();
    m_redo.clear();
    m_bytes = 0;
}

HistoryState EditHistory::state() const {
    HistoryState out;
    out.entries.assign(m_entries.begin(), m_entries.end());
    for (const Step& s : m_undo) out.undo.push_back({s.version, s.batch});
    for (const Step& s : m_redo) out.redo.push_back({s.version, s.batch});
    return out;
}

void EditHistory::restore(HistoryState&& state) {
    clear();
    for (HistoryEntry& e : state.entries) m_entries.push_back(std::move(e));
    while (m_entries.size() > m_limits.max_entries) m_entries.pop_front();
    for (auto [from, to] : {std::pair{&state.undo, &m_undo}, std::pair{&state.redo, &m_redo}}) {
        for (HistoryState::Step& s : *from) {
            if (!s.batch) continue;
            Step step{s.version, std::move(s.batch), 0};
            step.bytes = approx_bytes(*step.batch);
            m_bytes += step.bytes;
            to->push_back(std::move(step));
        }
    }
    trim();
}

}  // namespace strata
