#include "server/direct_response.h"

namespace strata::server {

const char* status_reason(int status) {
    switch (status) {
        case 100:
            return "Continue";
        case 200:
            return "OK";
        case 400:
            return "Bad Request";
        case 401:
            return "Unauthorized";
        case 404:
            return "Not Found";
        case 405:
            return "Method Not Allowed";
        case 408:
            return "Request Timeout";
        case 412:
            return "Precondition Failed";
        case 413:
            return "Content Too Large";
        case 414:
            return "URI Too Long";
        case 415:
            return "Unsupported Media Type";
        case 417:
            return "Expectation Failed";
        case 422:
            return "Unprocessable Content";
        case 429:
            return "Too Many Requests";
        case 431:
            return "Request Header Fields Too Large";
        case 500:
            return "Internal Server Error";
        case 501:
            return "Not Implemented";
        case 503:
            return "Service Unavailable";
        case 505:
            return "HTTP Version Not Supported";
        default:
            return "Unknown";
    }
}

std::string response_bytes(const protocol::ApiResponse& answer, bool close, bool head_only) {
    std::string out =
        "HTTP/1.1 " + std::to_string(answer.status) + " " + status_reason(answer.status) + "\r\n";
    if (!answer.content_type.empty()) out += "Content-Type: " + answer.content_type + "\r\n";
    out += "Content-Length: " + std::to_string(answer.body.size()) + "\r\n";
    if (close) out += "Connection: close\r\n";
    for (const auto& [name, value] : answer.headers) out += name + ": " + value + "\r\n";
    out += "\r\n";
    if (!head_only) out += answer.body;
    return out;
}

std::string problem_bytes(const protocol::Problem& problem, bool close) {
    return response_bytes(protocol::problem_response(problem), close);
}

}  // namespace strata::server
