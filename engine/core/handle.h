#pragma once
// Generational handles and the flat slot array that hands them out (Filament's EntityManager,
// GenerationalArena). A handle is {index, generation}; once its object is erased the slot's
// generation moves on, so the old handle is refused instead of aliasing whatever reuses the slot.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "engine/core/check.h"
#include "engine/core/cow.h"

namespace strata {

/// Typed generational handle. `Tag` only keeps mesh, instance, material, group and light handles apart.
template <class Tag>
struct Handle {
    static constexpr uint32_t INVALID_INDEX = std::numeric_limits<uint32_t>::max();

    uint32_t index = INVALID_INDEX;
    uint32_t generation = 0;

    bool is_null() const { return index == INVALID_INDEX; }
    friend bool operator==(const Handle&, const Handle&) = default;
};

struct MeshTag;
struct InstanceTag;
struct MaterialTag;
struct GroupTag;
struct TextureTag;
struct LightTag;
using MeshHandle = Handle<MeshTag>;
using InstanceHandle = Handle<InstanceTag>;
using MaterialHandle = Handle<MaterialTag>;
using GroupHandle = Handle<GroupTag>;
using TextureHandle = Handle<TextureTag>;
using LightHandle = Handle<LightTag>;

/// Flat storage indexed by slot. Erased slots are reused (lowest generation bump first, LIFO).
///
/// Slots live in fixed-size chunks held copy-on-write (engine/core/cow.h): copying a SlotArray
/// shares every chunk (one atomic increment per CHUNK slots), and the first write to a shared
/// chunk copies that chunk alone. This is what lets a snapshot take a consistent copy of a
/// million-instance scene in microseconds under the scene lock. Element addresses are stable while
/// the array is written by one owner (chunks never move; a shared chunk is replaced once, on its
/// first write).
template <class T, class Tag>
class SlotArray {
public:
    using HandleT = Handle<Tag>;
    static constexpr uint32_t CHUNK_BITS = 8;
    static constexpr uint32_t CHUNK = 1u << CHUNK_BITS;

    /// Stores `value` and returns its handle. `reused_slot`, when given, says whether a free
    /// slot was reused (what undo_insert needs to know).
    HandleT insert(T value, bool* reused_slot = nullptr) {
        if (reused_slot) *reused_slot = !m_free.empty();
        uint32_t index;
        if (!m_free.empty()) {
            index = m_free.back();
            m_free.pop_back();
        } else {
            index = m_slots;
            STRATA_CHECK(index != HandleT::INVALID_INDEX);
            if ((index & (CHUNK - 1)) == 0) m_chunks.emplace_back();
            ++m_slots;
        }
        Chunk& c = chunk_mut(index);
        c.items[index & (CHUNK - 1)] = std::move(value);
        c.alive[index & (CHUNK - 1)] = 1;
        ++m_size;
        return {index, c.generations[index & (CHUNK - 1)]};
    }

    /// True when `h` names a live object (not erased, not from an older generation).
    bool contains(HandleT h) const {
        if (h.index >= m_slots) return false;
        const Chunk& c = chunk(h.index);
        const uint32_t i = h.index & (CHUNK - 1);
        return c.alive[i] && c.generations[i] == h.generation;
    }

    /// The object, or nullptr for a stale or null handle.
    T* get(HandleT h) { return contains(h) ? &at_slot(h.index) : nullptr; }
    const T* get(HandleT h) const { return contains(h) ? &at_slot(h.index) : nullptr; }

    /// The object of a handle known to be live (a stale handle here is a bug).
    T& at(HandleT h) {
        STRATA_CHECK(contains(h));
        return at_slot(h.index);
    }
    const T& at(HandleT h) const {
        STRATA_CHECK(contains(h));
        return at_slot(h.index);
    }

    /// Erases the object; returns false for a stale handle.
    bool erase(HandleT h) {
        if (!contains(h)) return false;
        Chunk& c = chunk_mut(h.index);
        const uint32_t i = h.index & (CHUNK - 1);
        c.items[i] = T{};
        c.alive[i] = 0;
        ++c.generations[i];
        m_free.push_back(h.index);
        --m_size;
        return true;
    }

    /// Takes back the most recent insert(), which returned `h`: the slot goes back exactly as it
    /// was (same generation, same place in the free list), so later inserts hand out the same
    /// handles as if the insert had never happened. Undo steps must run in reverse order.
    void undo_insert(HandleT h, bool reused_slot) {
        STRATA_CHECK(contains(h));
        --m_size;
        Chunk& c = chunk_mut(h.index);
        const uint32_t i = h.index & (CHUNK - 1);
        c.items[i] = T{};
        c.alive[i] = 0;
        if (reused_slot) {
            m_free.push_back(h.index);
            return;
        }
        STRATA_CHECK(h.index + 1 == m_slots);
        c.generations[i] = 0;  // a slot past the end starts again at generation 0
        --m_slots;
        if (i == 0) m_chunks.pop_back();
    }

    /// Takes the object out before erase()-ing it: what undo_erase needs to put it back.
    T take(HandleT h) {
        STRATA_CHECK(contains(h));
        T value = std::move(at_slot(h.index));
        erase(h);
        return value;
    }

    /// Takes back the most recent erase() of `h` (its generation and the free list are restored).
    void undo_erase(HandleT h, T value) {
        STRATA_CHECK(h.index < m_slots && !alive_at(h.index) && !m_free.empty() &&
                     m_free.back() == h.index &&
                     chunk(h.index).generations[h.index & (CHUNK - 1)] == h.generation + 1);
        m_free.pop_back();
        Chunk& c = chunk_mut(h.index);
        const uint32_t i = h.index & (CHUNK - 1);
        --c.generations[i];
        c.alive[i] = 1;
        c.items[i] = std::move(value);
        ++m_size;
    }

    /// Erases everything; every outstanding handle becomes stale.
    void clear() {
        for (uint32_t i = 0; i < m_slots; ++i) {
            if (alive_at(i)) erase(handle_at(i));
        }
    }

    std::size_t size() const { return m_size; }
    /// One past the highest slot ever used: the size of a table indexed by slot.
    uint32_t slot_count() const { return m_slots; }
    bool alive_at(uint32_t index) const {
        return index < m_slots && chunk(index).alive[index & (CHUNK - 1)];
    }
    HandleT handle_at(uint32_t index) const {
        return {index, chunk(index).generations[index & (CHUNK - 1)]};
    }
    T& at_slot(uint32_t index) { return chunk_mut(index).items[index & (CHUNK - 1)]; }
    const T& at_slot(uint32_t index) const { return chunk(index).items[index & (CHUNK - 1)]; }

    /// Calls f(handle, object) for each live object in slot order.
    template <class F>
    void for_each(F&& f) const {
        for (uint32_t k = 0; k < m_chunks.size(); ++k) {
            const Chunk& c = *m_chunks[k];
            const uint32_t n = std::min(CHUNK, m_slots - k * CHUNK);
            for (uint32_t i = 0; i < n; ++i) {
                if (c.alive[i]) f(HandleT{k * CHUNK + i, c.generations[i]}, c.items[i]);
            }
        }
    }
    /// The same, for writing: every chunk with a live object is made unshared first.
    template <class F>
    void for_each(F&& f) {
        for (uint32_t k = 0; k < m_chunks.size(); ++k) {
            Chunk& c = m_chunks[k].mut();
            const uint32_t n = std::min(CHUNK, m_slots - k * CHUNK);
            for (uint32_t i = 0; i < n; ++i) {
                if (c.alive[i]) f(HandleT{k * CHUNK + i, c.generations[i]}, c.items[i]);
            }
        }
    }

    /// How many chunks this array shares with a copy of it (tests, statistics).
    std::size_t shared_chunks() const {
        std::size_t n = 0;
        for (const auto& c : m_chunks) n += c.unique() ? 0 : 1;
        return n;
    }

private:
    struct Chunk {
        T items[CHUNK];
        uint32_t generations[CHUNK] = {};
        uint8_t alive[CHUNK] = {};
    };
    const Chunk& chunk(uint32_t index) const { return *m_chunks[index >> CHUNK_BITS]; }
    Chunk& chunk_mut(uint32_t index) { return m_chunks[index >> CHUNK_BITS].mut(); }

    std::vector<CowPtr<Chunk>> m_chunks;
    uint32_t m_slots = 0;
    std::vector<uint32_t> m_free;
    std::size_t m_size = 0;
};

}  // namespace strata

template <class Tag>
struct std::hash<strata::Handle<Tag>> {
    std::size_t operator()(const strata::Handle<Tag>& h) const noexcept {
        return std::hash<uint64_t>{}((uint64_t(h.generation) << 32) | h.index);
    }
};
