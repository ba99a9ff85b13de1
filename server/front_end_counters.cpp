#include "server/front_end_counters.h"

namespace strata::server {

void FrontEndCounters::write_prometheus(std::string& out) const {
    auto line = [&](const char* name, const char* type, const char* help, uint64_t v) {
        out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" +
               name + " " + std::to_string(v) + "\n";
    };
    line("strata_http_connections_open", "gauge", "Open client connections.", open.load());
    line("strata_http_requests_in_flight", "gauge",
         "Requests a worker is handling (this /metrics request included).", handling.load());
    line("strata_http_connections_accepted_total", "counter", "Connections accepted.",
         accepted.load());
    line("strata_http_connections_restricted_total", "counter",
         "Connections over a connection limit, served health checks only.", restricted.load());
    line("strata_http_connections_refused_total", "counter",
         "Connections closed at once, over every limit.", refused.load());
    line("strata_http_timeouts_total", "counter",
         "Requests that did not arrive, and answers not taken, in time.", timeouts.load());
    line("strata_http_clients_gone_total", "counter",
         "Clients that disconnected while their request was being handled.", client_gone.load());
}

}  // namespace strata::server
