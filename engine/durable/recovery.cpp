#include "engine/durable/recovery.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "engine/durable/edit_codec.h"
#include "engine/durable/file_io.h"
#include "engine/engine.h"

namespace strata::durable {

namespace {

Unexpected<Error> damaged(const std::string& path, const std::string& problem,
                          const std::string& consequence) {
    return failure(ErrorCode::Storage,
                   path + " is damaged: " + problem + ". Refusing to start: " + consequence +
                       ". Start with --recover-truncate to keep what precedes the damage and "
                       "set the rest aside");
}

/// Renames `path` to `path.damaged` (kept for forensics, never read again).
void set_aside(const std::string& path, RecoveryResult& out) {
    const std::string to = path + ".damaged";
    if (::rename(path.c_str(), to.c_str()) == 0) {
        out.notes.push_back("set aside " + path + " as " + to);
    } else {
        ::unlink(path.c_str());
        out.notes.push_back("removed " + path);
    }
}

/// The history written beside snapshot `version` (journal_format.h), into `engine`. One that is
/// missing (a directory from before history files) or damaged costs only the history before the
/// snapshot, never the scene: a note says so.
void restore_history(const std::string& dir, uint64_t version, Engine& engine,
                     RecoveryResult& out) {
    const std::string path = join_path(dir, history_name(version));
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return;
    auto bytes = read_whole_file(path);
    Result<DecodedHistory> history =
        bytes ? decode_history(bytes.value()) : Result<DecodedHistory>(Unexpected(bytes.error()));
    if (history && history->version != version)
        history = failure(ErrorCode::InvalidArgument,
                          "it holds version " + std::to_string(history->version));
    if (!history) {
        out.notes.push_back("the history saved with the snapshot was not restored (" + path +
                            ": " + history.error().message + "): undo reaches back to version " +
                            std::to_string(version) + " only");
        return;
    }
    const HistoryState& h = history->state;
    out.notes.push_back("restored the history saved with the snapshot (" +
                        std::to_string(h.entries.size()) + " versions, " +
                        std::to_string(h.undo.size()) + " to undo, " +
                        std::to_string(h.redo.size()) + " to redo)");
    engine.restore_history(std::move(history->state));
}

}  // namespace

std::string RecoveryProgress::describe() const {
    const uint64_t v = version.load();
    switch (phase.load()) {
        case Opening: return "recovering the scene: opening the data directory";
        case Snapshot:
            return "recovering the scene: loading the snapshot of version " + std::to_string(v);
        case Journal: {
            const uint64_t total = journal_bytes_total.load();
            const uint64_t done = std::min(journal_bytes_done.load(), total);
            const int percent = total ? int(done * 100 / total) : 100;
            return "recovering the scene: replaying the journal, at version " + std::to_string(v) +
                   " after " + std::to_string(records_replayed.load()) + " records (" +
                   std::to_string(percent) + "% of " + std::to_string(total) + " bytes)";
        }
        case Building:
            return "the scene is recovered (version " + std::to_string(v) +
                   "); its acceleration structures are being built";
        default: return "ready";
    }
}

Result<RecoveryResult> recover(const std::string& dir, Engine& engine,
                               const RecoveryOptions& options) {
    RecoveryResult out;
    RecoveryProgress unreported;
    RecoveryProgress& progress = options.progress ? *options.progress : unreported;
    auto names = list_files(dir);
    if (!names) return Unexpected(names.error());

    // Step: sort the directory: snapshots newest first, segments oldest first; leftovers of an
    // interrupted snapshot write are removed.
    std::vector<std::pair<uint64_t, std::string>> snapshots, segments;
    for (const std::string& name : names.value()) {
        uint64_t n = 0;
        if (parse_snapshot_name(name, n)) {
            snapshots.emplace_back(n, join_path(dir, name));
        } else if (parse_segment_name(name, n)) {
            segments.emplace_back(n, join_path(dir, name));
        } else if (name.size() > 4 && name.substr(name.size() - 4) == ".tmp") {
            ::unlink(join_path(dir, name).c_str());
            out.notes.push_back("removed " + join_path(dir, name) +
                                " (an interrupted snapshot write)");
        }
    }
    std::sort(snapshots.rbegin(), snapshots.rend());
    std::sort(segments.begin(), segments.end());

    // Step: the newest snapshot that reads back whole.
    for (const auto& [version, path] : snapshots) {
        progress.version = version;
        progress.phase = RecoveryProgress::Snapshot;
        auto bytes = read_whole_file(path);
        if (!bytes) return Unexpected(bytes.error());
        auto snap = open_snapshot(bytes.value());
        if (snap && snap->version != version) {
            snap = failure(ErrorCode::InvalidArgument,
                           "it holds version " + std::to_string(snap->version) +
                               " but its name says " + std::to_string(version));
        }
        // Loaded straight into the scene's storage, edit by edit (Engine::restore_snapshot). A
        // payload that does not decode is damage like a bad checksum; one the rules refuse is not
        // a file problem and stops recovery.
        Status loaded = snap ? engine.restore_snapshot(snap->payload, version) : Status{};
        const bool undecodable = snap && !loaded &&
                                 loaded.error().code == ErrorCode::InvalidArgument &&
                                 loaded.error().edit_index == Error::NO_INDEX;
        if (!snap || undecodable) {
            const std::string why = !snap ? snap.error().message
                                          : "snapshot " + loaded.error().message;
            if (!options.truncate_damage)
                return damaged(path, why, "the scene at that version cannot be loaded");
            set_aside(path, out);
            continue;
        }
        if (!loaded)
            return failure(ErrorCode::Storage, "snapshot " + path +
                                                   " could not be loaded: " +
                                                   loaded.error().describe());
        out.loaded_snapshot = true;
        out.snapshot_version = version;
        out.notes.push_back("loaded snapshot " + path + " (version " + std::to_string(version) +
                            ")");
        restore_history(dir, version, engine, out);
        break;
    }
    uint64_t current = out.snapshot_version;

    // Step: segments wholly covered by the snapshot (the next one starts at or before it) are
    // what an interrupted clean-up left behind.
    std::size_t first = 0;
    while (first + 1 < segments.size() && segments[first + 1].first <= current) ++first;
    for (std::size_t i = 0; i < first; ++i) {
        if (options.keep_covered) {
            std::error_code ec;
            const auto size = std::filesystem::file_size(segments[i].second, ec);
            out.segments.push_back({segments[i].first, segments[i].second, ec ? 0 : size});
            continue;
        }
        ::unlink(segments[i].second.c_str());
        out.notes.push_back("removed " + segments[i].second + " (covered by the snapshot)");
    }
    segments.erase(segments.begin(), segments.begin() + std::ptrdiff_t(first));

    // Step: replay, checking that versions follow one another.
    progress.version = current;
    {
        uint64_t total = 0;
        std::error_code ec;
        for (const auto& segment : segments) {
            const auto size = std::filesystem::file_size(segment.second, ec);
            if (!ec) total += size;
        }
        progress.journal_bytes_total = total;
    }
    progress.phase = RecoveryProgress::Journal;
    uint64_t bytes_before = 0;  // in the segments before this one
    for (std::size_t i = 0; i < segments.size(); ++i) {
        const auto& [base, path] = segments[i];
        const bool last = i + 1 == segments.size();
        auto bytes = read_whole_file(path);
        if (!bytes) return Unexpected(bytes.error());
        const uint64_t segment_start = bytes_before;
        bytes_before += bytes->size();
        const SegmentScan scan = scan_segment(bytes.value());
        if (scan.empty_file ||
            (scan.tail == SegmentScan::Tail::Torn && scan.records.empty() && scan.valid_end == 0)) {
            // A crash between creating the file and writing its header.
            if (!last && !options.truncate_damage)
                return damaged(path, "the file has no complete header",
                               "later journal files would follow a gap");
            ::unlink(path.c_str());
            out.notes.push_back("removed " + path + " (no complete header: " +
                                (scan.empty_file ? std::string("empty file") : scan.problem) + ")");
            continue;
        }
        if (scan.tail == SegmentScan::Tail::Corrupt && scan.valid_end == 0) {
            if (!options.truncate_damage)
                return damaged(path, scan.problem, "its records cannot be read");
            for (std::size_t k = i; k < segments.size(); ++k) set_aside(segments[k].second, out);
            break;
        }
        if (scan.base > current) {
            const std::string problem = "it starts after version " + std::to_string(scan.base) +
                                        " but the scene is at " + std::to_string(current);
            if (!options.truncate_damage)
                return damaged(path, problem, "versions in between are missing");
            for (std::size_t k = i; k < segments.size(); ++k) set_aside(segments[k].second, out);
            break;
        }
        bool stop = false;
        uint64_t keep_bytes = scan.valid_end;
        for (const ScannedRecord& r : scan.records) {
            if (r.version <= current) continue;
            std::string problem;
            if (r.version != current + 1) {
                problem = "record at offset " + std::to_string(r.offset) + " has version " +
                          std::to_string(r.version) + ", expected " + std::to_string(current + 1);
            } else {
                auto batch = decode_batch(r.payload);
                if (!batch) {
                    problem = "record at offset " + std::to_string(r.offset) +
                              " does not decode: " + batch.error().message;
                } else {
                    auto applied = engine.apply(std::move(batch.value()));
                    if (!applied) {
                        problem = "record at offset " + std::to_string(r.offset) + " (version " +
                                  std::to_string(r.version) +
                                  ") was refused on replay: " + applied.error().describe();
                    } else {
                        current = applied->version;
                        ++out.records_replayed;
                        progress.version = current;
                        progress.records_replayed = out.records_replayed;
                        progress.journal_bytes_done = segment_start + r.offset + r.payload.size();
                        continue;
                    }
                }
            }
            if (!options.truncate_damage)
                return damaged(path, problem, "the records after it cannot be replayed");
            keep_bytes = r.offset;
            stop = true;
            break;
        }
        // Step: the end of the segment. A torn tail of the newest segment is a crash mid-write.
        std::string cut_reason;
        if (!stop && scan.tail == SegmentScan::Tail::Torn && last) {
            ++out.torn_truncated;
            cut_reason = "torn last record (" + scan.problem + ")";
        } else if (!stop && scan.tail != SegmentScan::Tail::Clean) {
            if (!options.truncate_damage)
                return damaged(path, scan.problem,
                               last ? "records after the damage would be lost"
                                    : "later journal files would follow a gap");
            stop = true;
        }
        if (stop) cut_reason = "damage kept out by --recover-truncate";
        if (keep_bytes < bytes->size()) {
            if (::truncate(path.c_str(), off_t(keep_bytes)) != 0)
                return failure(ErrorCode::Storage, errno_message("cannot truncate " + path));
            out.notes.push_back("truncated " + path + " at offset " + std::to_string(keep_bytes) +
                                " (" + std::to_string(bytes->size() - keep_bytes) +
                                " bytes): " + cut_reason);
        }
        out.segments.push_back({base, path, keep_bytes});
        if (stop) {
            for (std::size_t k = i + 1; k < segments.size(); ++k)
                set_aside(segments[k].second, out);
            break;
        }
    }
    if (!out.notes.empty() || !segments.empty()) (void)sync_directory(dir);
    out.version = current;
    return out;
}

}  // namespace strata::durable
