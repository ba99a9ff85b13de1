#include "protocol/json_document.h"

#include <charconv>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace strata::protocol {

namespace {

bool is_digit(char c) {
    return c >= '0' && c <= '9';
}

class Reader {
public:
    Reader(std::string_view text, const JsonLimits& limits)
        : m_begin(text.data()),
          m_p(text.data()),
          m_end(text.data() + text.size()),
          m_limits(limits) {}

    std::optional<Json> document() {
        Json root;
        skip_ws();
        if (!value(root)) return std::nullopt;
        skip_ws();
        if (m_p != m_end) {
            fail("unexpected data after the JSON value");
            return std::nullopt;
        }
        return root;
    }

    Problem take_error() { return std::move(*m_error); }

private:
    // Step: errors and whitespace ----------------------------------------------------------------

    bool fail(const std::string& what, ProblemType type = ProblemType::MalformedJson) {
        if (!m_error) {
            m_error = make_problem(
                type, type == ProblemType::MalformedJson
                          ? "malformed JSON at byte " + std::to_string(m_p - m_begin) + ": " + what
                          : what);
        }
        return false;
    }

    void skip_ws() {
        while (m_p != m_end && (*m_p == ' ' || *m_p == '\n' || *m_p == '\r' || *m_p == '\t')) ++m_p;
    }

    bool expect(char c, const char* what) {
        skip_ws();
        if (m_p == m_end || *m_p != c) return fail(what);
        ++m_p;
        return true;
    }

    // Step: values -------------------------------------------------------------------------------

    /// Counts one DOM value against the document's budget.
    bool count_value() {
        if (++m_values <= m_limits.max_values) return true;
        return fail("the JSON document holds more than the limit of " +
                        std::to_string(m_limits.max_values) +
                        " values (--max-json-values): split it into smaller requests",
                    ProblemType::TooLarge);
    }

    bool value(Json& out) {
        if (m_p == m_end) return fail("unexpected end of input");
        if (!count_value()) return false;
        switch (*m_p) {
            case '{':
                return object(out);
            case '[':
                return array(out);
            case '"': {
                std::string s;
                if (!string(s)) return false;
                out = std::move(s);
                return true;
            }
            case 't':
                return literal("true", Json(true), out);
            case 'f':
                return literal("false", Json(false), out);
            case 'n':
                return literal("null", Json(nullptr), out);
            default: {
                double unused;
                return number(out, unused);
            }
        }
    }

    bool literal(std::string_view word, Json v, Json& out) {
        if (std::size_t(m_end - m_p) < word.size() || std::string_view(m_p, word.size()) != word)
            return fail("invalid literal");
        m_p += word.size();
        out = std::move(v);
        return true;
    }

    bool enter() {
        if (++m_depth > m_limits.max_depth)
            return fail(
                "JSON nesting is deeper than the limit of " + std::to_string(m_limits.max_depth),
                ProblemType::NestingTooDeep);
        return true;
    }

    bool object(Json& out) {
        if (!enter()) return false;
        ++m_p;
        out = Json::object();
        skip_ws();
        if (m_p != m_end && *m_p == '}') {
            ++m_p;
            --m_depth;
            return true;
        }
        for (;;) {
            skip_ws();
            if (m_p == m_end || *m_p != '"') return fail("expected a string key");
            std::string key;
            if (!string(key)) return false;
            if (out.contains(key)) return fail("duplicate key '" + key + "'");
            if (!expect(':', "expected ':' after a key")) return false;
            skip_ws();
            if (!value(out[std::move(key)])) return false;
            skip_ws();
            if (m_p != m_end && *m_p == ',') {
                ++m_p;
                continue;
            }
            if (!expect('}', "expected ',' or '}' in an object")) return false;
            --m_depth;
            return true;
        }
    }

    /// Arrays keep their first PACK_THRESHOLD numbers as DOM nodes, then pack if all are numbers.
    bool array(Json& out) {
        if (!enter()) return false;
        ++m_p;
        Json::array_t items;
        std::vector<double> packed;
        bool packing = false;
        bool all_numbers = true;  // every element so far is a number
        std::size_t count = 0;
        skip_ws();
        if (m_p != m_end && *m_p == ']') {
            ++m_p;
            --m_depth;
            out = Json::array();
            return true;
        }
        for (;;) {
            skip_ws();
            if (++count > m_limits.max_array_elements)
                return fail("an array has more than the limit of " +
                                std::to_string(m_limits.max_array_elements) + " elements",
                            ProblemType::TooLarge);
            const bool numeric = m_p != m_end && (*m_p == '-' || is_digit(*m_p));
            if (packing && numeric) {
                double d;
                Json unused;
                if (!number(unused, d)) return false;
                packed.push_back(d);
            } else {
                if (packing) {
                    // A packed array met a non-number: no protocol field accepts one, but the
                    // reader should still report the exact element, so go back to DOM nodes.
                    for (double d : packed) items.emplace_back(d);
                    packed = {};
                    packing = false;
                }
                items.emplace_back();
                double d;
                if (numeric && !count_value()) return false;
                if (!(numeric ? number(items.back(), d) : value(items.back()))) return false;
                all_numbers = all_numbers && numeric;
                if (all_numbers && items.size() == PACK_THRESHOLD) {
                    packed.reserve(PACK_THRESHOLD * 16);
                    for (const Json& e : items) packed.push_back(e.get<double>());
                    items.clear();
                    packing = true;
                }
            }
            skip_ws();
            if (m_p != m_end && *m_p == ',') {
                ++m_p;
                continue;
            }
            if (!expect(']', "expected ',' or ']' in an array")) return false;
            break;
        }
        --m_depth;
        if (packing) {
            std::vector<std::uint8_t> bytes(packed.size() * sizeof(double));
            std::memcpy(bytes.data(), packed.data(), bytes.size());
            out = Json::binary(std::move(bytes), PACKED_NUMBERS_SUBTYPE);
        } else {
            out = std::move(items);
        }
        return true;
    }

    // Step: numbers ------------------------------------------------------------------------------

    /// A JSON number into `out` (integer kinds when it has no fraction or exponent) and `d`.
    bool number(Json& out, double& d) {
        const char* start = m_p;
        const char* q = m_p;
        if (q != m_end && *q == '-') ++q;
        if (q == m_end || !is_digit(*q)) return fail("invalid number");
        if (*q == '0') {
            ++q;
        } else {
            while (q != m_end && is_digit(*q)) ++q;
        }
        bool integral = true;
        if (q != m_end && *q == '.') {
            integral = false;
            ++q;
            if (q == m_end || !is_digit(*q)) return fail("invalid number: no digit after '.'");
            while (q != m_end && is_digit(*q)) ++q;
        }
        if (q != m_end && (*q == 'e' || *q == 'E')) {
            integral = false;
            ++q;
            if (q != m_end && (*q == '+' || *q == '-')) ++q;
            if (q == m_end || !is_digit(*q))
                return fail("invalid number: no digit in the exponent");
            while (q != m_end && is_digit(*q)) ++q;
        }
        m_p = q;
        if (integral) {
            if (*start == '-') {
                int64_t i;
                if (std::from_chars(start, q, i).ec == std::errc()) {
                    out = i;
                    d = double(i);
                    return true;
                }
            } else {
                uint64_t u;
                if (std::from_chars(start, q, u).ec == std::errc()) {
                    out = u;
                    d = double(u);
                    return true;
                }
            }
        }
        const auto r = std::from_chars(start, q, d);
        if (r.ec == std::errc::result_out_of_range) {
            // Overflow becomes +-inf (rejected later as not finite, with its pointer) and
            // underflow 0, as strtod does; from_chars leaves `d` untouched in both cases.
            d = std::strtod(std::string(start, q).c_str(), nullptr);
        } else if (r.ec != std::errc()) {
            return fail("invalid number");
        }
        out = d;
        return true;
    }

    // Step: strings ------------------------------------------------------------------------------

    bool string(std::string& out) {
        ++m_p;  // opening quote
        for (;;) {
            const char* run = m_p;
            while (m_p != m_end) {
                const auto c = static_cast<unsigned char>(*m_p);
                if (c == '"' || c == '\\' || c < 0x20 || c >= 0x80) break;
                ++m_p;
            }
            out.append(run, m_p);
            if (m_p == m_end) return fail("unterminated string");
            const auto c = static_cast<unsigned char>(*m_p);
            if (c == '"') {
                ++m_p;
                return true;
            }
            if (c < 0x20) return fail("control character in a string");
            if (c == '\\') {
                if (!escape(out)) return false;
            } else if (!utf8_sequence(out)) {
                return false;
            }
        }
    }

    bool hex4(uint32_t& v) {
        if (m_end - m_p < 4) return fail("truncated \\u escape");
        v = 0;
        for (int i = 0; i < 4; ++i) {
            const char c = *m_p++;
            v <<= 4;
            if (is_digit(c)) {
                v |= uint32_t(c - '0');
            } else if (c >= 'a' && c <= 'f') {
                v |= uint32_t(c - 'a' + 10);
            } else if (c >= 'A' && c <= 'F') {
                v |= uint32_t(c - 'A' + 10);
            } else {
                return fail("invalid hex digit in a \\u escape");
            }
        }
        return true;
    }

    bool escape(std::string& out) {
        ++m_p;
        if (m_p == m_end) return fail("unterminated escape");
        const char c = *m_p++;
        switch (c) {
            case '"':
                out += '"';
                return true;
            case '\\':
                out += '\\';
                return true;
            case '/':
                out += '/';
                return true;
            case 'b':
                out += '\b';
                return true;
            case 'f':
                out += '\f';
                return true;
            case 'n':
                out += '\n';
                return true;
            case 'r':
                out += '\r';
                return true;
            case 't':
                out += '\t';
                return true;
            case 'u':
                break;
            default:
                return fail("invalid escape");
        }
        uint32_t cp = 0;
        if (!hex4(cp)) return false;
        if (cp >= 0xDC00 && cp <= 0xDFFF) return fail("lone low surrogate in a \\u escape");
        if (cp >= 0xD800 && cp <= 0xDBFF) {
            uint32_t low = 0;
            if (m_end - m_p < 2 || m_p[0] != '\\' || m_p[1] != 'u')
                return fail("high surrogate without a low surrogate");
            m_p += 2;
            if (!hex4(low)) return false;
            if (low < 0xDC00 || low > 0xDFFF) return fail("invalid low surrogate");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
        }
        append_utf8(out, cp);
        return true;
    }

    static void append_utf8(std::string& out, uint32_t cp) {
        if (cp < 0x80) {
            out += char(cp);
        } else if (cp < 0x800) {
            out += char(0xC0 | (cp >> 6));
            out += char(0x80 | (cp & 0x3F));
        } else if (cp < 0x10000) {
            out += char(0xE0 | (cp >> 12));
            out += char(0x80 | ((cp >> 6) & 0x3F));
            out += char(0x80 | (cp & 0x3F));
        } else {
            out += char(0xF0 | (cp >> 18));
            out += char(0x80 | ((cp >> 12) & 0x3F));
            out += char(0x80 | ((cp >> 6) & 0x3F));
            out += char(0x80 | (cp & 0x3F));
        }
    }

    /// One multi-byte UTF-8 sequence, validated (no overlongs, surrogates or code points past
    /// U+10FFFF), appended as is.
    bool utf8_sequence(std::string& out) {
        const auto* s = reinterpret_cast<const unsigned char*>(m_p);
        const std::size_t avail = std::size_t(m_end - m_p);
        std::size_t len = 0;
        unsigned char lo = 0x80, hi = 0xBF;  // bounds of the second byte
        if (s[0] >= 0xC2 && s[0] <= 0xDF) {
            len = 2;
        } else if (s[0] >= 0xE0 && s[0] <= 0xEF) {
            len = 3;
            if (s[0] == 0xE0) lo = 0xA0;
            if (s[0] == 0xED) hi = 0x9F;
        } else if (s[0] >= 0xF0 && s[0] <= 0xF4) {
            len = 4;
            if (s[0] == 0xF0) lo = 0x90;
            if (s[0] == 0xF4) hi = 0x8F;
        } else {
            return fail("invalid UTF-8 byte");
        }
        if (avail < len) return fail("truncated UTF-8 sequence");
        if (s[1] < lo || s[1] > hi) return fail("invalid UTF-8 sequence");
        for (std::size_t i = 2; i < len; ++i) {
            if (s[i] < 0x80 || s[i] > 0xBF) return fail("invalid UTF-8 sequence");
        }
        out.append(m_p, len);
        m_p += len;
        return true;
    }

    const char* m_begin;
    const char* m_p;
    const char* m_end;
    const JsonLimits& m_limits;
    std::size_t m_depth = 0;
    std::size_t m_values = 0;  ///< DOM values so far (packed numbers not counted)
    std::optional<Problem> m_error;
};

}  // namespace

Parsed<Json> parse_json(std::string_view text, const JsonLimits& limits) {
    Reader reader(text, limits);
    if (auto root = reader.document()) return std::move(*root);
    return Unexpected(reader.take_error());
}

bool is_packed_numbers(const Json& v) {
    return v.is_binary() && v.get_binary().has_subtype() &&
           v.get_binary().subtype() == PACKED_NUMBERS_SUBTYPE;
}

std::size_t packed_size(const Json& v) {
    return v.get_binary().size() / sizeof(double);
}

double packed_value(const Json& v, std::size_t i) {
    double d;
    std::memcpy(&d, v.get_binary().data() + i * sizeof(double), sizeof d);
    return d;
}

}  // namespace strata::protocol
