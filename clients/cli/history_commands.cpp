// `strata undo`, `strata redo` and `strata history`: the scene's history (protocol/README.md,
// "POST /v1/undo, POST /v1/redo and GET /v1/history").

#include <string>

#include "clients/cli/commands.h"
#include "clients/cli/outcome.h"

namespace strata::cli {

namespace {

/// "v12  edit  2026-11-27T17:02:03.456Z  3 edits: add_mesh 1, add_instance 2  \"msg\"  undoable"
std::string entry_line(const Json& e) {
    std::string line = "v" + std::to_string(e.value("version", uint64_t(0)));
    const std::string kind = e.value("kind", std::string("edit"));
    line += "  " + kind;
    if (e.contains("target")) line += " of v" + std::to_string(e.value("target", uint64_t(0)));
    line += "  " + e.value("time", std::string());
    const uint64_t edits = e.value("edits", uint64_t(0));
    line += "  " + std::to_string(edits) + (edits == 1 ? " edit" : " edits");
    const char* sep = ": ";
    const Json ops = e.value("ops", Json::object());
    for (const auto& [op, n] : ops.items()) {
        line += sep + op + " " + n.dump();
        sep = ", ";
    }
    if (e.contains("message")) line += "  " + Json(e.value("message", std::string())).dump();
    if (e.value("undoable", false)) line += "  undoable";
    return line;
}

}  // namespace

int run_undo(Transport& t, const Console& c, bool redo,
             const std::optional<std::string>& if_match) {
    int code = OK;
    const auto doc = json_answer(c, t, redo ? "redo" : "undo", t.undo(redo, if_match), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
    } else {
        c.out << "v" << doc->value("version", uint64_t(0)) << ": " << (redo ? "redid v" : "undid v")
              << doc->value(redo ? "redone" : "undone", uint64_t(0)) << " ("
              << doc->value("applied", uint64_t(0)) << " edits applied)\n";
    }
    return OK;
}

int run_history(Transport& t, const Console& c, const HistoryArgs& args) {
    std::multimap<std::string, std::string> query;
    query.emplace("limit", std::to_string(args.page_size));
    uint64_t printed = 0;
    while (true) {
        int code = OK;
        const auto page = json_answer(c, t, "history", t.history(query), code);
        if (!page) return code;
        if (printed == 0 && !c.json) {
            const Json undo = page->value("undo", Json::object());
            const Json redo = page->value("redo", Json::object());
            c.err << "version " << page->value("version", uint64_t(0)) << ", "
                  << undo.value("depth", uint64_t(0)) << " to undo, "
                  << redo.value("depth", uint64_t(0)) << " to redo\n";
        }
        for (const Json& entry : page->value("entries", Json::array())) {
            if (args.max_items && printed == *args.max_items) return OK;
            c.out << (c.json ? entry.dump() : entry_line(entry)) << '\n';
            ++printed;
        }
        const Json next = page->value("next_cursor", Json(nullptr));
        if (!next.is_string()) break;
        query.erase("cursor");
        query.emplace("cursor", next.get<std::string>());
    }
    return OK;
}

}  // namespace strata::cli
