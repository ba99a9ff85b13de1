// A past version of a data directory's scene, loaded read-only (past_version.h).

#include "engine/durable/past_version.h"

#include <algorithm>
#include <filesystem>
#include <utility>
#include <vector>

#include "engine/core/timer.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/file_io.h"
#include "engine/durable/journal_format.h"

namespace strata::durable {

namespace {

using Named = std::vector<std::pair<uint64_t, std::string>>;

/// The directory's snapshots and segments, each sorted by version.
Status list_directory(const std::string& dir, Named& snapshots, Named& segments) {
    auto names = list_files(dir);
    if (!names) return Unexpected(names.error());
    for (const std::string& name : names.value()) {
        uint64_t n = 0;
        if (parse_snapshot_name(name, n))
            snapshots.emplace_back(n, join_path(dir, name));
        else if (parse_segment_name(name, n))
            segments.emplace_back(n, join_path(dir, name));
    }
    std::sort(snapshots.begin(), snapshots.end());
    std::sort(segments.begin(), segments.end());
    return {};
}

/// A file's bytes; `vanished` is set when it was removed since it was listed (a snapshot's
/// clean-up: the caller lists again).
Result<std::string> read_listed(const std::string& path, bool& vanished) {
    auto bytes = read_whole_file(path);
    if (!bytes && !std::filesystem::exists(path)) vanished = true;
    return bytes;
}

Error damaged(const std::string& path, const std::string& why) {
    return make_error(ErrorCode::Storage, path + ": " + why);
}

/// Applies the records of one segment (`bytes`, read from `path`) that follow `current`, up to
/// `version`, to `engine`; `current` follows them.
Status replay(const std::string& path, std::string_view bytes, uint64_t version, Engine& engine,
              uint64_t& current, PastVersionLoad& load) {
    const SegmentScan scan = scan_segment(bytes);
    if (scan.base > current)
        return Unexpected(damaged(path, "it starts after version " + std::to_string(scan.base) +
                                            ", past the scene's " + std::to_string(current)));
    for (const ScannedRecord& r : scan.records) {
        if (r.version <= current) continue;
        if (r.version > version) break;
        if (r.version != current + 1)
            return Unexpected(damaged(path, "record at offset " + std::to_string(r.offset) +
                                                " has version " + std::to_string(r.version) +
                                                ", expected " + std::to_string(current + 1)));
        auto batch = decode_batch(r.payload);
        if (!batch) return Unexpected(damaged(path, batch.error().message));
        auto applied = engine.apply(std::move(batch.value()));
        if (!applied) return Unexpected(damaged(path, applied.error().describe()));
        current = applied->version;
        ++load.records_replayed;
    }
    // A torn tail is a record being written now: only what precedes it is needed.
    if (scan.tail == SegmentScan::Tail::Corrupt && current < version)
        return Unexpected(damaged(path, scan.problem));
    return {};
}

/// One try at loading `version`; `vanished` says a listed file went away meanwhile.
Result<std::unique_ptr<Engine>> try_load(const std::string& dir, uint64_t version,
                                         const EngineConfig& config, PastVersionLoad& load,
                                         bool& vanished) {
    Named snapshots, segments;
    if (Status s = list_directory(dir, snapshots, segments); !s) return Unexpected(s.error());
    // Step: where to start: the newest snapshot at or before the version, or the empty scene
    // when the journal still starts at version 0.
    const bool from_empty = !segments.empty() && segments.front().first == 0;
    const std::pair<uint64_t, std::string>* start = nullptr;
    for (const auto& s : snapshots)
        if (s.first <= version) start = &s;
    if (!start && !from_empty) {
        const uint64_t oldest = snapshots.empty() ? 0 : snapshots.front().first;
        return failure(ErrorCode::OutOfRange,
                       "version " + std::to_string(version) +
                           " is older than the data directory keeps (its oldest is version " +
                           std::to_string(oldest) + ")");
    }

    auto created = Engine::create(config);
    if (!created) return Unexpected(created.error());
    std::unique_ptr<Engine> engine = std::move(created.value());
    uint64_t current = 0;
    if (start) {
        auto bytes = read_listed(start->second, vanished);
        if (!bytes) return Unexpected(bytes.error());
        auto snap = open_snapshot(bytes.value());
        if (!snap) return Unexpected(damaged(start->second, snap.error().message));
        if (Status s = engine->restore_snapshot(snap->payload, start->first); !s)
            return Unexpected(damaged(start->second, s.error().describe()));
        current = load.snapshot_version = start->first;
    }

    // Step: the records after it, up to the version. A segment whose successor starts at or
    // before the current version holds nothing needed.
    for (std::size_t i = 0; i < segments.size() && current < version; ++i) {
        if (i + 1 < segments.size() && segments[i + 1].first <= current) continue;
        auto bytes = read_listed(segments[i].second, vanished);
        if (!bytes) return Unexpected(bytes.error());
        load.journal_bytes += bytes->size();
        if (Status s = replay(segments[i].second, bytes.value(), version, *engine, current, load);
            !s)
            return Unexpected(s.error());
    }
    if (current != version)
        return failure(ErrorCode::OutOfRange, "version " + std::to_string(version) +
                                                  " is not in the data directory (its journal "
                                                  "ends at version " +
                                                  std::to_string(current) + ")");
    return engine;
}

}  // namespace

Result<std::unique_ptr<Engine>> load_past_version(const std::string& dir, uint64_t version,
                                                  EngineConfig config, PastVersionLoad* load) {
    Stopwatch clock;
    config.history.max_undo = 0;  // never edited: no inverses to keep
    // A snapshot written meanwhile removes the files it covers; listing again finds it.
    for (int attempt = 0;; ++attempt) {
        PastVersionLoad done;
        bool vanished = false;
        auto engine = try_load(dir, version, config, done, vanished);
        if (engine || !vanished || attempt == 2) {
            done.load_ms = clock.ms();
            if (load) *load = done;
            return engine;
        }
    }
}

}  // namespace strata::durable
