#include "protocol/render_parser.h"

#include <charconv>
#include <optional>
#include <string_view>
#include <type_traits>

#include "protocol/field_json.h"
#include "protocol/json_fields.h"

namespace strata::protocol {

SetCamera read_camera_override(FieldReader& r, const Json& v) {
    // The camera's fields as set_camera takes them (the field table), any of them.
    static const MemberRule CAMERA = [] {
        MemberRule rule;
        for_each_field<CameraFields>(
            [&](const auto& row) { rule.allowed.emplace_back(row.info.name); });
        return rule;
    }();
    static const std::string POINTER = "/camera";  // OpFields keeps a reference to it
    r.expect_object(v, POINTER, CAMERA);
    EditSource source;
    OpFields f(r, v, POINTER, CAMERA, source);
    SetCamera c;
    read_updates<CameraFields>(f, c);
    return c;
}

namespace {

/// `frame`: {"group": id} or {"instance": id}.
FrameTarget read_frame(FieldReader& r, const Json& v) {
    r.expect_object(v, "/frame", {"group", "instance"});
    const Json* group = FieldReader::member(v, "group");
    const Json* instance = FieldReader::member(v, "instance");
    if ((group != nullptr) == (instance != nullptr))
        r.schema_error("/frame", "give exactly one of group and instance");
    return {group ? FrameTarget::Kind::Group : FrameTarget::Kind::Instance,
            r.text(group ? *group : *instance, group ? "/frame/group" : "/frame/instance")};
}

RenderRequest read_render(FieldReader& r, const Json& v, uint32_t* split,
                          std::optional<FrameTarget>* frame) {
    MemberRule members{{"width", "height", "format", "spp", "aovs", "compression", "accumulate",
                        "exposure", "camera", "filter", "band", "time"},
                       {}};
    if (split) members.allowed.push_back("split");
    if (frame) members.allowed.push_back("frame");
    r.expect_object(v, "", members);
    RenderRequest q;
    auto u32 = [&](const char* key, uint32_t& out, uint64_t hi) {
        if (const Json* f = FieldReader::member(v, key))
            out = static_cast<uint32_t>(r.integer(*f, child("", key), 1, hi));
    };
    u32("width", q.width, MAX_RENDER_SIDE);
    u32("height", q.height, MAX_RENDER_SIDE);
    u32("spp", q.spp, MAX_RENDER_SPP);
    if (const Json* f = FieldReader::member(v, "format"))
        q.format = ImageFormat(r.choice(*f, "/format", {"png", "exr", "npz"}));
    if (const Json* f = FieldReader::member(v, "compression")) {
        static constexpr std::string_view NAMES[] = {"none", "zip", "piz"};
        q.compression =
            *parse_exr_compression(NAMES[r.choice(*f, "/compression", {"none", "zip", "piz"})]);
    }
    if (const Json* f = FieldReader::member(v, "aovs")) {
        if (!f->is_array()) r.schema_error("/aovs", "expected an array of AOV names");
        for (std::size_t i = 0; i < f->size(); ++i) {
            const Json& a = (*f)[i];
            const auto aov =
                a.is_string() ? parse_aov(a.get_ref<const std::string&>()) : std::nullopt;
            if (!aov)
                r.schema_error("/aovs/" + std::to_string(i),
                               "expected an AOV name: color, albedo, normal, depth, position, "
                               "instance_id, primitive_id, mesh_id or user_id");
            q.aovs.push_back(*aov);
        }
    }
    if (const Json* f = FieldReader::member(v, "accumulate"))
        q.accumulate = r.boolean(*f, "/accumulate");
    if (const Json* f = FieldReader::member(v, "exposure")) q.exposure = r.number(*f, "/exposure");
    if (const Json* f = FieldReader::member(v, "time")) q.time = r.number(*f, "/time");
    if (const Json* f = FieldReader::member(v, "filter"))
        q.filter = r.choice(*f, "/filter", {"none", "atrous"}) == 1;
    if (const Json* f = FieldReader::member(v, "camera")) q.camera = read_camera_override(r, *f);
    if (const Json* f = FieldReader::member(v, "frame")) *frame = read_frame(r, *f);
    if (const Json* f = FieldReader::member(v, "band")) {
        if (!f->is_array() || f->size() != 2)
            r.schema_error("/band", "expected [y0, rows]: the first row and the number of rows");
        const uint64_t y0 = r.integer((*f)[0], "/band/0", 0, MAX_RENDER_SIDE - 1);
        const uint64_t rows = r.integer((*f)[1], "/band/1", 1, MAX_RENDER_SIDE);
        q.band = RowBand{static_cast<uint32_t>(y0), static_cast<uint32_t>(rows)};
    }
    if (const Json* f = FieldReader::member(v, "split")) {
        *split = static_cast<uint32_t>(r.integer(*f, "/split", 1, MAX_RENDER_SPLIT));
        // Value errors: what a split cannot be combined with (the engine checks the band).
        if (*split > 1 && q.band)
            r.record_value_error("/split",
                                 "split and band do not combine: a band is one process's part "
                                 "of a split frame");
        else if (*split > 1 && q.accumulate)
            r.record_value_error("/split",
                                 "a split frame cannot accumulate: accumulated samples live on "
                                 "one process");
        else if (*split > q.height)
            r.record_value_error("/split", "split " + std::to_string(*split) +
                                               " asks for more bands than the frame's " +
                                               std::to_string(q.height) + " rows");
    }
    return q;
}

/// True when `t` is a decimal number as JSON writes one (RFC 8259, leading zeros allowed): no
/// sign but '-', no spaces, no hexadecimal, no "inf" or "nan".
bool is_decimal_number(std::string_view t) {
    std::size_t i = 0;
    const auto digits = [&] {
        const std::size_t start = i;
        while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
        return i > start;
    };
    if (i < t.size() && t[i] == '-') ++i;
    if (!digits()) return false;
    if (i < t.size() && t[i] == '.') {
        ++i;
        if (!digits()) return false;
    }
    if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
        ++i;
        if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
        if (!digits()) return false;
    }
    return i == t.size();
}

/// A query value as the JSON it stands for: a number, a boolean or (failing both) a string, so
/// the body reader reports type errors for queries too. Numbers are decimal only: `0x10` and
/// ` 16` are strings, hence type errors.
Json scalar_from_text(const std::string& text) {
    if (text == "true") return true;
    if (text == "false") return false;
    if (is_decimal_number(text)) {
        double d = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), d);
        if (ec == std::errc() && end == text.data() + text.size()) {
            // Range first: converting a double beyond uint64_t is undefined behaviour.
            if (d >= 0 && d < 1.8e19 && d == double(uint64_t(d))) return uint64_t(d);
            return d;
        }
    }
    return text;
}

Json list_from_text(const std::string& text, bool numbers) {
    Json out = Json::array();
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t comma = std::min(text.find(',', start), text.size());
        const std::string item = text.substr(start, comma - start);
        out.push_back(numbers ? scalar_from_text(item) : Json(item));
        start = comma + 1;
    }
    return out;
}

}  // namespace

Parsed<RenderRequest> parse_render_body(const Json& body, uint32_t* split,
                                        std::optional<FrameTarget>* frame) {
    FieldReader r;
    if (split) *split = 1;
    try {
        RenderRequest q = read_render(r, body, split, frame);
        if (r.value_error()) return Unexpected(*r.value_error());
        return q;
    } catch (const RequestFailure& f) {
        return Unexpected(f.problem());
    }
}

namespace {

/// Whether `key` names one of the camera's fields, and if so whether its value is a vector.
std::optional<bool> camera_field(const std::string& key) {
    std::optional<bool> vector;
    for_each_field<CameraFields>([&](const auto& row) {
        using T = typename std::decay_t<decltype(row)>::Type;
        if (row.info.name == key) vector = std::is_same_v<T, Vec3>;
    });
    return vector;
}

}  // namespace

Parsed<Json> query_to_body(const std::multimap<std::string, std::string>& params) {
    Json body = Json::object();
    for (const auto& [key, text] : params) {
        const std::optional<bool> camera_vector = camera_field(key);
        const bool camera = camera_vector.has_value();
        if (key == "frame_group" || key == "frame_instance") {
            // An id stays text, even one that looks like a number.
            const std::string member = key.substr(6);
            Json& frame = body["frame"];
            if (frame.is_object())
                return Unexpected(problem_at(ProblemType::InvalidRequest, "/frame",
                                             "give one of frame_group and frame_instance, once"));
            frame = Json{{member, text}};
            continue;
        }
        if (key == "camera") {
            // The override's members are parameters of their own; "camera" itself would have to
            // be an object, which a query cannot carry.
            return Unexpected(problem_at(ProblemType::InvalidRequest, "/camera",
                                         "query parameter 'camera' is not supported: give the "
                                         "camera's fields (eye, target, up, fov_y_deg, "
                                         "shutter_open, shutter_close) as parameters of their "
                                         "own"));
        }
        Json& slot = camera ? body["camera"][key] : body[key];
        if (!slot.is_null()) {
            return Unexpected(
                problem_at(ProblemType::InvalidRequest,
                           camera ? "/camera/" + key : "/" + escape_pointer_token(key),
                           "query parameter '" + key + "' is given more than once"));
        }
        if (key == "aovs") {
            slot = text.empty() ? Json::array() : list_from_text(text, false);
        } else if (key == "band" || camera_vector.value_or(false)) {
            slot = list_from_text(text, true);
        } else {
            slot = scalar_from_text(text);
        }
    }
    return body;
}

Parsed<RenderRequest> parse_render_query(const std::multimap<std::string, std::string>& params,
                                         uint32_t* split, std::optional<FrameTarget>* frame) {
    auto body = query_to_body(params);
    if (!body) return Unexpected(std::move(body).error());
    return parse_render_body(body.value(), split, frame);
}

}  // namespace strata::protocol
