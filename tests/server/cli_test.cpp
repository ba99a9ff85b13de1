// The command line and its STRATA_* environment variables: precedence, tokens, the loopback rule.

#include "server/cli.h"

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "engine/accel/tlas.h"
#include "server/auth.h"
#include "server/past_scenes.h"

namespace strata::server::test {
namespace {

/// Sets environment variables for one test and restores the previous values afterwards.
class ScopedEnv {
public:
    ScopedEnv(std::initializer_list<std::pair<const char*, const char*>> vars) {
        for (const auto& [name, value] : vars) {
            const char* old = std::getenv(name);
            m_saved.emplace_back(name, old ? std::optional<std::string>(old) : std::nullopt);
            if (value) {
                setenv(name, value, 1);
            } else {
                unsetenv(name);
            }
        }
    }
    ~ScopedEnv() {
        for (const auto& [name, old] : m_saved) {
            if (old) {
                setenv(name.c_str(), old->c_str(), 1);
            } else {
                unsetenv(name.c_str());
            }
        }
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    std::vector<std::pair<std::string, std::optional<std::string>>> m_saved;
};

/// Every variable the server reads, unset, so that the caller's environment cannot leak in.
ScopedEnv clean_env() {
    return ScopedEnv{{"STRATA_HOST", nullptr},       {"STRATA_PORT", nullptr},
                     {"STRATA_DATA", nullptr},       {"STRATA_TOKEN", nullptr},
                     {"STRATA_TOKEN_FILE", nullptr}, {"STRATA_INSECURE", nullptr},
                     {"STRATA_LOG_LEVEL", nullptr}, {"STRATA_TLAS", nullptr},
                     {"STRATA_LOG", nullptr}, {"STRATA_TOKENS_FILE", nullptr}};
}

/// Parses `args` (after the program name); fails the test on a usage error.
CommandLine parse(std::vector<std::string> args) {
    args.insert(args.begin(), "strata-server");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    auto parsed = parse_command_line(int(argv.size()), argv.data());
    EXPECT_TRUE(std::holds_alternative<CommandLine>(parsed));
    return std::holds_alternative<CommandLine>(parsed) ? std::get<CommandLine>(parsed)
                                                       : CommandLine{};
}

std::string write_token_file(const std::string& content) {
    const std::string path = ::testing::TempDir() + "strata-cli-token";
    std::ofstream(path) << content;
    return path;
}

TEST(CommandLine, OptionsFallBackToStrataEnvironmentVariables) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_HOST", "0.0.0.0"},
                  {"STRATA_PORT", "8081"},
                  {"STRATA_DATA", "/data"},
                  {"STRATA_INSECURE", "1"},
                  {"STRATA_LOG_LEVEL", "warn"}};
    CommandLine cl = parse({});
    EXPECT_EQ(cl.config.host, "0.0.0.0");
    EXPECT_EQ(cl.config.port, 8081);
    EXPECT_EQ(cl.config.data_dir, "/data");
    EXPECT_TRUE(cl.insecure);
    EXPECT_EQ(cl.log_level, "warn");
    EXPECT_EQ(finish_config(cl), "");
}

TEST(CommandLine, TheTlasStrategyIsIncrementalUnlessToldOtherwise) {
    auto base = clean_env();
    EXPECT_EQ(parse({}).config.tlas, "incremental");
    EXPECT_EQ(parse({"--tlas", "embree"}).config.tlas, "embree");
    {
        ScopedEnv env{{"STRATA_TLAS", "embree"}};
        EXPECT_EQ(parse({}).config.tlas, "embree");
    }
    EXPECT_EQ(parse({}).config.tlas_array_min_instances, TlasPolicy{}.array_min_instances);
    CommandLine cl = parse({"--tlas-max-dynamic-fraction", "0.2", "--tlas-min-instances", "10",
                            "--tlas-background-merge", "false", "--tlas-array-min-instances", "0"});
    EXPECT_DOUBLE_EQ(cl.config.tlas_max_dynamic_fraction, 0.2);
    EXPECT_EQ(cl.config.tlas_min_instances, 10u);
    EXPECT_FALSE(cl.config.tlas_background_merge);
    EXPECT_EQ(cl.config.tlas_array_min_instances, 0u);

    std::vector<std::string> args = {"strata-server", "--tlas", "partitioned"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    EXPECT_TRUE(std::holds_alternative<int>(parse_command_line(int(argv.size()), argv.data())));
}

TEST(CommandLine, TheEditLogComesFromLogOrStrataLogAndABadUrlIsRefused) {
    auto base = clean_env();
    EXPECT_EQ(parse({}).config.log_url, "");
    {
        ScopedEnv env{{"STRATA_LOG", "redis://redis:6379/scene"}};
        CommandLine cl = parse({"--log-snapshot-every", "50", "--min-version-wait-ms", "250"});
        EXPECT_EQ(cl.config.log_url, "redis://redis:6379/scene");
        EXPECT_EQ(cl.config.log_snapshot_every, 50u);
        EXPECT_EQ(cl.config.min_version_wait_ms, 250);
        EXPECT_EQ(finish_config(cl), "");
    }
    CommandLine bad = parse({"--log", "redis://redis:6379"});
    EXPECT_NE(finish_config(bad).find("the stream name is missing"), std::string::npos);
}

TEST(CommandLine, TheCommandLineWinsOverTheEnvironment) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_PORT", "8081"}, {"STRATA_HOST", "0.0.0.0"}};
    CommandLine cl = parse({"--port", "9090", "--host", "127.0.0.1"});
    EXPECT_EQ(cl.config.port, 9090);
    EXPECT_EQ(cl.config.host, "127.0.0.1");
}

TEST(CommandLine, TheImportFlagsBoundTheImportersSandbox) {
    auto base = clean_env();
    const auto defaults = api_limits(parse({}).config).import_sandbox;
    EXPECT_TRUE(defaults.enabled);
    EXPECT_EQ(defaults.deadline_ms, 60000u);
    EXPECT_EQ(defaults.memory_mb, 2048u);
    const auto set =
        api_limits(parse({"--import-timeout", "5", "--import-memory-mb", "128"}).config)
            .import_sandbox;
    EXPECT_EQ(set.deadline_ms, 5000u);
    EXPECT_EQ(set.cpu_seconds, 5u);
    EXPECT_EQ(set.memory_mb, 128u);
}

TEST(CommandLine, ANonLoopbackHostNeedsATokenOrInsecure) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_HOST", "0.0.0.0"}, {"STRATA_INSECURE", "0"}};
    CommandLine cl = parse({});
    EXPECT_FALSE(cl.insecure);
    const std::string problem = finish_config(cl);
    EXPECT_NE(problem.find("STRATA_TOKEN"), std::string::npos) << problem;
    EXPECT_NE(problem.find("STRATA_INSECURE=1"), std::string::npos) << problem;
}

TEST(CommandLine, TheTokenCanComeFromStrataToken) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_HOST", "0.0.0.0"}, {"STRATA_TOKEN", "  s3cret\n"}};
    CommandLine cl = parse({});
    EXPECT_EQ(finish_config(cl), "");
    EXPECT_EQ(cl.config.token, "s3cret");
    EXPECT_EQ(cl.token_source, "STRATA_TOKEN");
}

TEST(CommandLine, TheTokenFileCanComeFromStrataTokenFile) {
    auto base = clean_env();
    const std::string path = write_token_file("fr0m-file\n");
    ScopedEnv env{{"STRATA_HOST", "0.0.0.0"}, {"STRATA_TOKEN_FILE", path.c_str()}};
    CommandLine cl = parse({});
    EXPECT_EQ(finish_config(cl), "");
    EXPECT_EQ(cl.config.token, "fr0m-file");
    EXPECT_EQ(cl.token_source, "token file '" + path + "'");
}

TEST(CommandLine, ATokenFileAndStrataTokenTogetherAreRefused) {
    auto base = clean_env();
    const std::string path = write_token_file("fr0m-file\n");
    ScopedEnv env{{"STRATA_TOKEN", "fr0m-env"}};
    CommandLine cl = parse({"--token-file", path});
    const std::string problem = finish_config(cl);
    EXPECT_NE(problem.find("one way only"), std::string::npos) << problem;
    EXPECT_EQ(cl.config.token, "");
}

TEST(CommandLine, ATokensFileGivesRolesPerSceneAndExcludesASingleToken) {
    auto base = clean_env();
    const std::string path = ::testing::TempDir() + "strata-cli-tokens";
    std::ofstream(path) << "alice a:admin\nbob *:read\n";
    {
        ScopedEnv env{{"STRATA_HOST", "0.0.0.0"}, {"STRATA_TOKENS_FILE", path.c_str()}};
        CommandLine cl = parse({});
        EXPECT_EQ(finish_config(cl), "");  // a tokens file is a token for the loopback rule
        ASSERT_TRUE(cl.config.tokens);
        EXPECT_EQ(cl.config.tokens->entries.size(), 2u);
        EXPECT_EQ(cl.token_source, "tokens file '" + path + "' (2 tokens)");
    }
    {
        ScopedEnv env{{"STRATA_TOKEN", "s3cret"}};
        CommandLine cl = parse({"--tokens-file", path});
        EXPECT_NE(finish_config(cl).find("give one"), std::string::npos);
    }
    CommandLine peers = parse({"--tokens-file", path, "--peers", "http://127.0.0.1:9"});
    EXPECT_NE(finish_config(peers).find("--peers needs"), std::string::npos);
    std::ofstream(path) << "alice a:superuser\n";
    CommandLine bad = parse({"--tokens-file", path});
    const std::string problem = finish_config(bad);
    EXPECT_NE(problem.find("line 1"), std::string::npos) << problem;
    EXPECT_EQ(problem.find("alice"), std::string::npos) << problem;
}

TEST(CommandLine, ABadTokenIsRefusedWithoutRepeatingIt) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_TOKEN", "half secret"}};
    CommandLine cl = parse({});
    const std::string problem = finish_config(cl);
    EXPECT_NE(problem.find("STRATA_TOKEN holds whitespace"), std::string::npos) << problem;
    EXPECT_EQ(problem.find("secret"), std::string::npos) << problem;
}

TEST(CommandLine, HealthcheckIsAFlagWithNoVariable) {
    auto base = clean_env();
    ScopedEnv env{{"STRATA_HEALTHCHECK", "1"}};
    EXPECT_FALSE(parse({}).healthcheck);
    EXPECT_TRUE(parse({"--healthcheck"}).healthcheck);
}

}  // namespace
}  // namespace strata::server::test
