#pragma once
// Scripted edit sequences (protocol/scripts.md): JSON Lines, one step per line.
//
//   {"edits": [...]}                                  apply a batch
//   {"commit": {}}                                    run a commit
//   {"plan": {}}                                      ask what the next commit would do
//   {"render": {...}, "out": "frames/f{n}.png"}       render (and save the frame)
//   {"repeat": N, "var": "n", "steps": [...]}         play steps N times, n = 0 .. N-1
//   {"pick": {"x": 3, "y": 4, "width": 8, "height": 8}}  what lies under one pixel
//   {"list": "instances", "filter": {"mesh": "rock"}}  list a collection (every page)
//
// Commit, plan, render, pick and list steps may carry "expect" (script_expect.h); any step may
// carry a "label" shown in the table and in failures. Blank lines and lines starting with '#' are
// comments. A script is checked whole when it loads: every error names its line.

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "clients/cli/script_expect.h"
#include "clients/cli/script_template.h"

namespace strata::cli {

enum class StepKind : uint8_t { Edits, Commit, Plan, Render, Repeat, Pick, List };

/// "edits", "commit", "plan", "render", "repeat", "pick" or "list".
const char* step_kind_name(StepKind k);

/// One step as written, compiled.
struct Step {
    StepKind kind = StepKind::Commit;
    std::size_t line = 0;  ///< 1-based line of the script the step is written on
    std::string label;
    /// Edits: the edits array; Render: the request body; Pick: the pixel, image size and camera;
    /// List: the filter (query parameters).
    std::optional<JsonTemplate> body;
    std::string collection;              ///< List: meshes, instances, materials, ...
    std::optional<StringTemplate> out;   ///< Render: where to save the frame
    std::optional<Expectation> expect;   ///< Commit, Plan, Render, Pick, List
    std::optional<CountTemplate> count;  ///< Repeat
    std::string var;                     ///< Repeat: the iteration variable
    std::vector<Step> steps;             ///< Repeat: its steps
};

/// A loaded script.
struct Script {
    std::string name;  ///< the file name (or "-"), for messages
    std::vector<Step> steps;
};

/// Loads a script from text; `name` is used in messages.
Outcome<Script> load_script(std::istream& in, const std::string& name);
/// Loads a script file ("-": standard input).
Outcome<Script> load_script_file(const std::string& path);

/// Parses one line of JSON strictly: RFC 8259, no trailing data, no duplicate keys.
Outcome<Json> parse_json_strict(const std::string& text);

}  // namespace strata::cli
