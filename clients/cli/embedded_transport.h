#pragma once
// The protocol in-process: an Engine of its own behind the same API functions strata-server's
// routes call (protocol/api.h), so `strata play --embedded` sees exactly the server's reports,
// problem documents and headers without a server.
//
// The one file of clients/ that links the engine and the protocol layer (the layering check in
// tests/check_layering.cmake keeps it that way).

#include <memory>

#include "clients/cli/outcome.h"
#include "clients/cli/transport.h"

namespace strata {
class Engine;
}

namespace strata::cli {

class EmbeddedTransport final : public Transport {
public:
    /// Starts an engine; with `demo`, loaded with the demo scene like `strata-server --demo`.
    static Outcome<std::unique_ptr<EmbeddedTransport>> create(bool demo);
    ~EmbeddedTransport() override;

    Reply edits(std::string body, const std::optional<std::string>& if_match) override;
    Reply undo(bool redo, const std::optional<std::string>& if_match) override;
    Reply history(const std::multimap<std::string, std::string>& query) override;
    Reply commit() override;
    Reply plan() override;
    Reply render(const std::string& body) override;
    Reply stats() override;
    Reply scene() override;
    Reply scene_list(const std::string& collection,
                     const std::multimap<std::string, std::string>& query) override;
    Reply scene_object(const std::string& collection, const std::string& id) override;
    Reply pick(const std::string& body) override;
    Reply get_snapshot(std::optional<uint64_t> at_version,
                       const std::optional<std::string>& at_time) override;
    Reply put_snapshot(std::string bytes) override;
    Reply import_asset(std::string bytes,
                       const std::multimap<std::string, std::string>& query) override;
    Reply assets(const std::optional<std::string>& id) override;
    Reply delete_asset(const std::string& id) override;
    Reply put_asset(const std::string& id, std::string bytes,
                    const std::multimap<std::string, std::string>& query) override;
    std::string describe() const override { return "the embedded engine"; }

private:
    explicit EmbeddedTransport(std::unique_ptr<Engine> engine);

    std::unique_ptr<Engine> m_engine;
};

}  // namespace strata::cli
