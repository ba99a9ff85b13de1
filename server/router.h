#pragma once
// Route registration on top of httplib: POST bodies read through a capped content reader, and
// a 405 with `Allow` for every method a known path does not serve.

#include <functional>
#include <map>
#include <set>
#include <string>

#include <httplib.h>

namespace strata::server {

class Router {
public:
    using Handler = std::function<void(const httplib::Request&, httplib::Response&)>;
    /// A POST handler gets the whole body, already read and within the size cap.
    using BodyHandler =
        std::function<void(const httplib::Request&, httplib::Response&, std::string&& body)>;

    Router(httplib::Server& http, std::size_t max_body_bytes)
        : m_http(http), m_max_body(max_body_bytes) {}

    /// GET (and HEAD) on `pattern`, an httplib regex.
    void get(const std::string& pattern, Handler handler);
    void post(const std::string& pattern, BodyHandler handler);

    /// Registers the 405 answers; call once after every route.
    void finish();

private:
    httplib::Server& m_http;
    std::size_t m_max_body;
    std::map<std::string, std::set<std::string>> m_methods;  ///< pattern -> methods served
};

}  // namespace strata::server
