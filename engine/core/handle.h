#pragma once
// Generational handles and the flat slot array that hands them out (Filament's EntityManager,
// GenerationalArena). A handle is {index, generation}; once its object is erased the slot's
// generation moves on, so the old handle is refused instead of aliasing whatever reuses the slot.

#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "engine/core/check.h"

namespace strata {

/// Typed generational handle. `Tag` only keeps mesh, instance, material and group handles apart.
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
using MeshHandle = Handle<MeshTag>;
using InstanceHandle = Handle<InstanceTag>;
using MaterialHandle = Handle<MaterialTag>;
using GroupHandle = Handle<GroupTag>;

/// Flat storage indexed by slot. Erased slots are reused (lowest generation bump first, LIFO).
template <class T, class Tag>
class SlotArray {
public:
    using HandleT = Handle<Tag>;

    /// Stores `value` and returns its handle. `reused_slot`, when given, says whether a free
    /// slot was reused (what undo_insert needs to know).
    HandleT insert(T value, bool* reused_slot = nullptr) {
        if (reused_slot) *reused_slot = !m_free.empty();
        uint32_t index;
        if (!m_free.empty()) {
            index = m_free.back();
            m_free.pop_back();
            m_items[index] = std::move(value);
        } else {
            index = static_cast<uint32_t>(m_items.size());
            STRATA_CHECK(index != HandleT::INVALID_INDEX);
            m_items.push_back(std::move(value));
            m_generations.push_back(0);
            m_alive.push_back(0);
        }
        m_alive[index] = 1;
        ++m_size;
        return {index, m_generations[index]};
    }

    /// True when `h` names a live object (not erased, not from an older generation).
    bool contains(HandleT h) const {
        return h.index < m_items.size() && m_alive[h.index] &&
               m_generations[h.index] == h.generation;
    }

    /// The object, or nullptr for a stale or null handle.
    T* get(HandleT h) { return contains(h) ? &m_items[h.index] : nullptr; }
    const T* get(HandleT h) const { return contains(h) ? &m_items[h.index] : nullptr; }

    /// The object of a handle known to be live (a stale handle here is a bug).
    T& at(HandleT h) {
        STRATA_CHECK(contains(h));
        return m_items[h.index];
    }
    const T& at(HandleT h) const {
        STRATA_CHECK(contains(h));
        return m_items[h.index];
    }

    /// Erases the object; returns false for a stale handle.
    bool erase(HandleT h) {
        if (!contains(h)) return false;
        m_items[h.index] = T{};
        m_alive[h.index] = 0;
        ++m_generations[h.index];
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
        if (reused_slot) {
            m_items[h.index] = T{};
            m_alive[h.index] = 0;
            m_free.push_back(h.index);
            return;
        }
        STRATA_CHECK(h.index + 1 == m_items.size());
        m_items.pop_back();
        m_generations.pop_back();
        m_alive.pop_back();
    }

    /// Takes the object out before erase()-ing it: what undo_erase needs to put it back.
    T take(HandleT h) {
        STRATA_CHECK(contains(h));
        T value = std::move(m_items[h.index]);
        erase(h);
        return value;
    }

    /// Takes back the most recent erase() of `h` (its generation and the free list are restored).
    void undo_erase(HandleT h, T value) {
        STRATA_CHECK(h.index < m_items.size() && !m_alive[h.index] && !m_free.empty() &&
                     m_free.back() == h.index && m_generations[h.index] == h.generation + 1);
        m_free.pop_back();
        --m_generations[h.index];
        m_alive[h.index] = 1;
        m_items[h.index] = std::move(value);
        ++m_size;
    }

    /// Erases everything; every outstanding handle becomes stale.
    void clear() {
        for (uint32_t i = 0; i < m_items.size(); ++i) {
            if (m_alive[i]) erase({i, m_generations[i]});
        }
    }

    std::size_t size() const { return m_size; }
    /// One past the highest slot ever used: the size of a table indexed by slot.
    uint32_t slot_count() const { return static_cast<uint32_t>(m_items.size()); }
    bool alive_at(uint32_t index) const { return index < m_items.size() && m_alive[index]; }
    HandleT handle_at(uint32_t index) const { return {index, m_generations[index]}; }
    T& at_slot(uint32_t index) { return m_items[index]; }
    const T& at_slot(uint32_t index) const { return m_items[index]; }

    /// Calls f(handle, object) for each live object in slot order.
    template <class F>
    void for_each(F&& f) const {
        for (uint32_t i = 0; i < m_items.size(); ++i) {
            if (m_alive[i]) f(HandleT{i, m_generations[i]}, m_items[i]);
        }
    }
    template <class F>
    void for_each(F&& f) {
        for (uint32_t i = 0; i < m_items.size(); ++i) {
            if (m_alive[i]) f(HandleT{i, m_generations[i]}, m_items[i]);
        }
    }

private:
    std::vector<T> m_items;
    std::vector<uint32_t> m_generations;
    std::vector<uint8_t> m_alive;
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
