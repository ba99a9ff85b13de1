// `strata assets`, `strata assets show`, `strata assets delete` and `strata assets reimport`:
// imports as units (protocol/README.md, "Assets").

#include <string>

#include "clients/cli/commands.h"

namespace strata::cli {

namespace {

std::string number(const Json& v) {
    return v.is_number_integer() ? std::to_string(v.get<int64_t>()) : v.dump();
}

/// "[0,0,0]..[3,1,0]", or "no instances".
std::string bounds_text(const Json& bounds) {
    if (!bounds.is_object()) return "no instances";
    return bounds.value("min", Json()).dump() + ".." + bounds.value("max", Json()).dump();
}

/// "kit  kit.tar  2 meshes  2 materials  1 textures  1 groups  2 instances  [0,0,0]..[3,1,0]"
std::string asset_line(const Json& a) {
    std::string line = a.value("id", std::string("?")) + "  " + a.value("file", std::string());
    const Json counts = a.value("counts", Json::object());
    for (const char* kind : {"meshes", "materials", "textures", "groups", "instances"})
        line += "  " + number(counts.value(kind, Json(0))) + " " + kind;
    return line + "  " + bounds_text(a.value("bounds", Json()));
}

/// "2 meshes, 1 instances" for the non-empty lists of `doc` (an object of id lists).
std::string list_counts(const Json& doc) {
    std::string out;
    for (const char* kind : {"textures", "materials", "meshes", "groups", "instances"}) {
        const std::size_t n = doc.value(kind, Json::array()).size();
        if (n == 0) continue;
        out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + kind;
    }
    return out.empty() ? "nothing" : out;
}

}  // namespace

int run_assets(Transport& t, const Console& c) {
    int code = OK;
    const auto doc = json_answer(c, t, "assets", t.assets(std::nullopt), code);
    if (!doc) return code;
    for (const Json& a : doc->value("assets", Json::array()))
        c.out << (c.json ? a.dump() : asset_line(a)) << '\n';
    return OK;
}

int run_asset_show(Transport& t, const Console& c, const std::string& id) {
    int code = OK;
    const auto doc = json_answer(c, t, "assets show " + id, t.assets(id), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    c.out << asset_line(*doc) << '\n';
    for (const char* kind : {"textures", "materials", "meshes", "groups", "instances"})
        for (const Json& item : doc->value(kind, Json::array()))
            if (item.is_string()) c.out << "  " << kind << "  " << item.get<std::string>() << '\n';
    return OK;
}

int run_asset_delete(Transport& t, const Console& c, const std::string& id) {
    int code = OK;
    const auto doc = json_answer(c, t, "assets delete " + id, t.delete_asset(id), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    c.out << "deleted asset " << id << ": " << list_counts(doc->value("removed", Json::object()))
          << "; the scene is now version " << doc->value("version", 0) << '\n';
    return OK;
}

int run_asset_reimport(Transport& t, const Console& c, const std::string& id,
                       const ImportArgs& args) {
    std::string bytes;
    std::multimap<std::string, std::string> query;
    if (const int packed = pack_upload(c, args, bytes, query); packed != OK) return packed;
    int code = OK;
    const auto doc = json_answer(c, t, "assets reimport " + id,
                                 t.put_asset(id, std::move(bytes), query), code);
    if (!doc) return code;
    print_warnings(c, *doc);
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    c.out << (doc->value("replaced", false) ? "re-imported " : "imported ") << args.file
          << " as asset " << id << ": " << list_counts(*doc) << "; kept unchanged "
          << list_counts(doc->value("kept", Json::object())) << "; removed "
          << doc->value("removed", Json::array()).size() << "; the scene is now version "
          << doc->value("version", 0) << '\n';
    return OK;
}

}  // namespace strata::cli
