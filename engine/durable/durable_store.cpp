#include "engine/durable/durable_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>

#include "engine/core/timer.h"
#include "engine/durable/file_io.h"
#include "engine/engine.h"

namespace strata::durable {

namespace {

/// Takes `dir/LOCK` with flock: released by the kernel when the process dies, even by SIGKILL.
Result<int> lock_directory(const std::string& dir) {
    const std::string path = join_path(dir, "LOCK");
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
        return failure(ErrorCode::Storage, errno_message("cannot create the lock file " + path +
                                                         " (the data directory must be writable)"));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        const int err = errno;
        char holder[32] = {};
        const ssize_t n = ::pread(fd, holder, sizeof holder - 1, 0);
        ::close(fd);
        if (err == EWOULDBLOCK)
            return failure(
                ErrorCode::Storage,
                "the data directory " + dir + " is in use by another strata-server" +
                    (n > 0 ? " (pid " + std::string(holder, std::size_t(n)) + ")" : std::string()) +
                    "; two servers cannot share one --data");
        errno = err;
        return failure(ErrorCode::Storage, errno_message("cannot lock " + path));
    }
    const std::string pid = std::to_string(::getpid());
    if (::ftruncate(fd, 0) == 0) (void)::pwrite(fd, pid.data(), pid.size(), 0);
    return fd;
}

uint64_t unix_ms_now() {
    return uint64_t(std::chrono::duration_cast<std::chrono::milliseconds>(
                        std::chrono::system_clock::now().time_since_epoch())
                        .count());
}

/// Records a snapshot now on disk (written in the background or replacing the scene).
void note_snapshot_written(DurableStats& s, uint64_t version, std::size_t bytes, double ms,
                           double lock_ms) {
    ++s.snapshots_written;
    s.last_snapshot_version = version;
    s.last_snapshot_bytes = bytes;
    s.last_snapshot_unix_ms = unix_ms_now();
    s.last_snapshot_seconds = ms / 1000.0;
    s.last_snapshot_lock_ms = lock_ms;
    s.last_snapshot_error.clear();
}

}  // namespace

DurableStore::DurableStore(const StoreOptions& options, Engine& engine)
    : m_options(options), m_engine(engine) {}

Result<std::unique_ptr<DurableStore>> DurableStore::open(const StoreOptions& options,
                                                         Engine& engine) {
    std::unique_ptr<DurableStore> store(new DurableStore(options, engine));
    const std::string& dir = options.dir;
    // Step: the directory and its lock.
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
        return failure(ErrorCode::Storage,
                       "cannot create the data directory " + dir + ": " + ec.message());
    auto fd = lock_directory(dir);
    if (!fd) return Unexpected(fd.error());
    store->m_lock_fd = fd.value();

    // Step: the scene as the directory left it.
    Stopwatch clock;
    RecoveryOptions recovery = options.recovery;
    recovery.keep_covered = options.keep_history_bytes > 0;  // kept on purpose (history_start)
    auto recovered = recover(dir, engine, recovery);
    if (!recovered) return Unexpected(recovered.error());
    store->m_recovery = std::move(recovered.value());
    store->m_stats.recovery_seconds = clock.ms() / 1000.0;
    store->m_stats.recovered_version = store->m_recovery.version;
    store->m_stats.recovered_records = store->m_recovery.records_replayed;
    store->m_stats.torn_records_truncated = store->m_recovery.torn_truncated;
    store->m_stats.directory = dir;

    // Step: the journal, from here on.
    auto journal =
        Journal::open(dir, store->m_recovery.version, options.journal, store->m_recovery.segments);
    if (!journal) return Unexpected(journal.error());
    store->m_journal = std::move(journal.value());
    engine.set_journal(store->m_journal.get());
    store->m_thread = std::thread([s = store.get()] { s->snapshot_loop(); });
    return store;
}

DurableStore::~DurableStore() {
    {
        std::lock_guard lock(m_loop_mutex);
        m_stop = true;
    }
    m_loop_cv.notify_all();
    if (m_thread.joinable()) m_thread.join();
    if (m_journal) {
        m_engine.set_journal(nullptr);
        (void)m_journal->flush();
        m_journal.reset();
    }
    if (m_lock_fd >= 0) ::close(m_lock_fd);
}

void DurableStore::snapshot_loop() {
    std::unique_lock lock(m_loop_mutex);
    while (!m_stop) {
        m_loop_cv.wait_for(lock, std::chrono::milliseconds(20), [&] { return m_stop; });
        if (m_stop) break;
        const auto now = std::chrono::steady_clock::now();
        const bool due = m_retry ? now >= m_retry_at
                                 : m_journal->bytes_since_rotation() >=
                                       m_options.snapshot_threshold_bytes;
        if (!due) continue;
        lock.unlock();
        const Status written = write_snapshot();
        lock.lock();
        if (written) {
            m_retry = false;
            continue;
        }
        // The journal still holds everything; try again later, less often while it fails.
        m_retry_delay = m_retry ? std::min(m_retry_delay * 2, std::chrono::milliseconds(15000))
                                : std::chrono::milliseconds(m_options.snapshot_retry_ms);
        m_retry = true;
        m_retry_at = std::chrono::steady_clock::now() + m_retry_delay;
    }
}

Status DurableStore::snapshot_now() {
    return write_snapshot();
}

Status DurableStore::write_snapshot() {
    std::lock_guard one_at_a_time(m_snapshot_mutex);
    Stopwatch clock;
    // Step: a consistent copy and the journal's cut, in one critical section. The copy shares
    // the scene's chunks and buffers copy-on-write (Scene::image), so edits wait microseconds.
    SceneImage image;
    HistoryState history;
    double lock_ms = 0.0;
    Status rotated = m_engine.read_with_history([&](const Scene& s, const EditHistory& h) {
        Stopwatch held;
        image = s.image();
        history = h.state();
        Status r = m_journal->rotate(image.version);
        lock_ms = held.ms();
        return r;
    });
    const uint64_t version = image.version;
    auto fail = [&](const Error& e) -> Status {
        const std::string why = "snapshot of version " + std::to_string(version) +
                                " not written (the journal keeps every record): " + e.message;
        {
            std::lock_guard stats(m_stats_mutex);
            ++m_stats.snapshot_failures;
            m_stats.last_snapshot_error = why;
        }
        if (m_options.on_snapshot_failure) m_options.on_snapshot_failure(why);
        return Unexpected(e);
    };
    if (!rotated) return fail(rotated.error());

    // Step: serialised and written outside the lock, atomically: the history first, so that a
    // snapshot on disk always has its history beside it.
    const std::string kept = encode_history(history, version);
    history = {};
    if (Status s = write_file_atomically(m_options.dir, history_name(version), kept); !s)
        return fail(s.error());
    std::string bytes = encode_snapshot(image.to_batch(), version);
    image = {};
    if (Status s = write_file_atomically(m_options.dir, snapshot_name(version), bytes); !s)
        return fail(s.error());

    // Step: what the snapshot replaces.
    remove_covered(version);
    std::lock_guard stats(m_stats_mutex);
    note_snapshot_written(m_stats, version, bytes.size(), clock.ms(), lock_ms);
    return {};
}

void DurableStore::remove_covered(uint64_t version) {
    const uint64_t keep_from = history_start(version);
    m_journal->drop_segments_before(keep_from);
    if (auto names = list_files(m_options.dir)) {
        for (const std::string& name : names.value()) {
            uint64_t v = 0;
            if ((parse_snapshot_name(name, v) || parse_history_name(name, v)) && v < keep_from)
                ::unlink(join_path(m_options.dir, name).c_str());
        }
        (void)sync_directory(m_options.dir);
    }
}

uint64_t DurableStore::history_start(uint64_t version) const {
    if (m_options.keep_history_bytes == 0) return version;
    // Step: the files on disk with their sizes, snapshots older than `version` newest first.
    std::vector<std::pair<uint64_t, uint64_t>> snapshots, segments;  // (version or base, bytes)
    auto names = list_files(m_options.dir);
    if (!names) return version;
    for (const std::string& name : names.value()) {
        uint64_t v = 0;
        const bool snapshot = parse_snapshot_name(name, v);
        if (!snapshot && !parse_segment_name(name, v)) continue;
        std::error_code ec;
        const uint64_t bytes = std::filesystem::file_size(join_path(m_options.dir, name), ec);
        if (ec) continue;
        if (snapshot && v < version) snapshots.emplace_back(v, bytes);
        if (!snapshot) segments.emplace_back(v, bytes);
    }
    std::sort(segments.begin(), segments.end());
    // A journal that still starts at version 0 starts from the empty scene: a snapshot of none.
    if (!segments.empty() && segments.front().first == 0) snapshots.emplace_back(0, 0);
    std::sort(snapshots.rbegin(), snapshots.rend());
    // Step: the oldest snapshot whose files, and the segments after it up to `version`, fit the
    // budget. A segment is needed from S when the next one starts after S.
    uint64_t start = version;
    uint64_t snapshot_bytes = 0;
    for (const auto& [s, bytes] : snapshots) {
        snapshot_bytes += bytes;
        uint64_t total = snapshot_bytes;
        for (std::size_t i = 0; i < segments.size(); ++i) {
            const bool covered = i + 1 < segments.size() && segments[i + 1].first <= s;
            if (!covered && segments[i].first < version) total += segments[i].second;
        }
        if (total > m_options.keep_history_bytes) break;
        start = s;
    }
    return start;
}

Result<SnapshotReplace> DurableStore::replace_scene(std::string_view snapshot) {
    // One snapshot at a time: the background thread neither rotates nor removes meanwhile.
    std::lock_guard one_at_a_time(m_snapshot_mutex);
    Stopwatch clock;
    auto view = open_snapshot(snapshot);
    if (!view) return Unexpected(view.error());
    const uint64_t version = view->version;
    const std::string name = snapshot_name(version);
    // Step: the snapshot is durable here before the swap. A crash before the swap recovers it
    // (its version covers every record the journal holds); the journal's next segment starts
    // at it under the scene lock, so no record after it can land in an older segment.
    bool written = false;
    auto replaced = m_engine.replace_with_snapshot(view->payload, version, [&]() -> Status {
        if (Status s = write_file_atomically(m_options.dir, name, snapshot); !s) return s;
        written = true;
        return {};
    });
    if (!replaced) {
        if (written) {
            ::unlink(join_path(m_options.dir, name).c_str());
            (void)sync_directory(m_options.dir);
        }
        return Unexpected(replaced.error());
    }
    remove_covered(version);
    std::lock_guard stats(m_stats_mutex);
    note_snapshot_written(m_stats, version, snapshot.size(), clock.ms(), replaced->lock_ms);
    return replaced;
}

void DurableStore::set_rebuild_seconds(double seconds) {
    std::lock_guard stats(m_stats_mutex);
    m_stats.rebuild_seconds = seconds;
}

DurableStats DurableStore::stats() const {
    DurableStats s;
    {
        std::lock_guard stats(m_stats_mutex);
        s = m_stats;
    }
    m_journal->add_stats(s);
    return s;
}

}  // namespace strata::durable
