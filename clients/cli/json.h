#pragma once
// The JSON type of the command-line client (nlohmann's; scripts and answers are small).

#include <nlohmann/json.hpp>

namespace strata::cli {

using Json = nlohmann::json;

}  // namespace strata::cli
