#include "server/healthcheck.h"

#include <cstdio>

#include <httplib.h>

namespace strata::server {

std::string healthcheck_target(const std::string& listen_host) {
    if (listen_host.empty() || listen_host == "0.0.0.0") return "127.0.0.1";
    if (listen_host == "::" || listen_host == "[::]") return "::1";
    return listen_host;
}

int run_healthcheck(const std::string& host, int port, std::chrono::milliseconds timeout) {
    const std::string target = healthcheck_target(host);
    const std::string url = (target.find(':') == std::string::npos ? target : "[" + target + "]") +
                            ":" + std::to_string(port) + "/readyz";
    try {
        httplib::Client client(target, port);
        client.set_connection_timeout(timeout);
        client.set_read_timeout(timeout);
        client.set_write_timeout(timeout);
        client.set_keep_alive(false);
        const auto res = client.Get("/readyz");
        if (!res) {
            std::printf("unhealthy: GET http://%s: %s error\n", url.c_str(),
                        httplib::to_string(res.error()).c_str());
            return 1;
        }
        const bool ok = res->status == 200;
        std::printf("%s: GET http://%s: %d\n", ok ? "healthy" : "unhealthy", url.c_str(),
                    res->status);
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::printf("unhealthy: GET http://%s: %s\n", url.c_str(), e.what());
        return 1;
    }
}

}  // namespace strata::server
