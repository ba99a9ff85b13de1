#pragma once
// Frames across replicas: GET/POST /v1/render with `split=N` renders horizontal bands of one
// frame on this server and N-1 of its peers (--peers) and answers the frame a single render of
// the same request gives, byte for byte.
//
//   1. The bands: split_rows (engine/render/band_assembly.h), band 0 here, band k on peer k.
//   2. Each peer is asked, concurrently, for its band as a full-precision EXR
//      (`band=y0,rows&format=exr&compression=none`, the filter's guides as AOVs when the frame is
//      filtered) with `min_version` = this server's version, and this server's bearer token.
//   3. This server renders band 0; the version of that launch is the frame's version V.
//   4. A peer's band counts only when its ETag says V and its EXR reads back as the band. Any
//      other answer (down, refused, slower than --peer-timeout-ms, ahead of or behind V) is
//      rendered here instead, all such bands in one launch; should that launch see another
//      version than V (an edit arrived meanwhile), every band is rendered here, in one launch.
//   5. The bands are assembled and finished (filtered, guides dropped, ID names merged) and the
//      frame encoded once, the way one render encodes it.
//
// X-Strata-Split says what happened: "3 bands at version 7: local, http://10.0.0.2:7070, local
// (http://10.0.0.3:7070: 503 ...)". Peers that follow the same edit log (server/replica) hold the
// same scene at the same versions; any server holding the same scene at V serves as a peer.
// Cancellation (deadline, client gone, shutdown) stops the local launches and abandons the
// peers' requests.

#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"
#include "engine/engine.h"
#include "protocol/api.h"

namespace strata::server {

/// One peer: its base URL as given (`http://host:port`) and where to connect.
struct PeerServer {
    std::string url;
    std::string host;
    int port = 80;
};

/// Parses --peers: comma-separated `http://host:port` (or `host:port`) URLs without paths. The
/// error names the item at fault.
Result<std::vector<PeerServer>> parse_peers(std::string_view list);

class SplitRenderer {
public:
    /// `token`: sent to peers as `Authorization: Bearer` when not empty (the server's own).
    SplitRenderer(Engine& engine, std::vector<PeerServer> peers, std::string token,
                  std::chrono::milliseconds peer_timeout);

    /// Renders `request` (checked; its cancel token set) in `split` bands: protocol::SplitRender.
    Result<protocol::SplitFrame> render(const RenderRequest& request, uint32_t split);

    const std::vector<PeerServer>& peers() const { return m_peers; }

private:
    Engine& m_engine;
    std::vector<PeerServer> m_peers;
    std::string m_token;
    std::chrono::milliseconds m_peer_timeout;
};

/// The query of the band request a coordinator sends for `band` of `request` (without
/// min_version): band_request's members as GET /v1/render parameters, floats written so that
/// they read back as the same floats.
std::string band_query(const RenderRequest& request, RowBand band);

}  // namespace strata::server
