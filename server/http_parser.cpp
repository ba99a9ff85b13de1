#include "server/http_parser.h"

#include <algorithm>
#include <charconv>
#include <optional>

namespace strata::server {

using protocol::make_problem;
using protocol::Problem;
using protocol::ProblemType;

namespace {

/// RFC 9110 tchar: the characters of a token (method, header name).
bool is_tchar(unsigned char c) {
    if ((c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) return true;
    return std::string_view("!#$%&'*+-.^_`|~").find(char(c)) != std::string_view::npos;
}

/// RFC 9110 field-vchar, SP or HTAB: what a field value may hold (obs-text included).
bool is_field_char(unsigned char c) {
    return c == '\t' || c == ' ' || (c >= 0x21 && c != 0x7F);
}

char lower(char c) {
    return c >= 'A' && c <= 'Z' ? char(c + 32) : c;
}

std::string_view trim_ows(std::string_view v) {
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.remove_suffix(1);
    return v;
}

/// Offset past the empty lines (CRLF or LF) at `pos`.
std::size_t skip_empty_lines(std::string_view s, std::size_t pos) {
    for (;;) {
        if (pos < s.size() && s[pos] == '\n') {
            ++pos;
        } else if (pos + 1 < s.size() && s[pos] == '\r' && s[pos + 1] == '\n') {
            pos += 2;
        } else {
            return pos;
        }
    }
}

/// Splits the next LF-terminated line off `s` at `pos` (dropping one CR before the LF). A line
/// with no LF is returned whole; callers only pass complete heads.
std::string_view next_line(std::string_view s, std::size_t& pos) {
    const std::size_t lf = std::min(s.find('\n', pos), s.size());
    std::string_view line = s.substr(pos, lf - pos);
    pos = lf + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
}

Problem error(ProblemType type, std::string detail) {
    return make_problem(type, std::move(detail));
}

/// Calls f(element) for each element of a comma-separated list, trimmed of OWS.
template <class F>
void for_each_list_element(std::string_view list, F&& f) {
    while (true) {
        const std::size_t comma = list.find(',');
        f(trim_ows(list.substr(0, comma)));
        if (comma == std::string_view::npos) return;
        list.remove_prefix(comma + 1);
    }
}

std::string in_quotes(std::string_view s) {
    return "'" + std::string(s.substr(0, 64)) + (s.size() > 64 ? "...'" : "'");
}

std::optional<Problem> parse_request_line(std::string_view line, const HttpLimits& limits,
                                          RequestHead& head) {
    const std::size_t sp1 = line.find(' ');
    const std::size_t sp2 = sp1 == std::string_view::npos ? sp1 : line.find(' ', sp1 + 1);
    if (sp2 == std::string_view::npos || line.find(' ', sp2 + 1) != std::string_view::npos)
        return error(ProblemType::InvalidRequest,
                     "malformed request line (expected: METHOD SP target SP HTTP/1.1)");
    const std::string_view method = line.substr(0, sp1);
    const std::string_view target = line.substr(sp1 + 1, sp2 - sp1 - 1);
    const std::string_view version = line.substr(sp2 + 1);
    if (method.empty() || method.size() > 32 ||
        !std::all_of(method.begin(), method.end(), [](char c) { return is_tchar(c); }))
        return error(ProblemType::InvalidRequest, "malformed request method");
    if (target.empty()) return error(ProblemType::InvalidRequest, "empty request target");
    if (target.size() > limits.max_target_bytes)
        return error(ProblemType::UriTooLong,
                     "the request target is " + std::to_string(target.size()) +
                         " bytes long; the limit is " + std::to_string(limits.max_target_bytes) +
                         " (--max-uri-bytes)");
    for (unsigned char c : target) {
        if (c < 0x21 || c > 0x7E)
            return error(ProblemType::InvalidRequest,
                         "the request target holds a control character, a space or a "
                         "non-ASCII byte (percent-encode it)");
    }
    if (version.size() != 8 || version.substr(0, 5) != "HTTP/" || version[6] != '.' ||
        version[5] < '0' || version[5] > '9' || version[7] < '0' || version[7] > '9')
        return error(ProblemType::InvalidRequest, "malformed HTTP version");
    if (version[5] != '1')
        return error(ProblemType::HttpVersion,
                     "HTTP version " + std::string(version.substr(5)) +
                         " is not supported; this server speaks HTTP/1.1 and HTTP/1.0");
    static constexpr std::string_view KNOWN[] = {"GET",   "HEAD",   "POST",   "PUT",
                                                 "PATCH", "DELETE", "OPTIONS"};
    if (std::find(std::begin(KNOWN), std::end(KNOWN), method) == std::end(KNOWN))
        return error(ProblemType::NotImplemented,
                     "method " + in_quotes(method) + " is not implemented");
    head.method = std::string(method);
    head.target = std::string(target);
    head.minor_version = version[7] - '0';
    return std::nullopt;
}

std::optional<Problem> parse_field(std::string_view line, RequestHead& head) {
    if (line.front() == ' ' || line.front() == '\t')
        return error(ProblemType::InvalidRequest,
                     "obsolete line folding (a header line starting with whitespace)");
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos)
        return error(ProblemType::InvalidRequest, "a header line has no colon");
    const std::string_view name = line.substr(0, colon);
    if (name.empty()) return error(ProblemType::InvalidRequest, "a header line has an empty name");
    for (unsigned char c : name) {
        if (!is_tchar(c))
            return error(ProblemType::InvalidRequest,
                         c == ' ' || c == '\t' ? "whitespace between a header name and its colon"
                                               : "invalid character in a header name");
    }
    const std::string_view value = trim_ows(line.substr(colon + 1));
    for (unsigned char c : value) {
        if (!is_field_char(c))
            return error(ProblemType::InvalidRequest,
                         "header " + in_quotes(name) +
                             " holds a control character (NUL, CR, ...) in its value");
    }
    head.headers.push_back({std::string(name), std::string(value)});
    return std::nullopt;
}

/// Works out the body framing, keep-alive and Expect from the fields (RFC 9112 section 6).
std::optional<Problem> interpret_fields(RequestHead& head) {
    static constexpr std::string_view SINGLETONS[] = {
        "host", "authorization", "content-type", "if-match", "expect", "content-encoding"};
    std::size_t hosts = 0;
    bool has_length = false, has_te = false;
    std::string codings;
    head.keep_alive = head.minor_version >= 1;
    for (std::size_t i = 0; i < head.headers.size(); ++i) {
        const HeaderField& f = head.headers[i];
        for (std::string_view s : SINGLETONS) {
            if (!iequals(f.name, s)) continue;
            for (std::size_t j = 0; j < i; ++j) {
                if (iequals(head.headers[j].name, s))
                    return error(ProblemType::InvalidRequest,
                                 "header " + in_quotes(f.name) + " is given more than once");
            }
        }
        if (iequals(f.name, "host")) {
            ++hosts;
        } else if (iequals(f.name, "content-length")) {
            uint64_t n = 0;
            const char* end = f.value.data() + f.value.size();
            const auto [p, ec] = std::from_chars(f.value.data(), end, n);
            if (f.value.empty() || ec != std::errc() || p != end || f.value.size() > 19)
                return error(ProblemType::InvalidRequest,
                             "Content-Length " + in_quotes(f.value) + " is not a number");
            if (has_length && n != head.content_length)
                return error(ProblemType::InvalidRequest, "conflicting Content-Length headers");
            has_length = true;
            head.content_length = n;
        } else if (iequals(f.name, "transfer-encoding")) {
            has_te = true;
            codings += (codings.empty() ? "" : ",") + f.value;
        } else if (iequals(f.name, "connection")) {
            for_each_list_element(f.value, [&](std::string_view option) {
                if (iequals(option, "close")) head.keep_alive = false;
                if (iequals(option, "keep-alive") && head.minor_version == 0)
                    head.keep_alive = true;
            });
        } else if (iequals(f.name, "expect")) {
            if (!iequals(f.value, "100-continue"))
                return error(
                    ProblemType::ExpectationFailed,
                    "Expect: " + in_quotes(f.value) + " is not supported (only 100-continue is)");
            head.expect_continue = true;
        }
    }
    if (head.minor_version >= 1 && hosts == 0)
        return error(ProblemType::InvalidRequest, "an HTTP/1.1 request needs a Host header");
    if (has_te) {
        if (has_length)
            return error(ProblemType::InvalidRequest,
                         "Content-Length and Transfer-Encoding together (ambiguous framing)");
        if (head.minor_version == 0)
            return error(ProblemType::InvalidRequest, "Transfer-Encoding in an HTTP/1.0 request");
        std::size_t count = 0;
        std::optional<Problem> bad;
        for_each_list_element(codings, [&](std::string_view coding) {
            if (!bad && (count++ > 0 || !iequals(coding, "chunked")))
                bad = error(ProblemType::InvalidRequest,
                            "unsupported transfer coding " + in_quotes(coding) +
                                " (only a single 'chunked' is accepted)");
        });
        if (bad) return bad;
        head.framing = BodyFraming::Chunked;
    } else if (has_length && head.content_length > 0) {
        head.framing = BodyFraming::Length;
    }
    return std::nullopt;
}

}  // namespace

const std::string* find_header(const std::vector<HeaderField>& headers, std::string_view name) {
    for (const HeaderField& f : headers) {
        if (iequals(f.name, name)) return &f.value;
    }
    return nullptr;
}

bool iequals(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (lower(a[i]) != lower(b[i])) return false;
    }
    return true;
}

std::size_t find_head_end(std::string_view buffer, std::size_t from) {
    const std::size_t lead = skip_empty_lines(buffer, 0);
    // A terminator (LF LF or LF CR LF) may straddle the end of what was searched before.
    for (std::size_t i = std::max(lead, from >= 2 ? from - 2 : 0); i < buffer.size(); ++i) {
        if (buffer[i] != '\n') continue;
        if (i + 1 < buffer.size() && buffer[i + 1] == '\n') return i + 2;
        if (i + 2 < buffer.size() && buffer[i + 1] == '\r' && buffer[i + 2] == '\n') return i + 3;
    }
    return std::string_view::npos;
}

std::variant<RequestHead, Problem> parse_request_head(std::string_view text,
                                                      const HttpLimits& limits) {
    if (text.size() > limits.max_head_bytes)
        return error(ProblemType::HeadersTooLarge, "the request head is larger than " +
                                                       std::to_string(limits.max_head_bytes) +
                                                       " bytes (--max-header-bytes)");
    RequestHead head;
    std::size_t pos = skip_empty_lines(text, 0);
    const std::string_view request_line = next_line(text, pos);
    if (request_line.find('\r') != std::string_view::npos)
        return error(ProblemType::InvalidRequest, "a bare CR in the request line");
    if (auto e = parse_request_line(request_line, limits, head)) return *e;
    while (pos < text.size()) {
        const std::string_view line = next_line(text, pos);
        if (line.empty()) break;
        if (line.size() > MAX_HEADER_LINE_BYTES)
            return error(
                ProblemType::HeadersTooLarge,
                "a header line is longer than " + std::to_string(MAX_HEADER_LINE_BYTES) + " bytes");
        if (head.headers.size() >= limits.max_headers)
            return error(ProblemType::HeadersTooLarge, "more than " +
                                                           std::to_string(limits.max_headers) +
                                                           " header fields (--max-headers)");
        if (auto e = parse_field(line, head)) return *e;
    }
    if (auto e = interpret_fields(head)) return *e;
    return head;
}

std::size_t ChunkedDecoder::fail(ProblemType type, std::string detail) {
    m_state = State::Failed;
    m_error = make_problem(type, std::move(detail));
    return 0;
}

std::size_t ChunkedDecoder::feed(std::string_view in, std::string& body) {
    // Chunk-size lines and trailer lines are short; a longer one is an attack or garbage.
    constexpr std::size_t MAX_LINE = 4096;
    constexpr std::size_t MAX_TRAILER_BYTES = 16 * 1024;
    std::size_t used = 0;
    while (used < in.size() && m_state != State::Done && m_state != State::Failed) {
        if (m_state == State::Data) {
            const std::size_t n = std::size_t(std::min<uint64_t>(m_remaining, in.size() - used));
            body.append(in.substr(used, n));
            used += n;
            m_remaining -= n;
            if (m_remaining == 0) m_state = State::DataEnd;
            continue;
        }
        // Size, DataEnd and Trailer read a line at a time.
        const std::size_t lf = in.find('\n', used);
        const std::size_t take = (lf == std::string_view::npos ? in.size() : lf + 1) - used;
        if (m_line.size() + take > MAX_LINE + 2)
            return used +
                   fail(ProblemType::InvalidRequest, "a chunk-size or trailer line is too long");
        m_line.append(in.substr(used, take));
        used += take;
        if (lf == std::string_view::npos) break;
        std::string_view line(m_line);
        line.remove_suffix(1);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.find('\r') != std::string_view::npos)
            return used + fail(ProblemType::InvalidRequest, "a bare CR in the chunked body");
        if (m_state == State::DataEnd) {
            if (!line.empty())
                return used + fail(ProblemType::InvalidRequest, "chunk data longer than its size");
            m_state = State::Size;
        } else if (m_state == State::Size) {
            const std::string_view digits = line.substr(0, line.find(';'));
            uint64_t size = 0;
            const auto [p, ec] =
                std::from_chars(digits.data(), digits.data() + digits.size(), size, 16);
            if (digits.empty() || digits.size() > 15 || ec != std::errc() ||
                p != digits.data() + digits.size())
                return used + fail(ProblemType::InvalidRequest, "malformed chunk size");
            for (unsigned char c : line.substr(digits.size())) {
                if (!is_field_char(c))
                    return used + fail(ProblemType::InvalidRequest, "control character in a chunk");
            }
            if (m_decoded + size > m_max_body)
                return used +
                       fail(ProblemType::TooLarge, "the chunked body is larger than the limit of " +
                                                       std::to_string(m_max_body) + " bytes");
            m_decoded += size;
            m_remaining = size;
            m_state = size == 0 ? State::Trailer : State::Data;
        } else if (line.empty()) {  // State::Trailer: the empty line ends the body
            m_state = State::Done;
        } else {
            m_trailer_bytes += line.size();
            RequestHead ignored;
            if (m_trailer_bytes > MAX_TRAILER_BYTES)
                return used + fail(ProblemType::HeadersTooLarge,
                                   "the chunked body's trailer is too large");
            if (auto e = parse_field(line, ignored)) return used + fail(e->type, e->detail);
        }
        m_line.clear();
    }
    return used;
}

}  // namespace strata::server
