#include "protocol/pick_parser.h"

#include "protocol/json_fields.h"
#include "protocol/render_parser.h"

namespace strata::protocol {

namespace {

/// Width and height, the same bounds as a render's.
void read_size(FieldReader& r, const Json& v, PickRequest& q) {
    q.width = uint32_t(r.integer(r.required(v, "", "width"), "/width", 1, MAX_RENDER_SIDE));
    q.height = uint32_t(r.integer(r.required(v, "", "height"), "/height", 1, MAX_RENDER_SIDE));
}

PickRequest read_pick_body(FieldReader& r, const Json& v) {
    r.expect_object(v, "", {"width", "height", "pixels", "camera", "time"});
    PickRequest q;
    read_size(r, v, q);
    const Json& pixels = r.required(v, "", "pixels");
    if (!pixels.is_array())
        r.schema_error("/pixels", "expected an array of [x, y] pixel positions");
    if (pixels.size() > MAX_PICK_PIXELS)
        r.schema_error("/pixels", "at most " + std::to_string(MAX_PICK_PIXELS) +
                                      " pixels per pick, not " + std::to_string(pixels.size()));
    q.pixels.reserve(pixels.size());
    for (std::size_t i = 0; i < pixels.size(); ++i) {
        const std::string ptr = "/pixels/" + std::to_string(i);
        const Json& p = pixels[i];
        if (!p.is_array() || p.size() != 2) r.schema_error(ptr, "expected [x, y]");
        q.pixels.push_back({uint32_t(r.integer(p[0], ptr + "/0", 0, MAX_RENDER_SIDE - 1)),
                            uint32_t(r.integer(p[1], ptr + "/1", 0, MAX_RENDER_SIDE - 1))});
    }
    if (const Json* f = FieldReader::member(v, "camera")) q.camera = read_camera_override(r, *f);
    if (const Json* f = FieldReader::member(v, "time")) q.time = r.number(*f, "/time");
    return q;
}

PickRequest read_pick_query(FieldReader& r, const Json& v) {
    r.expect_object(v, "", {"x", "y", "width", "height", "camera", "time"});
    PickRequest q;
    read_size(r, v, q);
    q.pixels.push_back({uint32_t(r.integer(r.required(v, "", "x"), "/x", 0, MAX_RENDER_SIDE - 1)),
                        uint32_t(r.integer(r.required(v, "", "y"), "/y", 0, MAX_RENDER_SIDE - 1))});
    if (const Json* f = FieldReader::member(v, "camera")) q.camera = read_camera_override(r, *f);
    if (const Json* f = FieldReader::member(v, "time")) q.time = r.number(*f, "/time");
    return q;
}

template <class Read>
Parsed<PickRequest> read_with(const Json& body, Read&& read) {
    FieldReader r;
    try {
        PickRequest q = read(r, body);
        if (r.value_error()) return Unexpected(*r.value_error());
        return q;
    } catch (const RequestFailure& f) {
        return Unexpected(f.problem());
    }
}

}  // namespace

Parsed<PickRequest> parse_pick_body(const Json& body) {
    return read_with(body, read_pick_body);
}

Parsed<PickRequest> parse_pick_query(const std::multimap<std::string, std::string>& params) {
    auto body = query_to_body(params);
    if (!body) return Unexpected(std::move(body).error());
    return read_with(body.value(), read_pick_query);
}

}  // namespace strata::protocol
