// GET /v1/stream and GET /v1/events against the real server in-process, read over raw sockets
// (a stream never ends, which httplib's client cannot read): frames arrive, stop when the client
// leaves, nothing renders when nothing changed, a slow reader holds at most a frame or two, the
// drain ends streams; plus the token in the query, CORS and the viewer's files.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <turbojpeg.h>

#include <chrono>
#include <optional>
#include <thread>

#include "server/cors.h"
#include "server/stream_hub.h"
#include "test_server.h"

namespace strata::server::test {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

/// One connection, read with deadlines.
class RawClient {
public:
    explicit RawClient(int port, int rcvbuf = 0) {
        m_fd = ::socket(AF_INET, SOCK_STREAM, 0);
        if (rcvbuf > 0) setsockopt(m_fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(uint16_t(port));
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        EXPECT_EQ(::connect(m_fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    }
    ~RawClient() { close(); }
    void close() {
        if (m_fd >= 0) ::close(m_fd);
        m_fd = -1;
    }
    void send_get(const std::string& target, const std::string& headers = {}) {
        const std::string req = "GET " + target + " HTTP/1.1\r\nHost: t\r\n" + headers + "\r\n";
        ASSERT_EQ(::send(m_fd, req.data(), req.size(), MSG_NOSIGNAL), ssize_t(req.size()));
    }
    /// Reads until `needle` is buffered past `from`; its position, or nothing on timeout/EOF.
    std::optional<std::size_t> wait_for(const std::string& needle, std::size_t from = 0,
                                        std::chrono::milliseconds timeout = 5000ms) {
        const auto end = Clock::now() + timeout;
        for (;;) {
            if (auto p = m_in.find(needle, from); p != std::string::npos) return p;
            if (!read_some(end)) return std::nullopt;
        }
    }
    /// Reads until `n` bytes are buffered.
    bool wait_bytes(std::size_t n, std::chrono::milliseconds timeout = 5000ms) {
        const auto end = Clock::now() + timeout;
        while (m_in.size() < n) {
            if (!read_some(end)) return false;
        }
        return true;
    }
    /// True when the server closes the connection within `timeout` (bytes before are kept).
    bool wait_eof(std::chrono::milliseconds timeout) {
        const auto end = Clock::now() + timeout;
        while (read_some(end)) {
        }
        return m_eof;
    }
    std::string& in() { return m_in; }

private:
    bool read_some(Clock::time_point end) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
        if (left.count() <= 0 || m_eof) return false;
        pollfd p{m_fd, POLLIN, 0};
        if (::poll(&p, 1, int(left.count())) <= 0) return false;
        char buf[65536];
        const ssize_t n = ::recv(m_fd, buf, sizeof buf, 0);
        if (n <= 0) {
            m_eof = true;
            return false;
        }
        m_in.append(buf, std::size_t(n));
        return true;
    }

    int m_fd = -1;
    std::string m_in;
    bool m_eof = false;
};

/// One multipart frame.
struct Part {
    std::string jpeg;
    uint64_t version = 0;
    uint32_t samples = 0;
};

std::string header_value(const std::string& head, const std::string& name) {
    const std::size_t p = head.find(name + ": ");
    if (p == std::string::npos) return {};
    const std::size_t start = p + name.size() + 2;
    return head.substr(start, head.find("\r\n", start) - start);
}

/// Reads a frame stream: the response head once, then part after part.
class FrameReader {
public:
    FrameReader(int port, const std::string& query, const std::string& headers = {}, int rcvbuf = 0)
        : m_client(port, rcvbuf) {
        m_client.send_get("/v1/stream?" + query, headers);
    }
    /// The response head ("" when none came).
    std::string head() {
        // Up to the first part's headers, which the response sends at once.
        auto end = m_client.wait_for("\r\n\r\n");
        if (!end) return {};
        auto first = m_client.wait_for("--strata-frame\r\nContent-Type: image/jpeg\r\n\r\n");
        if (!first) return {};
        m_pos =
            *first + std::string_view("--strata-frame\r\nContent-Type: image/jpeg\r\n\r\n").size();
        return m_client.in().substr(0, *end + 4);
    }
    std::optional<Part> next(std::chrono::milliseconds timeout = 10000ms) {
        // Parts are the JPEG up to the next separator; the version and sample count are in
        // the JPEG's comment segment "strata version=V samples=S".
        auto end = m_client.wait_for(STREAM_PART_SEPARATOR, m_pos, timeout);
        if (!end) return std::nullopt;
        Part part;
        part.jpeg = m_client.in().substr(m_pos, *end - m_pos);
        m_pos = *end + std::string_view(STREAM_PART_SEPARATOR).size();
        const std::size_t c = part.jpeg.find("strata version=");
        if (c == std::string::npos) return std::nullopt;
        part.version = std::stoull(part.jpeg.substr(c + 15));
        part.samples = uint32_t(std::stoul(part.jpeg.substr(part.jpeg.find("samples=", c) + 8)));
        return part;
    }
    /// The first frame showing `version` or later.
    std::optional<Part> next_at(uint64_t version, std::chrono::milliseconds timeout = 10000ms) {
        const auto end = Clock::now() + timeout;
        while (Clock::now() < end) {
            auto p =
                next(std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now()));
            if (!p) return std::nullopt;
            if (p->version >= version) return p;
        }
        return std::nullopt;
    }
    RawClient& client() { return m_client; }

private:
    RawClient m_client;
    std::size_t m_pos = 0;
};

bool is_jpeg(const std::string& b) {
    return b.size() > 4 && uint8_t(b[0]) == 0xFF && uint8_t(b[1]) == 0xD8 &&
           uint8_t(b[b.size() - 2]) == 0xFF && uint8_t(b[b.size() - 1]) == 0xD9;
}

/// Polls `pred` for up to `timeout`.
template <class Pred>
bool eventually(Pred pred, std::chrono::milliseconds timeout = 3000ms) {
    const auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
        if (pred()) return true;
        std::this_thread::sleep_for(10ms);
    }
    return pred();
}

Json move_ball(float x) {
    return {
        {"op", "set_transform"}, {"instance", "ball"}, {"transform", {{"translate", {x, 1.5, 0}}}}};
}

uint64_t scene_version(TestServer& s) {
    return s.engine().read([](const Scene& scene) { return scene.version(); });
}

TEST(StreamEndpoint, FramesArriveAsJpegPartsOfAMultipartResponse) {
    TestServer s({}, true);
    FrameReader r(s.port(), "width=64&height=36&max_samples=8&fps=30");
    const std::string head = r.head();
    EXPECT_EQ(head.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << head;
    EXPECT_EQ(header_value(head, "Content-Type"),
              "multipart/x-mixed-replace; boundary=strata-frame");
    auto first = r.next();
    ASSERT_TRUE(first.has_value());
    EXPECT_TRUE(is_jpeg(first->jpeg));
    EXPECT_EQ(first->version, scene_version(s));
    // Progressive accumulation improves the frame: each next one has more samples, up to the
    // cap. A loaded machine may skip some (the newest frame wins), never all of them.
    int frames = 1;
    for (uint32_t samples = first->samples; samples < 8; ++frames) {
        auto next = r.next();
        ASSERT_TRUE(next.has_value()) << "after a frame of " << samples << " samples";
        EXPECT_GT(next->samples, samples);
        samples = next->samples;
    }
    EXPECT_GE(frames, 2);
}

TEST(StreamEndpoint, AnEditByAnotherClientSendsAFrameOfTheNewVersion) {
    TestServer s({}, true);
    FrameReader r(s.port(), "width=64&height=36&max_samples=1&fps=30");
    ASSERT_FALSE(r.head().empty());
    ASSERT_TRUE(r.next().has_value());
    const Reply edit = s.edits({move_ball(2.0f)});
    ASSERT_EQ(edit.status, 200) << edit.body;
    auto part = r.next_at(edit.json()["version"].get<uint64_t>(), 10000ms);
    ASSERT_TRUE(part.has_value());
    EXPECT_TRUE(is_jpeg(part->jpeg));
}

TEST(StreamEndpoint, NothingRendersWhenNothingChanged) {
    TestServer s({}, true);
    FrameReader r(s.port(), "width=64&height=36&max_samples=3&fps=60");
    ASSERT_FALSE(r.head().empty());
    // Frames until the accumulation is complete (a paced viewer may skip one in between).
    for (std::optional<Part> p = r.next(); !p || p->samples < 3; p = r.next())
        ASSERT_TRUE(p.has_value());
    EXPECT_EQ(s.server().streams().stats().frames_rendered, 3u);
    const uint64_t rendered = s.server().streams().stats().frames_rendered;
    std::this_thread::sleep_for(400ms);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, rendered);
    EXPECT_FALSE(r.next(200ms).has_value());
}

TEST(StreamEndpoint, RenderingStopsWhenTheClientLeaves) {
    TestServer s({}, true);
    {
        FrameReader r(s.port(), "width=64&height=36&max_samples=1&fps=30");
        ASSERT_FALSE(r.head().empty());
        ASSERT_TRUE(r.next().has_value());
        EXPECT_EQ(s.server().streams().stats().viewers, 1u);
    }
    EXPECT_TRUE(eventually([&] {
        const StreamHubStats st = s.server().streams().stats();
        return st.viewers == 0 && st.views == 0;
    }));
    const uint64_t rendered = s.server().streams().stats().frames_rendered;
    ASSERT_EQ(s.edits({move_ball(3.0f)}).status, 200);
    std::this_thread::sleep_for(300ms);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, rendered);
}

TEST(StreamEndpoint, ViewersOfTheSameViewShareOneRenderPerVersion) {
    TestServer s({}, true);
    const std::string q = "width=64&height=36&max_samples=1&fps=30";
    FrameReader a(s.port(), q), b(s.port(), q);
    ASSERT_FALSE(a.head().empty());
    ASSERT_FALSE(b.head().empty());
    ASSERT_TRUE(a.next().has_value());
    ASSERT_TRUE(b.next().has_value());
    const uint64_t before = s.server().streams().stats().frames_rendered;
    const Reply edit = s.edits({move_ball(1.0f)});
    const uint64_t v = edit.json()["version"].get<uint64_t>();
    auto pa = a.next_at(v), pb = b.next_at(v);
    ASSERT_TRUE(pa && pb);
    EXPECT_EQ(pa->jpeg, pb->jpeg);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, before + 1);
    EXPECT_EQ(s.server().streams().stats().views, 1u);
    // Another size is another view.
    FrameReader c(s.port(), "width=32&height=18&max_samples=1&fps=30");
    ASSERT_FALSE(c.head().empty());
    ASSERT_TRUE(c.next().has_value());
    EXPECT_EQ(s.server().streams().stats().views, 2u);
}

TEST(StreamEndpoint, NewViewsBeyondTheMemoryBudgetAre503AndViewersOfAnOpenViewJoinIt) {
    // 1 MiB: a 320x200 view takes 320 * 200 * 8 = 512000 bytes, so two views fit, not three.
    ServerConfig config;
    config.max_stream_mb = 1;
    TestServer s(config, true);
    const std::string a_query = "width=320&height=200&max_samples=1&fps=30";
    const std::string b_query = "width=320&height=199&max_samples=1&fps=30";
    auto a = std::make_unique<FrameReader>(s.port(), a_query);
    FrameReader b(s.port(), b_query);
    ASSERT_FALSE(a->head().empty());
    ASSERT_FALSE(b.head().empty());
    RawClient c(s.port());
    c.send_get("/v1/stream?width=320&height=198&max_samples=1");
    ASSERT_TRUE(c.wait_for("\r\n\r\n").has_value());
    ASSERT_TRUE(c.wait_for("}").has_value());
    EXPECT_EQ(c.in().substr(0, 12), "HTTP/1.1 503");
    EXPECT_NE(c.in().find("Retry-After: 5"), std::string::npos);
    EXPECT_NE(c.in().find("--max-stream-mb"), std::string::npos) << c.in();
    EXPECT_EQ(s.server().streams().stats().views_refused, 1u);
    EXPECT_EQ(s.server().streams().stats().view_bytes, 320u * 200 * 8 + 320u * 199 * 8);
    // Another viewer of an open view shares its memory: welcome.
    FrameReader a2(s.port(), a_query);
    ASSERT_FALSE(a2.head().empty());
    // Once the first view's viewers leave, its memory is free for another view.
    a.reset();
    a2.client().close();
    ASSERT_TRUE(eventually([&] { return s.server().streams().stats().viewers == 1; }, 5000ms));
    FrameReader d(s.port(), "width=320&height=198&max_samples=1&fps=30");
    EXPECT_FALSE(d.head().empty());
}

TEST(StreamEndpoint, ViewerRendersWaitWhileAnApiRenderRuns) {
    TestServer s({}, true);
    // A view that always has more samples to add: the hub renders as often as it may.
    FrameReader r(s.port(), "width=160&height=90&max_samples=4096&fps=60");
    ASSERT_FALSE(r.head().empty());
    ASSERT_TRUE(r.next().has_value());
    for (int i = 0; i < 3; ++i) {
        const Reply api = s.get("/v1/render?width=640&height=360&spp=2");
        EXPECT_EQ(api.status, 200) << api.body;
    }
    EXPECT_GT(s.server().streams().stats().renders_deferred, 0u);
    // And the stream goes on afterwards.
    EXPECT_TRUE(r.next().has_value());
}

TEST(StreamEndpoint, ASlowReaderHoldsAtMostTwoFramesAndMissesTheRest) {
    TestServer s({}, true);
    // A client that never reads, with a tiny receive buffer: once the socket buffers are full
    // (the server caps a stream's send buffer), every later frame replaces the pending one
    // instead of queueing. A second viewer of the same view reads every frame it gets, to know
    // how large a frame is.
    const std::string view = "width=480&height=270&quality=100&max_samples=1&fps=60";
    FrameReader slow(s.port(), view, {}, 4096);
    FrameReader reader(s.port(), view);
    ASSERT_FALSE(reader.head().empty());
    ASSERT_TRUE(reader.next().has_value());
    std::size_t largest_held = 0, largest_frame = 0;
    for (int i = 0; i < 25; ++i) {
        const Reply edit = s.edits({move_ball(float(i % 7) * 0.3f)});
        ASSERT_EQ(edit.status, 200);
        auto frame = reader.next_at(edit.json()["version"].get<uint64_t>());
        ASSERT_TRUE(frame.has_value());
        largest_frame = std::max(largest_frame, frame->jpeg.size());
        largest_held = std::max(largest_held, s.server().streams().stats().held_bytes);
    }
    const StreamHubStats st = s.server().streams().stats();
    EXPECT_GT(st.frames_dropped, 0u);
    EXPECT_EQ(st.viewers, 2u);
    // Per viewer: one frame being written and one pending, each with its part headers.
    EXPECT_LE(largest_held, 2 * 2 * (largest_frame + 256));
}

TEST(StreamEndpoint, TheDrainEndsFrameAndEventStreams) {
    auto s = std::make_unique<TestServer>(ServerConfig{}, true);
    FrameReader frames(s->port(), "width=64&height=36&max_samples=1&fps=30");
    ASSERT_FALSE(frames.head().empty());
    ASSERT_TRUE(frames.next().has_value());
    RawClient events(s->port());
    events.send_get("/v1/events");
    ASSERT_TRUE(events.wait_for("event: hello").has_value());
    const auto start = Clock::now();
    s->server().stop();
    EXPECT_TRUE(frames.client().wait_eof(3000ms));
    EXPECT_TRUE(events.wait_eof(3000ms));
    s.reset();  // the server thread has returned: run() finished its drain
    EXPECT_LT(Clock::now() - start, 3000ms);
}

TEST(EventsEndpoint, EachCommitIsOneEventWithItsVersionAndReport) {
    TestServer s({}, true);
    RawClient c(s.port());
    c.send_get("/v1/events");
    auto hello = c.wait_for("event: hello\ndata: ");
    ASSERT_TRUE(hello.has_value());
    EXPECT_NE(c.in().find("Content-Type: text/event-stream"), std::string::npos);
    for (int i = 1; i <= 2; ++i) {
        const Reply edit = s.edits({move_ball(float(i))});
        ASSERT_EQ(edit.status, 200);
        ASSERT_EQ(s.post("/v1/commit", std::string()).status, 200);
        const uint64_t v = edit.json()["version"].get<uint64_t>();
        auto at = c.wait_for("id: " + std::to_string(v) + "\nevent: commit\ndata: ");
        ASSERT_TRUE(at.has_value()) << c.in();
        const std::size_t data = c.in().find("data: ", *at) + 6;
        const Json j = Json::parse(c.in().substr(data, c.in().find('\n', data) - data));
        EXPECT_EQ(j["version"].get<uint64_t>(), v);
        EXPECT_EQ(j["report"]["version"].get<uint64_t>(), v);
        EXPECT_TRUE(j["report"].contains("tlas")) << j.dump();
    }
    // A commit with nothing new is no event.
    ASSERT_EQ(s.post("/v1/commit", std::string()).status, 200);
    EXPECT_FALSE(c.wait_for("event: commit", c.in().rfind("event: commit") + 1, 300ms));
}

TEST(EventsEndpoint, ANamedScenesStreamsCarryItsCommitsOnly) {
    TestServer s({}, true);
    auto http = s.client();
    ASSERT_EQ(http.Put("/v1/scenes/side", "", "application/json")->status, 201);
    RawClient side(s.port());
    side.send_get("/v1/scenes/side/events");
    auto hello = side.wait_for("event: hello\ndata: ");
    ASSERT_TRUE(hello.has_value()) << side.in();
    EXPECT_NE(side.in().find("\"version\":0", *hello), std::string::npos) << side.in();
    // The default scene's commits are not this scene's events.
    ASSERT_EQ(s.edits({move_ball(1.0f)}).status, 200);
    ASSERT_EQ(s.post("/v1/commit", std::string()).status, 200);
    EXPECT_FALSE(side.wait_for("event: commit", 0, 300ms));
    const Reply edit = s.post("/v1/scenes/side/edits",
                              Json{{"edits", {{{"op", "set_camera"}, {"eye", {1, 2, 3}}}}}});
    ASSERT_EQ(edit.status, 200) << edit.body;
    ASSERT_EQ(s.post("/v1/scenes/side/commit", std::string()).status, 200);
    EXPECT_TRUE(side.wait_for("id: 1\nevent: commit\n").has_value()) << side.in();
    // Its frames come from its own hub.
    RawClient frames(s.port());
    frames.send_get("/v1/scenes/side/stream?width=32&height=32&max_samples=1");
    EXPECT_TRUE(frames.wait_for("Content-Type: image/jpeg\r\n\r\n").has_value())
        << frames.in().substr(0, 600);
    // Deleting the scene ends its streams.
    ASSERT_EQ(http.Delete("/v1/scenes/side")->status, 204);
    EXPECT_TRUE(side.wait_eof(3000ms));
    EXPECT_TRUE(frames.wait_eof(3000ms));
}

TEST(EventsEndpoint, CommitsInQuickSuccessionAreEachOneEventInOrder) {
    // Edit-and-commit round trips on loopback take about a millisecond: a stream that looked for
    // commits now and then would report only some of them.
    TestServer s({}, true);
    RawClient c(s.port());
    c.send_get("/v1/events");
    ASSERT_TRUE(c.wait_for("event: hello\ndata: ").has_value());
    std::vector<uint64_t> versions;
    for (int i = 1; i <= 40; ++i) {
        const Reply edit = s.edits({move_ball(float(i) * 0.01f)});
        ASSERT_EQ(edit.status, 200);
        ASSERT_EQ(s.post("/v1/commit", std::string()).status, 200);
        versions.push_back(edit.json()["version"].get<uint64_t>());
    }
    std::size_t from = 0;
    for (uint64_t v : versions) {
        auto at = c.wait_for("id: " + std::to_string(v) + "\nevent: commit\n", from);
        ASSERT_TRUE(at.has_value()) << "no event for version " << v << " after offset " << from;
        from = *at + 1;  // and after the previous one: in order
    }
}

TEST(StreamEndpoint, BadParametersAreRefusedWithAProblemNamingThem) {
    TestServer s({}, true);
    expect_problem(s.get("/v1/stream?fps=0"), 400, "invalid-request", "/fps");
    expect_problem(s.get("/v1/stream?quality=101"), 400, "invalid-request", "/quality");
    expect_problem(s.get("/v1/stream?format=png"), 400, "invalid-request", "/format");
    expect_problem(s.get("/v1/stream?width=0"), 400, "invalid-request", "/width");
    expect_problem(s.get("/v1/stream?width=65536&height=65536"), 413);
    expect_problem(s.get("/v1/events?x=1"), 400, "invalid-request", "/x");
    expect_problem(s.get("/v1/stream?highlight="), 400, "invalid-request", "/highlight");
    // A stream is one process's view: no bands, no split.
    expect_problem(s.get("/v1/stream?band=0,4"), 400, "invalid-request", "/band");
    expect_problem(s.get("/v1/stream?split=2"), 400, "invalid-request", "/split");
    expect_problem(s.get("/v1/stream?highlight=no-such-instance"), 404, "not-found", "/highlight");
    // A camera no frame can be rendered with is refused before the stream starts, not answered
    // 200 and then left silent.
    expect_problem(s.get("/v1/stream?eye=3e38,0,0&target=-3e38,0,0"), 422, "invalid-value",
                   "/camera/eye");
    expect_problem(s.get("/v1/stream?eye=0,2,8&target=0,2,8"), 422, "invalid-value",
                   "/camera/target");
    // A past version is read from the data directory, which this server has none of; a
    // version still to come does not exist.
    const uint64_t now = scene_version(s);
    expect_problem(s.get("/v1/stream?at_version=" + std::to_string(now)), 404, "not-found",
                   "/at_version");
    expect_problem(s.get("/v1/stream?at_version=" + std::to_string(now + 1)), 404, "not-found",
                   "/at_version");
    expect_problem(s.get("/v1/stream?at_version=-1"), 400, "invalid-request", "/at_version");
    EXPECT_EQ(s.server().streams().stats().views, 0u);
}

/// A stream part decoded to packed RGB. Fast upsampling: a pixel's chroma comes from its own
/// 16x16 block only, so blocks whose source pixels are equal decode to equal bytes.
std::vector<uint8_t> decode_rgb(const std::string& jpeg, int width, int height) {
    std::vector<uint8_t> rgb(std::size_t(width) * height * 3);
    tjhandle h = tjInitDecompress();
    const int rc = tjDecompress2(h, reinterpret_cast<const unsigned char*>(jpeg.data()),
                                 (unsigned long)jpeg.size(), rgb.data(), width, 0, height, TJPF_RGB,
                                 TJFLAG_FASTUPSAMPLE);
    tjDestroy(h);
    EXPECT_EQ(rc, 0);
    return rc == 0 ? rgb : std::vector<uint8_t>{};
}

/// The instance_id AOV of the scene camera's view at this size (the stream's pixel-centre ids).
std::vector<uint32_t> instance_ids(TestServer& s, uint32_t width, uint32_t height) {
    RenderRequest r;
    r.width = width;
    r.height = height;
    r.format = ImageFormat::Exr;
    r.aovs = {Aov::InstanceId};
    auto frame = s.engine().render_frame(r);
    EXPECT_TRUE(frame.has_value());
    return frame ? frame->buffers.instance_id : std::vector<uint32_t>{};
}

/// Compares a highlighted frame with a plain one of the same render: every 16x16 JPEG block
/// without a pixel of `slot` decodes to the same bytes, and the instance's inner pixels (all
/// 8-neighbours its own too) moved clearly towards the highlight colour.
void expect_tinted_exactly(const std::string& plain_jpeg, const std::string& tinted_jpeg,
                           const std::vector<uint32_t>& ids, uint32_t slot, int w, int h) {
    const auto plain = decode_rgb(plain_jpeg, w, h), tinted = decode_rgb(tinted_jpeg, w, h);
    ASSERT_FALSE(plain.empty() || tinted.empty());
    auto block_has_slot = [&](int bx, int by) {
        for (int y = by * 16; y < std::min(h, by * 16 + 16); ++y)
            for (int x = bx * 16; x < std::min(w, bx * 16 + 16); ++x)
                if (ids[std::size_t(y) * w + x] == slot) return true;
        return false;
    };
    std::size_t clean_pixels = 0, inner = 0;
    double inner_diff = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!block_has_slot(x / 16, y / 16)) {
                ++clean_pixels;
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(plain[3 * p + c], tinted[3 * p + c])
                        << "pixel " << x << "," << y << " is far from the instance but changed";
                continue;
            }
            bool interior = x > 0 && y > 0 && x + 1 < w && y + 1 < h;
            for (int dy = -1; interior && dy <= 1; ++dy)
                for (int dx = -1; interior && dx <= 1; ++dx)
                    interior = ids[std::size_t(y + dy) * w + x + dx] == slot;
            if (!interior) continue;
            ++inner;
            for (int c = 0; c < 3; ++c)
                inner_diff += std::abs(plain[3 * p + c] - tinted[3 * p + c]);
        }
    }
    EXPECT_GT(clean_pixels, std::size_t(w) * h / 4) << "the instance should not fill the frame";
    ASSERT_GT(inner, 20u) << "the instance should show some inner pixels";
    EXPECT_GT(inner_diff / double(inner * 3), 15.0) << "the instance's pixels were not tinted";
}

TEST(StreamEndpoint, TheFilterIsOnByDefaultAndFilterNoneTurnsItOff) {
    TestServer s({}, true);
    const std::string q = "width=96&height=54&max_samples=1&fps=30&quality=95";
    // No `filter` is the same view as filter=atrous: the two viewers share one render.
    FrameReader by_default(s.port(), q);
    ASSERT_FALSE(by_default.head().empty());
    auto d = by_default.next();
    ASSERT_TRUE(d.has_value());
    FrameReader atrous(s.port(), q + "&filter=atrous");
    ASSERT_FALSE(atrous.head().empty());
    auto a = atrous.next();
    ASSERT_TRUE(a.has_value());
    EXPECT_EQ(a->jpeg, d->jpeg);
    EXPECT_EQ(s.server().streams().stats().views, 1u);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, 1u);
    // filter=none is another view, rendered on its own (it continues the engine's one
    // accumulation, whose sums are never filtered), and shows other pixels.
    FrameReader plain(s.port(), q + "&filter=none");
    ASSERT_FALSE(plain.head().empty());
    auto p = plain.next();
    ASSERT_TRUE(p.has_value());
    EXPECT_NE(p->jpeg, d->jpeg);
    EXPECT_EQ(s.server().streams().stats().views, 2u);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, 2u);
    expect_problem(s.get("/v1/stream?filter=yes"), 400, "invalid-request", "/filter");
}

TEST(StreamEndpoint, AHighlightTintsOnlyTheInstancesPixelsAndTheRenderStaysShared) {
    TestServer s({}, true);
    const int W = 128, H = 72;
    const std::string q = "width=128&height=72&max_samples=1&fps=30&quality=95";
    const uint32_t ball =
        s.engine().read([](const Scene& scene) { return scene.find_instance("ball").index; });
    const uint32_t crate =
        s.engine().read([](const Scene& scene) { return scene.find_instance("crate-a").index; });
    const auto ids = instance_ids(s, W, H);
    ASSERT_EQ(ids.size(), std::size_t(W) * H);

    // The highlighting viewer first: its render carries ids; the plain viewer who joins gets
    // the same render encoded without the tint.
    FrameReader tinted(s.port(), q + "&highlight=ball");
    ASSERT_FALSE(tinted.head().empty());
    auto t = tinted.next();
    ASSERT_TRUE(t.has_value());
    FrameReader plain(s.port(), q);
    ASSERT_FALSE(plain.head().empty());
    auto p = plain.next();
    ASSERT_TRUE(p.has_value());
    EXPECT_EQ(p->version, t->version);
    EXPECT_EQ(p->samples, t->samples);
    EXPECT_NE(p->jpeg, t->jpeg);
    StreamHubStats st = s.server().streams().stats();
    EXPECT_EQ(st.views, 1u);
    EXPECT_EQ(st.frames_rendered, 1u) << "one shared render, two encodings";
    expect_tinted_exactly(p->jpeg, t->jpeg, ids, ball, W, H);

    // Another selection once accumulation has ended: the newest frame, encoded for it, at once.
    FrameReader other(s.port(), q + "&highlight=crate-a");
    ASSERT_FALSE(other.head().empty());
    auto o = other.next(3000ms);
    ASSERT_TRUE(o.has_value());
    EXPECT_EQ(o->version, t->version);
    EXPECT_EQ(s.server().streams().stats().frames_rendered, 1u);
    expect_tinted_exactly(p->jpeg, o->jpeg, ids, crate, W, H);
    EXPECT_GE(s.server().streams().stats().highlight_encodes, 2u);
}

TEST(StreamEndpoint, AHighlightJoiningAPlainViewNeedsNoRenderAndAnEditKeepsItTinted) {
    TestServer s({}, true);
    const int W = 96, H = 54;
    const std::string q = "width=96&height=54&max_samples=1&fps=30&quality=95";
    FrameReader plain(s.port(), q);
    ASSERT_FALSE(plain.head().empty());
    ASSERT_TRUE(plain.next().has_value());
    FrameReader tinted(s.port(), q + "&highlight=ball");
    ASSERT_FALSE(tinted.head().empty());
    auto t = tinted.next(3000ms);
    ASSERT_TRUE(t.has_value()) << "a new highlight shows at once even after accumulation ended";
    EXPECT_EQ(s.server().streams().stats().frames_rendered, 1u);

    // The ball moves: the next frames of both viewers show the new version, tinted where the
    // ball is now.
    const Reply edit = s.edits({move_ball(-1.5f)});
    ASSERT_EQ(edit.status, 200) << edit.body;
    const uint64_t v = edit.json()["version"].get<uint64_t>();
    auto p2 = plain.next_at(v), t2 = tinted.next_at(v);
    ASSERT_TRUE(p2 && t2);
    ASSERT_EQ(p2->samples, t2->samples);
    const uint32_t ball =
        s.engine().read([](const Scene& scene) { return scene.find_instance("ball").index; });
    expect_tinted_exactly(p2->jpeg, t2->jpeg, instance_ids(s, W, H), ball, W, H);
}

TEST(StreamEndpoint, TheTokenMayComeInTheQueryOnStreamPathsOnly) {
    ServerConfig config;
    config.token = "s3cret";
    TestServer s(config, true);
    expect_problem(s.get("/v1/stream?width=64&height=36"), 401);
    expect_problem(s.get("/v1/stream?width=64&height=36&access_token=wrong"), 401);
    FrameReader r(s.port(), "width=64&height=36&max_samples=1&access_token=s3cret");
    EXPECT_EQ(r.head().rfind("HTTP/1.1 200", 0), 0u);
    EXPECT_TRUE(r.next().has_value());
    RawClient e(s.port());
    e.send_get("/v1/events?access_token=s3cret");
    EXPECT_TRUE(e.wait_for("event: hello").has_value());
    expect_problem(s.get("/v1/scene?access_token=s3cret"), 401);
    EXPECT_EQ(s.get("/v1/scene", {{"Authorization", "Bearer s3cret"}}).status, 200);
    // The viewer's page itself is open: it asks for the token.
    const Reply page = s.get("/");
    EXPECT_EQ(page.status, 200);
    EXPECT_EQ(page.header("Content-Type"), "text/html; charset=utf-8");
}

TEST(Cors, AllowedOriginsGetPreflightAnswersAndAccessControlHeaders) {
    ServerConfig config;
    config.token = "s3cret";
    config.cors_origin = "http://viewer.test, http://other.test:8000";
    TestServer s(config, true);
    const httplib::Headers preflight = {{"Origin", "http://viewer.test"},
                                        {"Access-Control-Request-Method", "POST"},
                                        {"Access-Control-Request-Headers", "authorization"}};
    auto c = s.client();
    auto r = c.Options("/v1/edits", preflight);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 204);
    EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), "http://viewer.test");
    EXPECT_NE(r->get_header_value("Access-Control-Allow-Headers").find("Authorization"),
              std::string::npos);
    auto denied = c.Options(
        "/v1/edits", {{"Origin", "http://evil.test"}, {"Access-Control-Request-Method", "POST"}});
    ASSERT_TRUE(denied);
    EXPECT_FALSE(denied->has_header("Access-Control-Allow-Origin"));
    const Reply scene = s.get(
        "/v1/scene", {{"Origin", "http://other.test:8000"}, {"Authorization", "Bearer s3cret"}});
    EXPECT_EQ(scene.status, 200);
    EXPECT_EQ(scene.header("Access-Control-Allow-Origin"), "http://other.test:8000");
    EXPECT_NE(scene.header("Access-Control-Expose-Headers").find("ETag"), std::string::npos);
    // Refusals by the front end carry it too, so that the page can read why.
    const Reply refused = s.get("/v1/scene", {{"Origin", "http://viewer.test"}});
    EXPECT_EQ(refused.status, 401);
    EXPECT_EQ(refused.header("Access-Control-Allow-Origin"), "http://viewer.test");
    EXPECT_EQ(
        s.get("/v1/scene", {{"Origin", "http://evil.test"}, {"Authorization", "Bearer s3cret"}})
            .header("Access-Control-Allow-Origin"),
        "");
    FrameReader stream(s.port(), "width=32&height=18&max_samples=1&access_token=s3cret",
                       "Origin: http://viewer.test\r\n");
    EXPECT_EQ(header_value(stream.head(), "Access-Control-Allow-Origin"), "http://viewer.test");
}

TEST(CorsPolicy, ParsesOriginListsAndRefusesWhatIsNoOrigin) {
    EXPECT_FALSE(CorsPolicy::parse("").value().enabled());
    auto any = CorsPolicy::parse("*");
    ASSERT_TRUE(any.has_value());
    const std::string o = "https://x.example";
    EXPECT_EQ(any.value().allow(&o), o);
    EXPECT_FALSE(CorsPolicy::parse("https://x.example/path").has_value());
    EXPECT_FALSE(CorsPolicy::parse("x.example").has_value());
    auto list = CorsPolicy::parse("HTTPS://X.example");
    ASSERT_TRUE(list.has_value());
    EXPECT_EQ(list.value().allow(&o), o);
    const std::string other = "https://y.example";
    EXPECT_FALSE(list.value().allow(&other).has_value());
    EXPECT_FALSE(list.value().allow(nullptr).has_value());
}

TEST(WebRoutes, TheViewerFilesAreServedAndUnknownOnesAreNotFound) {
    TestServer s;
    const Reply page = s.get("/");
    EXPECT_EQ(page.status, 200);
    EXPECT_NE(page.body.find("<title>"), std::string::npos);
    expect_problem(s.get("/web/no-such-file.js"), 404, "not-found");
    expect_problem(s.get("/web/../CMakeLists.txt"), 404);
}

}  // namespace
}  // namespace strata::server::test
