#include "clients/cli/commands.h"

#include "clients/cli/asset_pack.h"
#include "clients/cli/image_files.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>

namespace strata::cli {

namespace {

std::string fixed(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    return buf;
}

/// Prints a report answer (commit or plan); returns the exit code.
int print_report(const Console& c, const Transport& t, const char* what, const Reply& reply) {
    int code = OK;
    const auto doc = json_answer(c, t, what, reply, code);
    if (!doc) return code;
    c.out << (c.json ? doc->dump() : format_report(*doc)) << '\n';
    return OK;
}

void entries(std::string& out, const Json& list, const char* what) {
    if (!list.is_array()) return;
    for (const Json& e : list) {
        if (e.is_string()) {
            out += "\n  " + std::string(what) + "  " + e.get<std::string>();
            continue;
        }
        out += "\n  " + std::string(what) + "  " + e.value("mesh", std::string("?")) + "  " +
               e.value("reason", std::string()) + "  " +
               std::to_string(e.value("primitives", uint64_t(0))) + " prims";
        if (e.contains("ms")) out += "  " + fixed(e["ms"].get<double>()) + " ms";
        if (e.contains("detail")) out += "  (" + e["detail"].get<std::string>() + ")";
    }
}

}  // namespace

int refused(const Console& c, const Transport& t, const char* what, const Reply& reply) {
    c.err << "strata: " << what << " failed on " << t.describe() << ": " << describe_failure(reply)
          << '\n';
    return REFUSED;
}

std::optional<Json> json_answer(const Console& c, const Transport& t, const std::string& what,
                                const Reply& reply, int& code) {
    if (!reply.ok()) {
        code = refused(c, t, what.c_str(), reply);
        return std::nullopt;
    }
    Json doc = Json::parse(reply.body, nullptr, false);
    if (doc.is_discarded()) {
        c.err << "strata: " << what << ": the answer from " << t.describe() << " is not JSON\n";
        code = REFUSED;
        return std::nullopt;
    }
    return doc;
}

std::string report_summary(const Json& r) {
    const Json tlas = r.value("tlas", Json::object());
    std::string out = std::string(r.value("planned", false) ? "plan for v" : "commit v") +
                      std::to_string(r.value("version", uint64_t(0))) + ": tlas " +
                      tlas.value("action", std::string("?")) + " (" +
                      std::to_string(tlas.value("instances", uint64_t(0))) + " instances), " +
                      std::to_string(r.value("blas_rebuilds", 0)) + " rebuilds, " +
                      std::to_string(r.value("blas_refits", 0)) + " refits, " +
                      std::to_string(r.value("primitives_built", uint64_t(0))) +
                      " primitives built, " +
                      std::to_string(r.value("primitives_refit", uint64_t(0))) + " refit";
    if (r.contains("ms")) out += ", " + fixed(r["ms"].get<double>()) + " ms";
    return out;
}

std::string format_report(const Json& r) {
    std::string out = report_summary(r);
    entries(out, r.value("rebuilt", Json::array()), "rebuilt ");
    entries(out, r.value("refit", Json::array()), "refit   ");
    entries(out, r.value("released", Json::array()), "released");
    return out;
}

int run_edit(Transport& t, const Console& c, const std::string& file,
             const std::optional<std::string>& if_match) {
    std::string text;
    if (file == "-") {
        text.assign(std::istreambuf_iterator<char>(std::cin), {});
    } else {
        std::ifstream in(file, std::ios::binary);
        if (!in) {
            c.err << "strata: cannot open '" << file << "'\n";
            return BAD_INPUT;
        }
        text.assign(std::istreambuf_iterator<char>(in), {});
    }
    // A bare array of edits is wrapped; anything else goes to the server as it is, so that the
    // server's own validation answers (with pointers into the file).
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && text[first] == '[') text = "{\"edits\": " + text + "}";
    int code = OK;
    const auto doc = json_answer(c, t, "edit", t.edits(std::move(text), if_match), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
    } else {
        c.out << "v" << doc->value("version", uint64_t(0)) << ": "
              << doc->value("applied", uint64_t(0)) << " edits applied\n";
    }
    return OK;
}

Json camera_json(const CameraOverride& o) {
    Json camera = Json::object();
    if (!o.eye.empty()) camera["eye"] = o.eye;
    if (!o.target.empty()) camera["target"] = o.target;
    if (!o.up.empty()) camera["up"] = o.up;
    if (o.fov_y_deg) camera["fov_y_deg"] = *o.fov_y_deg;
    return camera;
}

std::optional<std::string> render_body(const RenderArgs& a, std::string& error) {
    Json body = Json::object();
    if (a.width) body["width"] = *a.width;
    if (a.height) body["height"] = *a.height;
    if (a.spp) body["spp"] = *a.spp;
    const char* named = format_of_file_name(a.out);
    const std::string by_name = named ? named : "";
    if (a.format && !by_name.empty() && *a.format != by_name) {
        error = "--format " + *a.format + " does not match the file name '" + a.out + "'";
        return std::nullopt;
    }
    if (a.format) {
        body["format"] = *a.format;
    } else if (!by_name.empty()) {
        body["format"] = by_name;
    }
    if (a.compression) body["compression"] = *a.compression;
    if (!a.aovs.empty()) body["aovs"] = a.aovs;
    if (a.exposure) body["exposure"] = *a.exposure;
    if (a.accumulate) body["accumulate"] = true;
    if (a.filter) body["filter"] = *a.filter;
    if (a.split) body["split"] = *a.split;
    if (a.time) body["time"] = *a.time;
    const Json camera = camera_json(a.camera);
    if (!camera.empty()) body["camera"] = camera;
    if (a.frame_group && a.frame_instance) {
        error = "give --frame-group or --frame-instance, not both";
        return std::nullopt;
    }
    if (a.frame_group) body["frame"] = {{"group", *a.frame_group}};
    if (a.frame_instance) body["frame"] = {{"instance", *a.frame_instance}};
    return body.dump();
}

int run_render(Transport& t, const Console& c, const RenderArgs& args) {
    std::string error;
    const auto body = render_body(args, error);
    if (!body) {
        c.err << "strata: " << error << '\n';
        return BAD_INPUT;
    }
    const Reply reply = t.render(*body);
    if (!reply.ok()) return refused(c, t, "render", reply);
    std::ofstream file(args.out, std::ios::binary | std::ios::trunc);
    file.write(reply.body.data(), std::streamsize(reply.body.size()));
    file.close();
    if (!file) {
        c.err << "strata: cannot write '" << args.out << "'\n";
        return REFUSED;
    }
    const uint64_t version = etag_version(reply).value_or(0);
    if (c.json) {
        c.out << Json{{"out", args.out},
                      {"bytes", reply.body.size()},
                      {"content_type", reply.content_type},
                      {"version", version},
                      {"rebuild", reply.header("X-Strata-Rebuild")}}
                     .dump()
              << '\n';
    } else {
        c.out << "wrote " << args.out << " (" << reply.body.size() << " bytes, "
              << reply.content_type << ", v" << version << ")\n"
              << "commit: " << reply.header("X-Strata-Rebuild") << '\n';
    }
    return OK;
}

int run_commit(Transport& t, const Console& c) {
    return print_report(c, t, "commit", t.commit());
}

int run_plan(Transport& t, const Console& c) {
    return print_report(c, t, "plan", t.plan());
}

int run_stats(Transport& t, const Console& c) {
    int code = OK;
    const auto doc = json_answer(c, t, "stats", t.stats(), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    c.out << "version " << doc->value("version", uint64_t(0)) << "\n";
    if (doc->contains("memory_bytes")) {
        const Json& memory = (*doc)["memory_bytes"];
        c.out << "memory  blas " << memory.value("blas", int64_t(0)) << " bytes, tlas "
              << memory.value("tlas", int64_t(0)) << " bytes\n";
        const Json compaction = memory.value("compaction", Json::object());
        if (compaction.value("meshes", uint64_t(0)) != 0)
            c.out << "compaction  " << compaction.value("meshes", uint64_t(0)) << " meshes, blas "
                  << compaction.value("uncompacted_bytes", int64_t(0)) << " bytes at full size, "
                  << compaction.value("bytes", int64_t(0)) << " compacted ("
                  << compaction.value("saved_bytes", int64_t(0)) << " saved)\n";
    }
    c.out << "counters\n";
    const Json counters = doc->value("counters", Json::object());
    for (const auto& [name, value] : counters.items()) {
        std::string key = name;
        key.resize(std::max<std::size_t>(key.size(), 18), ' ');
        c.out << "  " << key << " "
              << (value.is_number_float() ? fixed(value.get<double>()) : value.dump()) << '\n';
    }
    const Json last = doc->value("last_report", Json());
    c.out << "last " << (last.is_object() ? format_report(last) : "commit: none yet") << '\n';
    return OK;
}

int run_snapshot_save(Transport& t, const Console& c, const std::string& file,
                      std::optional<uint64_t> at_version,
                      const std::optional<std::string>& at_time) {
    const Reply reply = t.get_snapshot(at_version, at_time);
    if (!reply.ok()) return refused(c, t, "snapshot save", reply);
    if (file == "-") {
        c.out.write(reply.body.data(), std::streamsize(reply.body.size()));
        return OK;
    }
    const std::string tmp = file + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(reply.body.data(), std::streamsize(reply.body.size()));
        if (!out.flush()) {
            c.err << "strata: cannot write '" << tmp << "'\n";
            std::remove(tmp.c_str());
            return BAD_INPUT;
        }
    }
    if (std::rename(tmp.c_str(), file.c_str()) != 0) {
        c.err << "strata: cannot rename '" << tmp << "' to '" << file << "'\n";
        std::remove(tmp.c_str());
        return BAD_INPUT;
    }
    const auto version = etag_version(reply);
    if (c.json) {
        c.out << Json{{"file", file}, {"bytes", reply.body.size()},
                      {"version", version ? Json(*version) : Json(nullptr)}}
                     .dump()
              << '\n';
    } else {
        c.out << "saved version " << (version ? std::to_string(*version) : "?") << " to " << file
              << " (" << reply.body.size() << " bytes)\n";
    }
    return OK;
}

int pack_upload(const Console& c, const ImportArgs& args, std::string& bytes,
                std::multimap<std::string, std::string>& query) {
    // An .obj with MTL files or a .gltf with external files goes as a tar of them all (unless
    // --format says how to read the file alone); a missing side file stops here.
    PackedAsset packed;
    if (args.format.empty()) {
        std::string error;
        if (!pack_asset(args.file, packed, error)) {
            c.err << "strata: " << error << '\n';
            return BAD_INPUT;
        }
        bytes = std::move(packed.bytes);
    } else {
        std::ifstream in(args.file, std::ios::binary);
        if (!in) {
            c.err << "strata: cannot open '" << args.file << "'\n";
            return BAD_INPUT;
        }
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const std::size_t slash = args.file.find_last_of('/');
    const std::string name = slash == std::string::npos ? args.file : args.file.substr(slash + 1);
    if (packed.archive) {
        query.emplace("name", name.substr(0, name.rfind('.')) + ".tar");
        query.emplace("format", "tar");
        if (!c.json)
            for (const std::string& f : packed.side_files)
                c.err << "strata: packing " << f << " with " << packed.model_path << '\n';
    } else {
        query.emplace("name", name);
    }
    if (!args.prefix.empty()) query.emplace("prefix", args.prefix);
    if (!args.format.empty()) query.emplace("format", args.format);
    if (!args.parent.empty()) query.emplace("parent", args.parent);
    if (!args.instance) query.emplace("instance", "false");
    return OK;
}

void print_warnings(const Console& c, const Json& answer) {
    for (const Json& w : answer.value("warnings", Json::array()))
        if (w.is_string()) c.err << "strata: warning: " << w.get<std::string>() << '\n';
}

int run_import(Transport& t, const Console& c, const ImportArgs& args) {
    std::string bytes;
    std::multimap<std::string, std::string> query;
    if (const int packed = pack_upload(c, args, bytes, query); packed != OK) return packed;
    int code = OK;
    const auto doc =
        json_answer(c, t, "import " + args.file, t.import_asset(std::move(bytes), query), code);
    if (!doc) return code;
    print_warnings(c, *doc);
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    auto count = [&](const char* key) { return doc->value(key, Json::array()).size(); };
    c.out << "imported " << args.file << ": " << count("meshes") << " meshes, "
          << count("materials") << " materials, " << count("groups") << " groups, "
          << count("instances")
          << " instances; the scene is now version " << doc->value("version", 0) << '\n';
    return OK;
}

int run_snapshot_load(Transport& t, const Console& c, const std::string& file) {
    std::string bytes;
    if (file == "-") {
        bytes.assign(std::istreambuf_iterator<char>(std::cin), {});
    } else {
        std::ifstream in(file, std::ios::binary);
        if (!in) {
            c.err << "strata: cannot open '" << file << "'\n";
            return BAD_INPUT;
        }
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    int code = OK;
    const auto doc = json_answer(c, t, "snapshot load", t.put_snapshot(std::move(bytes)), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
    } else {
        c.out << "loaded " << file << ": the scene is now version " << doc->value("version", 0)
              << '\n';
    }
    return OK;
}

}  // namespace strata::cli
