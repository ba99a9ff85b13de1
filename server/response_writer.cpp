#include "server/response_writer.h"

#include "server/cors.h"

namespace strata::server {

const char* status_reason(int status) {
    switch (status) {
        case 100:
            return "Continue";
        case 200:
            return "OK";
        case 204:
            return "No Content";
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

namespace {

/// Status line, Content-Type, access-control and the answer's own headers; no blank line.
std::string head_lines(const protocol::ApiResponse& answer, std::string_view cors_origin) {
    std::string out =
        "HTTP/1.1 " + std::to_string(answer.status) + " " + status_reason(answer.status) + "\r\n";
    if (!answer.content_type.empty()) out += "Content-Type: " + answer.content_type + "\r\n";
    if (!cors_origin.empty()) out += cors_header_lines(cors_origin);
    for (const auto& [name, value] : answer.headers) out += name + ": " + value + "\r\n";
    return out;
}

}  // namespace

std::string write_response(const protocol::ApiResponse& answer, const Framing& framing) {
    std::string out = head_lines(answer, framing.cors_origin);
    out += "Content-Length: " + std::to_string(answer.body.size()) + "\r\n";
    if (framing.close) out += "Connection: close\r\n";
    out += "\r\n";
    // A HEAD answer has the headers of the body it leaves out: a body would be read as the next
    // response.
    if (!framing.head_only) out += answer.body;
    return out;
}

std::string write_stream_head(const protocol::ApiResponse& head, std::string_view cors_origin) {
    return head_lines(head, cors_origin) + "Connection: close\r\n\r\n" + head.body;
}

std::string problem_bytes(const protocol::Problem& problem, bool close) {
    Framing framing;
    framing.close = close;
    return write_response(protocol::problem_response(problem), framing);
}

}  // namespace strata::server
