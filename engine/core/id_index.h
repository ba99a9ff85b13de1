#pragma once
// The index from client ids to handles of one object kind. The ids themselves stay in the
// records: a bucket holds a handle and 32 bits of its id's hash (12 bytes, open addressing with
// linear probing), where a std::unordered_map<std::string, Handle> held a node per id with a
// second copy of the string (about 72 bytes an id). A lookup compares strings only for buckets
// whose hash bits match, reading the id from the record the handle names.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include "engine/core/check.h"

namespace strata {

template <class HandleT>
class IdIndex {
public:
    /// The handle whose record (in `records`, a SlotArray of records with an `id`) has id `id`;
    /// a null handle when none has.
    template <class Records>
    HandleT find(std::string_view id, const Records& records) const {
        if (m_size == 0) return {};
        const uint32_t tag = tag_of(id);
        for (std::size_t b = home(tag);; b = next(b)) {
            if (empty(b)) return {};
            if (m_tags[b] != tag) continue;
            const auto* record = records.get(m_handles[b]);
            if (record && record->id == id) return m_handles[b];
        }
    }

    /// Adds `id` for `h`. The id must not be in the index (callers look it up first).
    void insert(std::string_view id, HandleT h) {
        STRATA_CHECK(!h.is_null());
        if ((m_size + 1) * 5 > m_tags.size() * 4) grow((m_size + 1) * 2);
        place(tag_of(id), h);
        ++m_size;
    }

    /// Takes `id`, held for `h`, out of the index; false when it was not there.
    bool erase(std::string_view id, HandleT h) {
        if (m_size == 0) return false;
        const uint32_t tag = tag_of(id);
        std::size_t b = home(tag);
        for (;; b = next(b)) {
            if (empty(b)) return false;
            if (m_tags[b] == tag && m_handles[b] == h) break;
        }
        // Backward-shift deletion: move later entries of the probe run into the hole while
        // their home lies at or before it, so every run stays unbroken.
        for (std::size_t hole = b, j = next(b);; j = next(j)) {
            if (empty(j)) {
                m_handles[hole] = {};
                break;
            }
            const std::size_t distance_j = (j - home(m_tags[j])) & mask();
            const std::size_t distance_hole = (j - hole) & mask();
            if (distance_j >= distance_hole) {
                m_tags[hole] = m_tags[j];
                m_handles[hole] = m_handles[j];
                hole = j;
            }
        }
        --m_size;
        return true;
    }

    /// Makes room for `n` ids in all without growing again.
    void reserve(std::size_t n) {
        if (n * 5 > m_tags.size() * 4) grow(n);
    }

    void clear() {
        m_tags.clear();
        m_handles.clear();
        m_size = 0;
    }

    std::size_t size() const { return m_size; }
    /// Heap bytes held.
    std::size_t bytes() const { return m_tags.capacity() * (sizeof(uint32_t) + sizeof(HandleT)); }

private:
    static uint32_t tag_of(std::string_view id) {
        const uint64_t h = std::hash<std::string_view>{}(id);
        return uint32_t(h ^ (h >> 32));
    }
    std::size_t mask() const { return m_tags.size() - 1; }
    std::size_t home(uint32_t tag) const { return tag & mask(); }
    std::size_t next(std::size_t b) const { return (b + 1) & mask(); }
    bool empty(std::size_t b) const { return m_handles[b].is_null(); }

    void place(uint32_t tag, HandleT h) {
        std::size_t b = home(tag);
        while (!empty(b)) b = next(b);
        m_tags[b] = tag;
        m_handles[b] = h;
    }

    /// Rehashes into the smallest power of two of buckets that holds `n` ids at 80% load.
    void grow(std::size_t n) {
        std::size_t buckets = 16;
        while (n * 5 > buckets * 4) buckets *= 2;
        std::vector<uint32_t> tags(buckets);
        std::vector<HandleT> handles(buckets);
        tags.swap(m_tags);
        handles.swap(m_handles);
        for (std::size_t b = 0; b < tags.size(); ++b)
            if (!handles[b].is_null()) place(tags[b], handles[b]);
    }

    std::vector<uint32_t> m_tags;
    std::vector<HandleT> m_handles;  ///< null: an empty bucket
    std::size_t m_size = 0;
};

}  // namespace strata
