#pragma once
// Everything strata-server can be told on its command line (see cli.cpp for flags and defaults).

#include <cstddef>
#include <cstdint>
#include <string>

namespace strata::server {

struct ServerConfig {
    std::string host = "127.0.0.1";
    int port = 7070;          ///< 0: any free port (tests)
    std::size_t threads = 8;  ///< HTTP worker threads (rendering uses TBB's own pool)
    std::string data_dir;     ///< reserved for durability; unused for now
    std::size_t max_body_bytes = 256ull << 20;
    uint64_t max_pixels = 16ull << 20;  ///< width * height of one render
    std::size_t max_json_depth = 64;
    std::size_t max_array_elements = 1u << 26;
    int read_timeout_s = 30;
    int write_timeout_s = 30;
    int keep_alive_timeout_s = 5;
    std::string token;  ///< bearer token; empty: no authentication
    bool demo = false;  ///< start with the demo scene
};

}  // namespace strata::server
