#pragma once
// Access per scene (--tokens-file): which scene a request works on and the role it needs
// (auth.h, Role), and the answer when the token's grants fall short. A scene the token has no
// role in is answered as if it did not exist (404), so that a token for scene A cannot learn
// that B exists; a role too low for what the request does is 403.

#include <optional>
#include <string>
#include <string_view>

#include "protocol/problem.h"
#include "server/auth.h"

namespace strata::server {

struct Access {
    std::string scene;     ///< the scene the request works on; "" for none (any token may)
    Role role = Role::None;
};

/// What `method path` needs (path as the request has it, /v1/scenes/NAME/... included, NAME
/// decoded).
Access required_access(std::string_view method, std::string_view path);

/// Nothing when `grants` allow `need`; otherwise the problem to answer.
std::optional<protocol::Problem> refuse_access(const Grants& grants, const Access& need);

}  // namespace strata::server
