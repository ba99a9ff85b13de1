#pragma once
// `at_version` and `at_time` on a read, a render or a stream: the query parameters that ask for
// the scene as it was (past_scenes.h serves the engine), their description and their problems.

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "engine/core/expected.h"
#include "engine/core/result.h"
#include "protocol/openapi.h"
#include "protocol/problem.h"

namespace strata {
class Engine;
}

namespace strata::server {

/// The version `query` asks for with `at_version` or `at_time` (taken out of it), nullopt when
/// it asks for neither; a problem (pointer /at_version or /at_time) when the ask is malformed or
/// no version of `live`'s history matches the time.
Expected<std::optional<uint64_t>, protocol::Problem> asked_version(
    const Engine& live, std::multimap<std::string, std::string>& query);

/// The problem of a version PastScenes could not give: 404 at /at_version when the data
/// directory does not hold it (or there is none), else the error's own problem.
protocol::Problem past_version_problem(const Error& e);

/// Adds at_version, at_time and their 404 to a route's description; `how` says what loading a
/// version costs on this route.
void describe_past_version(protocol::RouteDoc& doc, const char* how);

}  // namespace strata::server
