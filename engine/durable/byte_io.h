#pragma once
// Little-endian binary writing and bounds-checked reading for the journal and snapshot codecs.
// Both sides are called the same way, `io(field, ...)`, so one function describes a layout for
// encoding and decoding alike: value_fields() below for the value types inside edits (Material,
// BuildOptions, Affine), fields() in edit_codec.cpp for each edit kind. Objects' plain fields come
// from their kinds' field tables (object_fields.h). Arrays of Vec3 and
// triangles are copied as raw buffers: the host is little-endian, and a static_assert keeps it
// that way.

#include <bit>
#include <concepts>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "engine/scene/edits.h"
#include "engine/scene/object_fields.h"

namespace strata::durable {

static_assert(std::endian::native == std::endian::little,
              "the journal stores raw little-endian buffers");
static_assert(sizeof(Keyframe) == 13 * sizeof(float), "keyframes are copied as raw buffers");

/// `E` is T or const T: the same function writes (const) and reads (mutable).
template <class E, class T>
concept Kind = std::same_as<std::remove_const_t<E>, T>;

// Step: one field list per value type, used by the writer and the reader -------------------------

/// Build options are the preference byte and a flags byte. The flags byte was allow_refit's
/// bool (0 or 1), so flags added later take its higher bits and older files read unchanged.
enum BuildFlagBits : uint8_t { ALLOW_REFIT = 1, COMPACT = 2 };
template <class Io, Kind<BuildOptions> E>
void value_fields(Io& io, E& v) {
    if constexpr (std::is_const_v<E>) {
        io(v.prefer, uint8_t((v.allow_refit ? ALLOW_REFIT : 0) | (v.compact ? COMPACT : 0)));
    } else {
        uint8_t flags = 0;
        io(v.prefer, flags);
        if (flags & ~(ALLOW_REFIT | COMPACT))
            return io.fail("build flags byte " + std::to_string(flags) + " has unknown bits");
        v.allow_refit = (flags & ALLOW_REFIT) != 0;
        v.compact = (flags & COMPACT) != 0;
    }
}
/// The first-layout (tag 0) fields of kind `K` in `v`, its record or add edit, in table order.
template <class K, class Io, class V>
void table_fields(Io& io, V& v) {
    for_each_field<K>([&](const auto& row) {
        if (row.info.tag == 0) io(field_in(row, v));
    });
}
/// The first-layout fields of kind `K`'s update edit `u`, each an optional.
template <class K, class Io, class U>
void table_updates(Io& io, U& u) {
    for_each_field<K>([&](const auto& row) {
        if (row.info.tag == 0) io(u.*(row.update));
    });
}

template <class Io, Kind<Material> E>
void value_fields(Io& io, E& v) {
    table_fields<MaterialFields>(io, v);
}
template <class Io, Kind<Light> E>
void value_fields(Io& io, E& v) {
    table_fields<LightFields>(io, v);
}
template <class Io, Kind<Affine> E>
void value_fields(Io& io, E& v) {
    io.raw(v.m.data(), sizeof(float) * v.m.size());
}

/// The largest value an enum's byte may hold (two-valued enums unless said otherwise).
template <class T>
constexpr uint8_t ENUM_MAX = 1;
template <>
inline constexpr uint8_t ENUM_MAX<LightKind> = 2;
template <>
inline constexpr uint8_t ENUM_MAX<TextureWrap> = 2;
template <>
inline constexpr uint8_t ENUM_MAX<BatchKind> = 2;
template <>
inline constexpr uint8_t ENUM_MAX<AlphaMode> = 2;
template <>
inline constexpr uint8_t ENUM_MAX<MeshKind> = 2;
template <>
inline constexpr uint8_t ENUM_MAX<CurveBasis> = 3;

/// True for the types that have a value_fields() layout.
template <class Io, class T>
concept HasValueFields = requires(Io& io, T& v) { value_fields(io, v); };

// Step: the writer and the reader ----------------------------------------------------------------

/// Appends fields to a byte string.
class ByteWriter {
public:
    explicit ByteWriter(std::string& out) : m_out(out) {}

    template <class... T>
    void operator()(const T&... values) {
        (put(values), ...);
    }

    void raw(const void* data, std::size_t size) {
        m_out.append(static_cast<const char*>(data), size);
    }

private:
    template <class T>
    void put(const T& v) {
        if constexpr (std::is_enum_v<T>) {
            put(static_cast<uint8_t>(v));
        } else if constexpr (std::is_same_v<T, bool>) {
            put(uint8_t(v ? 1 : 0));
        } else if constexpr (std::is_arithmetic_v<T>) {
            raw(&v, sizeof v);
        } else if constexpr (std::is_same_v<T, std::string>) {
            put(uint32_t(v.size()));
            raw(v.data(), v.size());
        } else if constexpr (std::is_same_v<T, Vec3> || std::is_same_v<T, Vec2> ||
                             std::is_same_v<T, Vec4> || std::is_same_v<T, Triangle>) {
            raw(&v, sizeof v);
        } else if constexpr (HasValueFields<ByteWriter, const T>) {
            value_fields(*this, v);
        } else {
            put_other(v);
        }
    }
    template <class T>
    void put_other(const std::vector<T>& v) {
        put(uint64_t(v.size()));
        if constexpr (std::is_same_v<T, std::string>) {
            for (const std::string& x : v) put(x);
        } else {
            static_assert(std::is_same_v<T, Vec3> || std::is_same_v<T, Vec2> ||
                          std::is_same_v<T, Vec4> || std::is_same_v<T, Triangle> ||
                          std::is_same_v<T, uint32_t> || std::is_same_v<T, float> ||
                          std::is_same_v<T, Affine> || std::is_same_v<T, Keyframe>);
            raw(v.data(), v.size() * sizeof(T));
        }
    }
    template <class T>
    void put_other(const std::optional<T>& v) {
        put(v.has_value());
        if (v) put(*v);
    }

    std::string& m_out;
};

/// Reads fields back; the first failure (short input, bad enum, bad flag) sticks and every later
/// read is a no-op, so callers check ok() once at the end.
class ByteReader {
public:
    explicit ByteReader(std::string_view in) : m_in(in) {}

    template <class... T>
    void operator()(T&... values) {
        (get(values), ...);
    }

    bool ok() const { return m_error.empty(); }
    const std::string& error() const { return m_error; }
    std::size_t offset() const { return m_pos; }
    std::size_t remaining() const { return m_in.size() - m_pos; }
    void fail(std::string why) {
        if (m_error.empty()) m_error = std::move(why) + " at byte " + std::to_string(m_pos);
    }

    bool raw(void* out, std::size_t size) {
        if (!ok()) return false;
        if (size > remaining()) {
            fail("truncated: " + std::to_string(size) + " bytes wanted, " +
                 std::to_string(remaining()) + " left");
            return false;
        }
        if (size) std::memcpy(out, m_in.data() + m_pos, size);
        m_pos += size;
        return true;
    }

private:
    template <class T>
    void get(T& v) {
        if constexpr (std::is_enum_v<T>) {
            uint8_t b = 0;
            get(b);
            if (b > ENUM_MAX<T>)
                return fail("enum value " + std::to_string(b) + " out of range");
            v = static_cast<T>(b);
        } else if constexpr (std::is_same_v<T, bool>) {
            uint8_t b = 0;
            get(b);
            if (b > 1) return fail("flag byte " + std::to_string(b) + " is neither 0 nor 1");
            v = b == 1;
        } else if constexpr (std::is_arithmetic_v<T>) {
            raw(&v, sizeof v);
        } else if constexpr (std::is_same_v<T, std::string>) {
            uint32_t n = 0;
            get(n);
            if (!ok()) return;
            if (n > remaining()) return fail("string of " + std::to_string(n) + " bytes");
            v.assign(m_in.data() + m_pos, n);
            m_pos += n;
        } else if constexpr (std::is_same_v<T, Vec3> || std::is_same_v<T, Vec2> ||
                             std::is_same_v<T, Vec4> || std::is_same_v<T, Triangle>) {
            raw(&v, sizeof v);
        } else if constexpr (HasValueFields<ByteReader, T>) {
            value_fields(*this, v);
        } else {
            get_other(v);
        }
    }
    template <class T>
    void get_other(std::vector<T>& v) {
        uint64_t n = 0;
        get(n);
        if (!ok()) return;
        // Checked before allocating: a corrupt count must not ask for terabytes (a string takes
        // at least its length's 4 bytes).
        constexpr std::size_t least = std::is_same_v<T, std::string> ? sizeof(uint32_t) : sizeof(T);
        if (n > remaining() / least) return fail("array of " + std::to_string(n) + " elements");
        v.resize(n);
        if constexpr (std::is_same_v<T, std::string>) {
            for (std::string& x : v) get(x);
        } else {
            static_assert(std::is_trivially_copyable_v<T>);
            raw(v.data(), n * sizeof(T));
        }
    }
    template <class T>
    void get_other(std::optional<T>& v) {
        bool present = false;
        get(present);
        if (!ok()) return;
        if (!present) {
            v.reset();
            return;
        }
        v.emplace();
        get(*v);
    }

    std::string_view m_in;
    std::size_t m_pos = 0;
    std::string m_error;
};

}  // namespace strata::durable
