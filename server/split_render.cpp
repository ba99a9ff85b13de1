#include "server/split_render.h"

#include <algorithm>
#include <charconv>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <httplib.h>

#include "engine/core/timer.h"
#include "engine/image/exr.h"
#include "engine/render/band_assembly.h"
#include "engine/render/frame_encode.h"
#include "engine/scene/object_fields.h"

namespace strata::server {

namespace {

/// Longest a coordinator waits to connect to a peer (the whole request has --peer-timeout-ms).
constexpr std::chrono::milliseconds CONNECT_TIMEOUT{1000};

/// `f` as text that reads back (strtod, then to float) as exactly `f`: the shortest text of the
/// double holding it.
std::string exact_text(float f) {
    char buf[64];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, double(f));
    return ec == std::errc() ? std::string(buf, end) : std::string("nan");
}

std::string vec_text(const Vec3& v) {
    return exact_text(v.x) + "," + exact_text(v.y) + "," + exact_text(v.z);
}

std::optional<uint64_t> version_of_etag(std::string_view etag) {
    if (etag.size() < 3 || etag.front() != '"' || etag.back() != '"') return std::nullopt;
    etag = etag.substr(1, etag.size() - 2);
    uint64_t v = 0;
    const auto [end, ec] = std::from_chars(etag.data(), etag.data() + etag.size(), v);
    if (ec != std::errc() || end != etag.data() + etag.size()) return std::nullopt;
    return v;
}

/// `text` fit for a header value: printable ASCII, at most 160 characters.
std::string header_safe(std::string text) {
    if (text.size() > 160) text = text.substr(0, 157) + "...";
    for (char& c : text)
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
    return text;
}

/// Waits for the fetches to finish; wakes the coordinator as each does.
struct FetchBoard {
    std::mutex mutex;
    std::condition_variable changed;
    std::size_t pending = 0;
};

/// One peer's band, fetched on a thread of its own.
struct PeerFetch {
    const PeerServer* peer = nullptr;
    uint32_t index = 0;  ///< the band's index
    RowBand band;
    std::unique_ptr<httplib::Client> client;
    std::thread thread;
    // Written by the thread, read once it has finished.
    std::optional<uint64_t> version;
    std::optional<DecodedBand> decoded;
    std::string failure;

    void run(const std::string& path, const httplib::Headers& headers, uint32_t width,
             AovSet aovs) {
        try {
            auto res = client->Get(path.c_str(), headers);
            if (!res) {
                failure = httplib::to_string(res.error());
                return;
            }
            if (res->status != 200) {
                failure = std::to_string(res->status);
                return;
            }
            version = version_of_etag(res->get_header_value("ETag"));
            if (!version) {
                failure = "no version (ETag) in the answer";
                return;
            }
            auto exr = decode_exr(res->body);
            if (!exr) {
                failure = exr.error().message;
                return;
            }
            auto band_buffers = band_from_exr(exr.value(), width, band.rows, aovs);
            if (!band_buffers) {
                failure = band_buffers.error().message;
                return;
            }
            decoded = std::move(band_buffers.value());
        } catch (const std::exception& e) {
            failure = e.what();
        }
    }
};

/// Stops and joins every fetch when the coordinator returns, whichever way.
struct FetchGuard {
    std::vector<std::unique_ptr<PeerFetch>>& fetches;
    ~FetchGuard() {
        for (auto& f : fetches)
            if (f->client) f->client->stop();
        for (auto& f : fetches)
            if (f->thread.joinable()) f->thread.join();
    }
};

Unexpected<Error> cancelled(const CancelToken& token) {
    return failure(ErrorCode::Cancelled, std::string("the split render stopped early: ") +
                                             cancel_reason_text(token.reason()));
}

/// How one split render is cut into bands: what its steps read.
struct SplitPlan {
    const RenderRequest& request;
    std::vector<RowBand> bands;  ///< band 0 rendered here, band k asked of peer k
    RenderRequest base;          ///< band_request of the request: what launches here render
    AovSet aovs;                 ///< the AOVs every band carries
};

/// A split frame being put together from its bands.
struct SplitAssembly {
    FrameAssembly assembly;
    FrameInfo info;                   ///< the info of the launch whose version the frame shows
    Camera camera;                    ///< the camera that launch traced with
    std::vector<std::string> labels;  ///< per band: "local", its peer's URL, or why not the peer
    std::string note;                 ///< told after the version when it moved during the split
};

/// The `split` bands of `request`: an error when the `peer_count` peers cannot take split - 1
/// of them or the frame has too few rows.
Result<std::vector<RowBand>> split_bands(const RenderRequest& request, uint32_t split,
                                         std::size_t peer_count) {
    if (split < 2 || split - 1 > peer_count)
        return failure(ErrorCode::InvalidArgument,
                       "split " + std::to_string(split) + " needs " + std::to_string(split - 1) +
                           " peers; this server has " + std::to_string(peer_count) + " (--peers)",
                       "split");
    std::vector<RowBand> bands = split_rows(request.height, split);
    if (bands.size() != split)
        return failure(ErrorCode::InvalidArgument,
                       "split " + std::to_string(split) + " asks for more bands than the frame's " +
                           std::to_string(request.height) + " rows",
                       "split");
    return bands;
}

/// The fetch of band `index` (`band`) from `peer`, whose client gives the peer `timeout` at
/// most (and CONNECT_TIMEOUT at most to connect).
std::unique_ptr<PeerFetch> make_fetch(const PeerServer& peer, uint32_t index, RowBand band,
                                      std::chrono::milliseconds timeout) {
    auto f = std::make_unique<PeerFetch>();
    f->peer = &peer;
    f->index = index;
    f->band = band;
    f->client = std::make_unique<httplib::Client>(peer.host, peer.port);
    f->client->set_connection_timeout(std::min(CONNECT_TIMEOUT, timeout));
    f->client->set_read_timeout(timeout);
    f->client->set_write_timeout(timeout);
    f->client->set_keep_alive(false);
    return f;
}

/// Runs `f` on a thread of its own, asking its peer for `path`; `board` counts it as pending
/// until it has finished.
void start_fetch(PeerFetch& f, const std::string& path, const httplib::Headers& headers,
                 FetchBoard& board, uint32_t width, AovSet aovs) {
    {
        std::lock_guard lock(board.mutex);
        ++board.pending;
    }
    PeerFetch* raw = &f;
    f.thread = std::thread([raw, path, headers, &board, width, aovs] {
        raw->run(path, headers, width, aovs);
        std::lock_guard lock(board.mutex);
        --board.pending;
        board.changed.notify_all();
    });
}

/// Waits until no fetch on `board` is pending; false as soon as `cancel` says to stop.
bool wait_for_fetches(FetchBoard& board, const CancelToken* cancel) {
    std::unique_lock lock(board.mutex);
    while (board.pending > 0) {
        if (should_stop(cancel)) return false;
        board.changed.wait_for(lock, std::chrono::milliseconds(10));
    }
    return true;
}

/// Places each peer's band that came at exactly `version` and reads back, labelling it with
/// its peer, or with why it does not count. Returns the bands that do not, to render here.
std::vector<RowBand> place_peer_bands(std::vector<std::unique_ptr<PeerFetch>>& fetches,
                                      uint64_t version, SplitAssembly& parts) {
    std::vector<RowBand> missing;
    for (auto& f : fetches) {
        if (f->thread.joinable()) f->thread.join();
        std::string why = f->failure;
        if (why.empty() && f->version != version)
            why = "at version " + std::to_string(*f->version) + ", not " + std::to_string(version);
        if (why.empty()) {
            const DecodedBand& decoded = *f->decoded;
            if (Status s = parts.assembly.place(decoded.buffers, f->band.y0, decoded.names); !s)
                why = s.error().message;
        }
        if (why.empty()) {
            parts.labels[f->index] = f->peer->url;
        } else {
            parts.labels[f->index] = "local (" + f->peer->url + ": " + header_safe(why) + ")";
            missing.push_back(f->band);
        }
    }
    return missing;
}

/// Places the frames of one launch, frame k at the rows of `bands[k]`.
Status place_bands(FrameAssembly& assembly, const std::vector<Frame>& frames,
                   const std::vector<RowBand>& bands) {
    for (std::size_t i = 0; i < bands.size(); ++i) {
        const Frame& f = frames[i];
        if (Status s = assembly.place(f.buffers, bands[i].y0, f.names); !s) return s;
    }
    return {};
}

/// Renders the `missing` bands here, in one launch, and places them. Should that launch be at
/// another version than `version`, every band is rendered here instead, so that the frame
/// shows one version.
Status render_missing_bands(Engine& engine, const SplitPlan& plan,
                            const std::vector<RowBand>& missing, uint64_t version,
                            SplitAssembly& parts) {
    auto local = engine.render_bands(plan.base, missing);
    if (!local) return Unexpected(local.error());
    if (local->front().info.version == version)
        return place_bands(parts.assembly, local.value(), missing);
    // An edit landed between the two launches: one launch renders every band, so the frame
    // shows one version.
    auto all = engine.render_bands(plan.base, plan.bands);
    if (!all) return Unexpected(all.error());
    parts.assembly = FrameAssembly(plan.request.width, plan.request.height, plan.aovs);
    if (Status s = place_bands(parts.assembly, all.value(), plan.bands); !s) return s;
    parts.note = " (version moved from " + std::to_string(version) +
                 " during the split: " + "every band rendered here)";
    parts.info = all->front().info;
    parts.camera = all->front().camera;
    std::fill(parts.labels.begin(), parts.labels.end(), "local");
    return {};
}

/// Finishes and encodes the assembled frame the way one render of `request` does; its bands
/// text says where each of the `split` bands came from. `clock` has timed the whole render.
Result<protocol::SplitFrame> encode_split_frame(const RenderRequest& request, uint32_t split,
                                                SplitAssembly&& parts, const Stopwatch& clock) {
    parts.info.samples = request.spp;
    parts.info.samples_added = request.spp;
    auto frame = std::move(parts.assembly).finish(request, parts.camera, parts.info);
    if (!frame) return Unexpected(frame.error());
    auto encoded = encode_frame(frame->buffers, request, exr_attributes(frame.value()));
    if (!encoded) return Unexpected(encoded.error());
    encoded->info = std::move(frame->info);
    encoded->info.render_ms = clock.ms();
    protocol::SplitFrame out;
    out.frame = std::move(encoded.value());
    out.bands = std::to_string(split) + " bands at version " +
                std::to_string(out.frame.info.version) + parts.note + ":";
    for (std::size_t k = 0; k < parts.labels.size(); ++k)
        out.bands += (k ? ", " : " ") + parts.labels[k];
    return out;
}

}  // namespace

Result<std::vector<PeerServer>> parse_peers(std::string_view list) {
    std::vector<PeerServer> peers;
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        std::string_view item = list.substr(start, comma - start);
        start = comma + 1;
        while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
        while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
        if (item.empty()) {
            if (list.empty()) break;
            return failure(ErrorCode::InvalidArgument,
                           "--peers has an empty item: give comma-separated http://host:port",
                           "peers");
        }
        auto bad = [&](const std::string& why) {
            return failure(ErrorCode::InvalidArgument,
                           "--peers item '" + std::string(item) + "': " + why, "peers");
        };
        std::string_view rest = item;
        if (rest.rfind("http://", 0) == 0) {
            rest.remove_prefix(7);
        } else if (rest.find("://") != std::string_view::npos) {
            return bad("only http:// peers are supported");
        }
        if (!rest.empty() && rest.back() == '/') rest.remove_suffix(1);
        if (rest.find('/') != std::string_view::npos) return bad("a peer URL has no path");
        const std::size_t colon = rest.rfind(':');
        if (colon == std::string_view::npos || colon == 0) return bad("expected host:port");
        PeerServer p;
        p.host = std::string(rest.substr(0, colon));
        if (p.host.size() > 2 && p.host.front() == '[' && p.host.back() == ']')
            p.host = p.host.substr(1, p.host.size() - 2);
        const std::string_view port = rest.substr(colon + 1);
        const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), p.port);
        if (ec != std::errc() || end != port.data() + port.size() || p.port < 1 || p.port > 65535)
            return bad("the port must be a number in [1, 65535]");
        p.url = "http://" + std::string(rest);
        peers.push_back(std::move(p));
    }
    return peers;
}

std::string band_query(const RenderRequest& request, RowBand band) {
    const RenderRequest b = band_request(request, band);
    std::string q = "width=" + std::to_string(b.width) + "&height=" + std::to_string(b.height) +
                    "&spp=" + std::to_string(b.spp) +
                    "&format=exr&compression=none&band=" + std::to_string(band.y0) + "," +
                    std::to_string(band.rows);
    if (!b.aovs.empty()) {
        q += "&aovs=";
        for (std::size_t i = 0; i < b.aovs.size(); ++i)
            q += (i ? "," : "") + std::string(aov_name(b.aovs[i]));
    }
    if (b.camera) {
        // Every field of the override, so peers trace the same frame (shutter included).
        for_each_field<CameraFields>([&](const auto& row) {
            const auto& value = (*b.camera).*(row.update);
            if (!value) return;
            q += "&" + std::string(row.info.name) + "=";
            if constexpr (std::is_same_v<std::decay_t<decltype(*value)>, Vec3>)
                q += vec_text(*value);
            else
                q += exact_text(*value);
        });
    }
    if (b.time) q += "&time=" + exact_text(*b.time);  // the animated instances where ours are
    return q;
}

SplitRenderer::SplitRenderer(Engine& engine, std::vector<PeerServer> peers, std::string token,
                             std::chrono::milliseconds peer_timeout)
    : m_engine(engine),
      m_peers(std::move(peers)),
      m_token(std::move(token)),
      m_peer_timeout(peer_timeout) {}

Result<protocol::SplitFrame> SplitRenderer::render(const RenderRequest& request, uint32_t split) {
    Stopwatch clock;
    auto bands = split_bands(request, split, m_peers.size());
    if (!bands) return Unexpected(bands.error());
    const SplitPlan plan{request, std::move(bands.value()), band_request(request, RowBand{}),
                         band_aovs(request)};
    const uint64_t asked = m_engine.read([](const Scene& s) { return s.version(); });

    // Step: ask the peers for bands 1..split-1, each on a thread of its own.
    httplib::Headers headers;
    if (!m_token.empty()) headers.emplace("Authorization", "Bearer " + m_token);
    FetchBoard board;
    std::vector<std::unique_ptr<PeerFetch>> fetches;
    FetchGuard guard{fetches};
    for (uint32_t k = 1; k < split; ++k) {
        fetches.push_back(make_fetch(m_peers[k - 1], k, plan.bands[k], m_peer_timeout));
        const std::string path = "/v1/render?" + band_query(request, plan.bands[k]) +
                                 "&min_version=" + std::to_string(asked);
        start_fetch(*fetches.back(), path, headers, board, request.width, plan.aovs);
    }

    // Step: band 0 here; its launch's version is the frame's.
    auto own = m_engine.render_bands(plan.base, {plan.bands[0]});
    if (!own) return Unexpected(own.error());
    const Frame& first = own.value().front();
    const uint64_t version = first.info.version;

    // Step: wait for the peers, still honouring the request's cancellation.
    if (!wait_for_fetches(board, request.cancel) || should_stop(request.cancel))
        return cancelled(*request.cancel);

    // Step: keep the peers' bands at exactly this version; render the others here.
    SplitAssembly parts{FrameAssembly(request.width, request.height, plan.aovs),
                        first.info,
                        first.camera,
                        std::vector<std::string>(split, "local"),
                        {}};
    if (Status s = parts.assembly.place(first.buffers, plan.bands[0].y0, first.names); !s)
        return Unexpected(s.error());
    const std::vector<RowBand> missing = place_peer_bands(fetches, version, parts);
    if (!missing.empty()) {
        if (Status s = render_missing_bands(m_engine, plan, missing, version, parts); !s)
            return Unexpected(s.error());
    }
    if (should_stop(request.cancel)) return cancelled(*request.cancel);

    // Step: finish and encode the frame as one render does.
    return encode_split_frame(request, split, std::move(parts), clock);
}

}  // namespace strata::server
