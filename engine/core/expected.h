#pragma once
// The one "value or error" type of the code base, with exactly the interface of C++23's
// std::expected (and tl::expected), so that it can become `using std::expected` once the
// compiler has it. Only the members the code base uses are here: construction from a value or
// from Unexpected, has_value / operator bool, value, error, operator* / operator->, value_or.
//
// Aliases name its uses: Result<T> and Status (engine errors), Parsed<T> (protocol problems,
// RFC 9457), Outcome<T> (command-line failures).

#include <type_traits>
#include <utility>
#include <variant>

#include "engine/core/check.h"

namespace strata {

/// The error alternative of an Expected, as std::unexpected.
template <class E>
class Unexpected {
public:
    explicit Unexpected(E error) : m_error(std::move(error)) {}

    E& error() & { return m_error; }
    const E& error() const& { return m_error; }
    E&& error() && { return std::move(m_error); }

private:
    E m_error;
};

template <class E>
Unexpected(E) -> Unexpected<E>;

/// A value of type T or an error of type E, as std::expected<T, E>.
template <class T, class E>
class Expected {
public:
    using value_type = T;
    using error_type = E;

    Expected() requires std::is_default_constructible_v<T> : m_v(std::in_place_index<0>) {}
    template <class U = T>
    requires std::is_constructible_v<T, U&&> &&
        (!std::is_same_v<std::remove_cvref_t<U>, Expected>)&&(
            !std::is_same_v<std::remove_cvref_t<U>, Unexpected<E>>)Expected(U&& value)
        : m_v(std::in_place_index<0>, std::forward<U>(value)) {}  // NOLINT
    template <class G>
    Expected(Unexpected<G> error)
        : m_v(std::in_place_index<1>, std::move(error).error()) {}  // NOLINT

    bool has_value() const { return m_v.index() == 0; }
    explicit operator bool() const { return has_value(); }

    T& value() & {
        STRATA_CHECK(has_value());
        return std::get<0>(m_v);
    }
    const T& value() const& {
        STRATA_CHECK(has_value());
        return std::get<0>(m_v);
    }
    T&& value() && { return std::move(value()); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }
    T&& operator*() && { return std::move(value()); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

    template <class U>
    T value_or(U&& fallback) const& {
        return has_value() ? value() : static_cast<T>(std::forward<U>(fallback));
    }

    E& error() & { return std::get<1>(m_v); }
    const E& error() const& { return std::get<1>(m_v); }
    E&& error() && { return std::get<1>(std::move(m_v)); }

private:
    std::variant<T, E> m_v;
};

/// Success or an error, as std::expected<void, E>.
template <class E>
class Expected<void, E> {
public:
    using value_type = void;
    using error_type = E;

    Expected() = default;
    template <class G>
    Expected(Unexpected<G> error) : m_error(std::move(error).error()), m_ok(false) {}  // NOLINT

    bool has_value() const { return m_ok; }
    explicit operator bool() const { return m_ok; }
    void value() const { STRATA_CHECK(m_ok); }

    E& error() & { return m_error; }
    const E& error() const& { return m_error; }
    E&& error() && { return std::move(m_error); }

private:
    E m_error{};
    bool m_ok = true;
};

/// True for Expected<T, E> (any T, E).
template <class X>
struct is_expected : std::false_type {};
template <class T, class E>
struct is_expected<Expected<T, E>> : std::true_type {};
template <class X>
inline constexpr bool is_expected_v = is_expected<std::remove_cvref_t<X>>::value;

}  // namespace strata
