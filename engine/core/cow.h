#pragma once
// Copy-on-write storage for the scene's big arrays. A copy of a CowPtr or CowVector shares the
// value (one atomic increment); the first write through a shared one copies it. The durable
// store's snapshot takes such copies of the scene's slot-array chunks and mesh buffers under the
// scene lock (microseconds) and serialises them outside it, while edits carry on: an edit that
// writes a chunk or buffer the snapshot still shares copies just that piece.
//
// Threads: reads of a shared value may run on any thread. Writes go through mut(), which needs
// the writer to be the only one that can write this handle (the scene's exclusive lock); the
// reference count is read with acquire order, so a value another thread has finished reading and
// released is seen as released before it is written in place.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace strata {

namespace detail {

/// A nullable, reference-counted box of T: the common part of CowPtr and CowVector.
template <class T>
class CowBox {
public:
    CowBox() = default;
    explicit CowBox(T value) : m_box(new Box{{1}, std::move(value)}) {}
    CowBox(const CowBox& other) : m_box(other.m_box) { retain(); }
    CowBox(CowBox&& other) noexcept : m_box(std::exchange(other.m_box, nullptr)) {}
    CowBox& operator=(const CowBox& other) {
        if (m_box != other.m_box) {
            release();
            m_box = other.m_box;
            retain();
        }
        return *this;
    }
    CowBox& operator=(CowBox&& other) noexcept {
        if (this != &other) {
            release();
            m_box = std::exchange(other.m_box, nullptr);
        }
        return *this;
    }
    ~CowBox() { release(); }

    bool has() const { return m_box != nullptr; }
    const T& get() const { return m_box->value; }
    /// Copies the value first when another box shares it.
    T& mut() {
        if (m_box->refs.load(std::memory_order_acquire) != 1) {
            Box* copy = new Box{{1}, m_box->value};
            release();
            m_box = copy;
        }
        return m_box->value;
    }
    bool unique() const { return m_box && m_box->refs.load(std::memory_order_acquire) == 1; }
    void reset() { release(); }

private:
    struct Box {
        std::atomic<uint32_t> refs{1};
        T value;
    };
    void retain() {
        if (m_box) m_box->refs.fetch_add(1, std::memory_order_relaxed);
    }
    void release() {
        if (m_box && m_box->refs.fetch_sub(1, std::memory_order_acq_rel) == 1) delete m_box;
        m_box = nullptr;
    }

    Box* m_box = nullptr;
};

}  // namespace detail

/// A shared, copy-on-write value of T. Never null: a default CowPtr holds a default T.
template <class T>
class CowPtr {
public:
    CowPtr() : m_box(T{}) {}
    explicit CowPtr(T value) : m_box(std::move(value)) {}

    /// The value, for reading.
    const T& get() const { return m_box.get(); }
    const T* operator->() const { return &m_box.get(); }
    const T& operator*() const { return m_box.get(); }
    /// The value, for writing: copied first when another CowPtr shares it.
    T& mut() { return m_box.mut(); }
    /// True when no other CowPtr shares the value (tests, statistics).
    bool unique() const { return m_box.unique(); }

private:
    detail::CowBox<T> m_box;
};

/// A copy-on-write std::vector: reads look like a const vector, writes go through mut() (which
/// copies a shared buffer first) or replace the whole buffer (assignment from a vector, which
/// copies nothing). Empty vectors allocate nothing.
template <class T>
class CowVector {
public:
    CowVector() = default;
    CowVector(std::vector<T> v) { *this = std::move(v); }  // NOLINT: implicit like a vector
    CowVector& operator=(std::vector<T> v) {
        if (v.empty()) {
            m_box.reset();
        } else {
            m_box = detail::CowBox<std::vector<T>>(std::move(v));
        }
        return *this;
    }

    const std::vector<T>& get() const { return m_box.has() ? m_box.get() : empty_vector(); }
    operator const std::vector<T>&() const { return get(); }  // NOLINT: reads as a vector

    std::size_t size() const { return get().size(); }
    bool empty() const { return get().empty(); }
    const T* data() const { return get().data(); }
    const T& operator[](std::size_t i) const { return get()[i]; }
    const T& back() const { return get().back(); }
    auto begin() const { return get().begin(); }
    auto end() const { return get().end(); }

    /// The vector, for writing in place (copied first while shared).
    std::vector<T>& mut() {
        if (!m_box.has()) m_box = detail::CowBox<std::vector<T>>(std::vector<T>{});
        return m_box.mut();
    }
    /// True when no other CowVector shares the buffer (tests).
    bool unique() const { return m_box.unique(); }

    friend bool operator==(const CowVector& a, const CowVector& b) { return a.get() == b.get(); }
    friend bool operator==(const CowVector& a, const std::vector<T>& b) { return a.get() == b; }

private:
    static const std::vector<T>& empty_vector() {
        static const std::vector<T> none;
        return none;
    }

    detail::CowBox<std::vector<T>> m_box;
};

}  // namespace strata
