#include "engine/durable/journal.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "engine/core/timer.h"
#include "engine/durable/file_io.h"

namespace strata::durable {

const char* fsync_mode_name(FsyncMode m) {
    switch (m) {
        case FsyncMode::Always:
            return "always";
        case FsyncMode::Batch:
            return "batch";
        case FsyncMode::Off:
            return "off";
    }
    return "always";
}

/// An open segment. Closed when the last holder (the journal, a sync leader) lets go.
struct Journal::File {
    int fd = -1;
    std::string path;
    uint64_t base = 0;
    uint64_t size = 0;  ///< bytes in the file (the append position)

    ~File() {
        if (fd >= 0) ::close(fd);
    }
};

Journal::Journal(std::string dir, const JournalOptions& options)
    : m_dir(std::move(dir)), m_options(options) {
    m_stats.mode = options.mode;
}

Journal::~Journal() {
    {
        std::lock_guard lock(m_mutex);
        m_stop = true;
    }
    m_stop_cv.notify_all();
    if (m_background.joinable()) m_background.join();
    // A graceful stop loses nothing, whatever the mode.
    (void)flush();
}

Result<std::unique_ptr<Journal>> Journal::open(const std::string& dir, uint64_t version,
                                               const JournalOptions& options,
                                               std::vector<SegmentInfo> segments) {
    std::unique_ptr<Journal> j(new Journal(dir, options));
    j->m_segments = std::move(segments);
    if (!j->m_segments.empty()) {
        // Step: append to the newest segment, which recovery left ending with a good record.
        SegmentInfo& last = j->m_segments.back();
        auto file = std::make_shared<File>();
        file->fd = ::open(last.path.c_str(), O_WRONLY | O_CLOEXEC);
        if (file->fd < 0)
            return failure(ErrorCode::Storage, errno_message("cannot open " + last.path));
        file->path = last.path;
        file->base = last.base;
        file->size = last.bytes;
        if (::lseek(file->fd, off_t(file->size), SEEK_SET) < 0)
            return failure(ErrorCode::Storage, errno_message("cannot seek in " + last.path));
        j->m_current = std::move(file);
    } else {
        auto file = j->create_segment(version);
        if (!file) return Unexpected(file.error());
        j->m_current = std::move(file.value());
        j->m_segments.push_back({version, j->m_current->path, j->m_current->size});
        // The new file must survive a crash before any record in it is acknowledged.
        if (Status s = sync_file(j->m_current->fd, j->m_current->path); !s)
            return Unexpected(s.error());
        if (Status s = sync_directory(dir); !s) return Unexpected(s.error());
    }
    if (options.mode == FsyncMode::Batch)
        j->m_background = std::thread([p = j.get()] { p->background_sync_loop(); });
    return j;
}

Result<std::shared_ptr<Journal::File>> Journal::create_segment(uint64_t base) {
    auto file = std::make_shared<File>();
    file->path = join_path(m_dir, segment_name(base));
    file->base = base;
    // O_TRUNC: a leftover file of that name holds nothing recovery kept (it would have been
    // reopened instead).
    file->fd = ::open(file->path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (file->fd < 0)
        return failure(ErrorCode::Storage, errno_message("cannot create " + file->path));
    const std::string header = segment_header(base);
    if (Status s = write_all(file->fd, header, file->path); !s) {
        ::unlink(file->path.c_str());
        return Unexpected(s.error());
    }
    file->size = header.size();
    return file;
}

Result<uint64_t> Journal::append(PendingRecord& record, uint64_t version) {
    stamp_record(record, version);
    std::lock_guard lock(m_mutex);
    if (!m_failure.empty())
        return failure(ErrorCode::Storage,
                       "the journal refuses batches since an fsync failed (" + m_failure +
                           "); restart the server to recover the last durable state");
    File& f = *m_current;
    std::size_t written = 0;
    Status s = write_all(f.fd, record.bytes, f.path, &written);
    if (!s) {
        // Step: leave no partial record behind; the batch is rolled back by the caller.
        if (written > 0 &&
            (::ftruncate(f.fd, off_t(f.size)) != 0 || ::lseek(f.fd, off_t(f.size), SEEK_SET) < 0)) {
            m_failure = errno_message("cannot cut a partial record off " + f.path);
            m_stats.failed = true;
            m_stats.failure = m_failure;
        }
        return failure(ErrorCode::Storage,
                       "the batch was not applied: the journal could not store it (" +
                           s.error().message + ")");
    }
    f.size += record.bytes.size();
    m_segments.back().bytes = f.size;
    m_written += record.bytes.size();
    m_since_rotation += record.bytes.size();
    ++m_records_written;
    ++m_stats.journal_records;
    m_stats.journal_appended_bytes += record.bytes.size();
    return m_written;
}

Status Journal::wait_durable(uint64_t position) {
    if (m_options.mode != FsyncMode::Always) return {};
    std::unique_lock lock(m_mutex);
    while (m_synced < position) {
        if (!m_failure.empty())
            return failure(ErrorCode::Storage,
                           "the batch was applied but could not be made durable (" + m_failure +
                               "); it may be lost on restart");
        if (m_syncing) {
            m_synced_cv.wait(lock);
            continue;
        }
        sync_as_leader(lock);
    }
    return {};
}

void Journal::sync_as_leader(std::unique_lock<std::mutex>& lock) {
    m_syncing = true;
    const uint64_t target = m_written;
    const uint64_t records = m_records_written;
    std::vector<std::shared_ptr<File>> files = std::move(m_retired);
    m_retired.clear();
    files.push_back(m_current);
    const bool dir = std::exchange(m_dir_dirty, false);
    lock.unlock();

    Status s;
    Stopwatch clock;
    int syncs = 0;
    for (const auto& f : files) {
        if (!s) break;
        s = sync_file(f->fd, f->path);
        ++syncs;
    }
    if (s && dir) {
        s = sync_directory(m_dir);
        ++syncs;
    }
    const double seconds = clock.ms() / 1000.0;
    files.clear();

    lock.lock();
    m_syncing = false;
    m_stats.fsyncs += syncs;
    m_stats.fsync_seconds += seconds;
    std::size_t bucket = 0;
    while (bucket < FSYNC_BOUNDS.size() && seconds > FSYNC_BOUNDS[bucket]) ++bucket;
    ++m_stats.fsync_buckets[bucket];
    if (s) {
        m_stats.batches_per_fsync_max =
            std::max(m_stats.batches_per_fsync_max, records - m_records_synced);
        m_synced = std::max(m_synced, target);
        m_records_synced = std::max(m_records_synced, records);
    } else {
        // After a failed fsync the kernel may have dropped the dirty pages: what the file holds
        // is unknown, so nothing more is acknowledged (PostgreSQL's lesson from fsyncgate).
        m_failure = s.error().message;
        m_stats.failed = true;
        m_stats.failure = m_failure;
    }
    m_synced_cv.notify_all();
}

void Journal::background_sync_loop() {
    std::unique_lock lock(m_mutex);
    const auto interval = std::chrono::milliseconds(std::max(1, m_options.fsync_interval_ms));
    while (!m_stop) {
        m_stop_cv.wait_for(lock, interval, [&] { return m_stop; });
        if (m_stop) break;
        if (m_synced < m_written && !m_syncing && m_failure.empty()) sync_as_leader(lock);
    }
}

Status Journal::rotate(uint64_t version) {
    {
        std::lock_guard lock(m_mutex);
        // Nothing appended since the segment began: it already starts at `version`.
        if (m_current->base == version) return {};
    }
    auto file = create_segment(version);
    if (!file) return Unexpected(file.error());
    std::lock_guard lock(m_mutex);
    // The old segment still needs its fsync (Always and Batch); the next leader does it.
    if (m_options.mode != FsyncMode::Off) m_retired.push_back(std::move(m_current));
    m_current = std::move(file.value());
    m_segments.push_back({version, m_current->path, m_current->size});
    m_dir_dirty = true;
    m_written += m_current->size;  // the header must be durable with the first record
    m_since_rotation = 0;
    return {};
}

void Journal::drop_segments_before(uint64_t version) {
    std::vector<std::string> doomed;
    {
        std::lock_guard lock(m_mutex);
        // A segment's records all precede `version` when the next segment starts at or before it.
        std::size_t keep = 0;
        while (keep + 1 < m_segments.size() && m_segments[keep + 1].base <= version) ++keep;
        for (std::size_t i = 0; i < keep; ++i) doomed.push_back(m_segments[i].path);
        m_segments.erase(m_segments.begin(), m_segments.begin() + std::ptrdiff_t(keep));
    }
    for (const std::string& path : doomed) ::unlink(path.c_str());
    if (!doomed.empty()) (void)sync_directory(m_dir);
}

uint64_t Journal::bytes_since_rotation() const {
    std::lock_guard lock(m_mutex);
    return m_since_rotation;
}

Status Journal::flush() {
    std::unique_lock lock(m_mutex);
    while (m_syncing) m_synced_cv.wait(lock);
    if (!m_failure.empty()) return failure(ErrorCode::Storage, m_failure);
    if (m_synced < m_written || !m_retired.empty() || m_dir_dirty) sync_as_leader(lock);
    if (!m_failure.empty()) return failure(ErrorCode::Storage, m_failure);
    return {};
}

void Journal::add_stats(DurableStats& stats) const {
    std::lock_guard lock(m_mutex);
    uint64_t bytes = 0;
    for (const SegmentInfo& s : m_segments) bytes += s.bytes;
    stats.journal_bytes = bytes;
    stats.journal_records = m_stats.journal_records;
    stats.journal_appended_bytes = m_stats.journal_appended_bytes;
    stats.fsyncs = m_stats.fsyncs;
    stats.fsync_seconds = m_stats.fsync_seconds;
    stats.batches_per_fsync_max = m_stats.batches_per_fsync_max;
    stats.fsync_buckets = m_stats.fsync_buckets;
    stats.mode = m_options.mode;
    stats.failed = m_stats.failed;
    stats.failure = m_stats.failure;
}

}  // namespace strata::durable
