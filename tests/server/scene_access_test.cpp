// Access per scene (--tokens-file): the file's format, the role each request needs, and a real
// server that lets each token do what its roles say, hiding the scenes it has none in.

#include <gmock/gmock.h>

#include "server/access.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

const char* const TOKENS = R"(# who may do what
alice a:admin b:read
bob   b:edit default:read
root  *:admin
viewer *:read
)";

TEST(TokensFile, ReadsEveryTokenAndItsRoles) {
    auto table = parse_token_table(TOKENS, "test");
    ASSERT_TRUE(table.has_value()) << table.error().message;
    ASSERT_EQ(table->entries.size(), 4u);
    const Grants& alice = *table->entries[0].second;
    EXPECT_EQ(alice.in("a"), Role::Admin);
    EXPECT_EQ(alice.in("b"), Role::Read);
    EXPECT_EQ(alice.in("default"), Role::None);
    EXPECT_EQ(table->entries[2].second->in("anything"), Role::Admin);
    EXPECT_EQ(match_grants(*table, "Bearer bob").get(), table->entries[1].second.get());
    EXPECT_EQ(match_grants(*table, "Bearer bo"), nullptr);
    EXPECT_EQ(match_grants(*table, "Bearer "), nullptr);
}

TEST(TokensFile, RefusesWhatItCannotRead) {
    for (const char* bad : {"", "# only a comment\n", "alone\n", "t a:owner\n", "t a\n",
                            "t A:read\n", "t a:read a:edit\n", "t *:read *:edit\n",
                            "t a:read\nt b:read\n", "t\x01 a:read\n", "t a:read \xc3\xa9\n"}) {
        auto table = parse_token_table(bad, "tokens");
        EXPECT_FALSE(table.has_value()) << bad;
        if (!table) {
            EXPECT_THAT(table.error().message, ::testing::StartsWith("tokens")) << bad;
        }
    }
    // An error names the line, never the token.
    auto table = parse_token_table("good a:read\nsecret-token a:root\n", "tokens");
    ASSERT_FALSE(table.has_value());
    EXPECT_THAT(table.error().message, ::testing::HasSubstr("line 2"));
    EXPECT_THAT(table.error().message, ::testing::Not(::testing::HasSubstr("secret")));
}

TEST(RequiredAccess, ReadsEditsAndAdministration) {
    const auto need = [](const char* method, const char* path) {
        const Access a = required_access(method, path);
        return a.scene + ":" + role_name(a.role);
    };
    EXPECT_EQ(need("GET", "/v1/scene"), "default:read");
    EXPECT_EQ(need("POST", "/v1/render"), "default:read");
    EXPECT_EQ(need("POST", "/v1/pick"), "default:read");
    EXPECT_EQ(need("POST", "/v1/edits"), "default:edit");
    EXPECT_EQ(need("POST", "/v1/scene/snapshot"), "default:edit");
    EXPECT_EQ(need("GET", "/metrics"), "default:read");
    EXPECT_EQ(need("GET", "/v1/scenes"), ":none");
    EXPECT_EQ(need("GET", "/v1/openapi.json"), ":none");
    EXPECT_EQ(need("GET", "/v1/scenes/a"), "a:read");
    EXPECT_EQ(need("PUT", "/v1/scenes/a"), "a:admin");
    EXPECT_EQ(need("DELETE", "/v1/scenes/a"), "a:admin");
    EXPECT_EQ(need("GET", "/v1/scenes/a/stream"), "a:read");
    EXPECT_EQ(need("POST", "/v1/scenes/a/undo"), "a:edit");
    EXPECT_EQ(need("POST", "/v1/scenes/a/render"), "a:read");
}

class SceneAccess : public ::testing::Test {
protected:
    static ServerConfig with_tokens() {
        ServerConfig c;
        c.tokens = std::make_shared<const TokenTable>(parse_token_table(TOKENS, "test").value());
        return c;
    }
    static httplib::Headers as(const std::string& token) {
        return {{"Authorization", "Bearer " + token}};
    }
    Reply put(const std::string& path, const std::string& token) {
        auto c = srv.client();
        return to_reply(c.Put(path.c_str(), as(token), "", "application/json"));
    }
    Reply del(const std::string& path, const std::string& token) {
        auto c = srv.client();
        return to_reply(c.Delete(path.c_str(), as(token)));
    }
    Reply edit(const std::string& prefix, const std::string& token) {
        return srv.post(prefix + "/edits", Json{{"edits", {triangle_mesh("m")}}}, as(token));
    }
    std::vector<std::string> listed(const std::string& token) {
        std::vector<std::string> names;
        const Json list = srv.get("/v1/scenes", as(token)).json();
        for (const Json& s : list["scenes"]) names.push_back(s["name"]);
        return names;
    }
    TestServer srv{with_tokens()};
};

TEST_F(SceneAccess, EachTokenDoesWhatItsRolesSay) {
    EXPECT_EQ(srv.get("/v1/scenes").status, 401);  // a token is still needed
    EXPECT_EQ(put("/v1/scenes/a", "alice").status, 201);
    EXPECT_EQ(put("/v1/scenes/b", "root").status, 201);
    expect_problem(put("/v1/scenes/c", "alice"), 403, "forbidden");  // admin of a only
    expect_problem(put("/v1/scenes/b", "bob"), 403, "forbidden");    // edit is not admin

    EXPECT_EQ(edit("/v1/scenes/a", "alice").status, 200);
    expect_problem(edit("/v1/scenes/b", "alice"), 403, "forbidden");  // read only in b
    EXPECT_EQ(srv.get("/v1/scenes/b/scene", as("alice")).status, 200);
    EXPECT_EQ(srv.get("/v1/scenes/b/render?width=8&height=8", as("alice")).status, 200);
    EXPECT_EQ(edit("/v1/scenes/b", "bob").status, 200);
    expect_problem(edit("/v1/scenes/default", "bob"), 403, "forbidden");
    expect_problem(edit("/v1", "bob"), 403, "forbidden");  // the unprefixed paths are "default"
    EXPECT_EQ(srv.get("/v1/scene", as("bob")).status, 200);
    expect_problem(srv.get("/v1/scene", as("alice")), 403, "forbidden");
    expect_problem(edit("/v1", "viewer"), 403, "forbidden");
    EXPECT_EQ(edit("/v1", "root").status, 200);
    expect_problem(del("/v1/scenes/a", "viewer"), 403, "forbidden");
    EXPECT_EQ(del("/v1/scenes/a", "alice").status, 204);
}

TEST_F(SceneAccess, ASceneWithoutARoleCannotBeSeen) {
    ASSERT_EQ(put("/v1/scenes/a", "root").status, 201);
    ASSERT_EQ(put("/v1/scenes/secret", "root").status, 201);
    EXPECT_THAT(listed("alice"), ::testing::ElementsAre("a"));
    EXPECT_THAT(listed("bob"), ::testing::ElementsAre("default"));
    EXPECT_THAT(listed("viewer"), ::testing::ElementsAre("default", "a", "secret"));
    // An existing scene the token has no role in answers as a missing one does.
    const Reply hidden = srv.get("/v1/scenes/secret", as("alice"));
    const Reply missing = srv.get("/v1/scenes/nothing", as("alice"));
    expect_problem(hidden, 404, "not-found", "/scene");
    expect_problem(missing, 404, "not-found", "/scene");
    expect_problem(srv.get("/v1/scenes/secret/scene", as("alice")), 404, "not-found");
    expect_problem(edit("/v1/scenes/secret", "alice"), 404, "not-found");
    // Making or deleting it is 403 whether it exists or not.
    expect_problem(put("/v1/scenes/secret", "alice"), 403, "forbidden");
    expect_problem(put("/v1/scenes/nothing", "alice"), 403, "forbidden");
    expect_problem(del("/v1/scenes/secret", "alice"), 403, "forbidden");
    expect_problem(del("/v1/scenes/nothing", "alice"), 403, "forbidden");
    // The stream takes the token in the query too, and checks the same roles.
    EXPECT_EQ(srv.get("/v1/scenes/secret/render?width=8&height=8&access_token=alice").status,
              404);
    EXPECT_EQ(srv.get("/v1/scenes/a/render?width=8&height=8&access_token=alice").status, 200);
}

}  // namespace
}  // namespace strata::server::test
