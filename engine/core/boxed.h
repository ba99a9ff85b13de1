#pragma once
// A value kept on the heap only once it is set: a record's rarely used fields, so that the
// millions of records that never set them hold one pointer instead of the fields.

#include <memory>

namespace strata {

/// Value semantics (copies copy the value). Reading an empty box reads T's defaults; mut()
/// allocates it.
template <class T>
class Boxed {
public:
    Boxed() = default;
    Boxed(const Boxed& other)
        : m_value(other.m_value ? std::make_unique<T>(*other.m_value) : nullptr) {}
    Boxed(Boxed&&) noexcept = default;
    Boxed& operator=(const Boxed& other) {
        if (this != &other) m_value = other.m_value ? std::make_unique<T>(*other.m_value) : nullptr;
        return *this;
    }
    Boxed& operator=(Boxed&&) noexcept = default;

    const T& operator*() const { return m_value ? *m_value : defaults(); }
    const T* operator->() const { return &**this; }
    /// The value, allocated (as T's defaults) if the box was empty.
    T& mut() {
        if (!m_value) m_value = std::make_unique<T>();
        return *m_value;
    }
    /// Whether the value was allocated.
    explicit operator bool() const { return m_value != nullptr; }

    static const T& defaults() {
        static const T value{};
        return value;
    }

private:
    std::unique_ptr<T> m_value;
};

}  // namespace strata
