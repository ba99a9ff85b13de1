#include "protocol/assets/sandbox.h"

#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <new>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <seccomp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace strata::assets {

namespace {

/// Bytes of address space the process has mapped now (/proc/self/statm's first field).
uint64_t mapped_bytes() {
    std::ifstream statm("/proc/self/statm");
    uint64_t pages = 0;
    statm >> pages;
    return pages * uint64_t(sysconf(_SC_PAGESIZE));
}

// Step (child): limits, descriptors, seccomp; then the work and its result down the pipe. Only
// the calling thread exists in the child; glibc's fork leaves malloc usable.

void limit(int resource, uint64_t soft, uint64_t hard) {
    const rlimit r{rlim_t(soft), rlim_t(hard)};
    setrlimit(resource, &r);
}

/// Keeps `out` (moved to 3 or above) and stderr; closes every other descriptor. Returns `out`'s
/// new number.
int keep_only(int out) {
    const int fd = out >= 3 ? out : fcntl(out, F_DUPFD, 3);
    close(0);
    close(1);
    if (fd > 3) close_range(3, unsigned(fd) - 1, 0);
    close_range(unsigned(fd) + 1, ~0u, 0);
    return fd;
}

/// The system calls an importer makes: memory, the pipe and stderr, futexes, the clock, signals
/// to itself. Opening or probing a path fails with EACCES (glibc's malloc reads
/// /proc/sys/vm/overcommit_memory when it first grows a thread's arena, and copes when it
/// cannot); anything else kills the child (SIGSYS). False when the filter could not be
/// installed.
bool install_filter(int out) {
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_KILL_PROCESS);
    if (!ctx) return false;
    bool ok = true;
    const auto allow = [&](int call) { ok = ok && seccomp_rule_add(ctx, SCMP_ACT_ALLOW, call, 0) == 0; };
    for (int call : {SCMP_SYS(brk), SCMP_SYS(mmap), SCMP_SYS(munmap), SCMP_SYS(mremap),
                     SCMP_SYS(madvise), SCMP_SYS(mprotect), SCMP_SYS(futex), SCMP_SYS(close),
                     SCMP_SYS(exit), SCMP_SYS(exit_group), SCMP_SYS(rt_sigreturn),
                     SCMP_SYS(rt_sigprocmask), SCMP_SYS(rt_sigaction), SCMP_SYS(sigaltstack),
                     SCMP_SYS(clock_gettime), SCMP_SYS(gettimeofday), SCMP_SYS(getpid),
                     SCMP_SYS(gettid), SCMP_SYS(getrandom), SCMP_SYS(fstat),
                     SCMP_SYS(lseek), SCMP_SYS(sched_yield), SCMP_SYS(sched_getaffinity)})
        allow(call);
    // Naming memory mappings (newer glibc names its malloc arenas): refused, not fatal.
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(prctl), 0);
    // fstat() of a descriptor only (glibc: newfstatat(fd, "", buf, AT_EMPTY_PATH)).
    ok = ok && seccomp_rule_add(ctx, SCMP_ACT_ALLOW, SCMP_SYS(newfstatat), 1,
                                SCMP_A3(SCMP_CMP_EQ, scmp_datum_t(AT_EMPTY_PATH))) == 0;
    // Paths: refused, not fatal. Calls this architecture lacks (open on aarch64) are skipped.
    for (int call : {SCMP_SYS(open), SCMP_SYS(openat), SCMP_SYS(openat2), SCMP_SYS(stat),
                     SCMP_SYS(lstat), SCMP_SYS(access), SCMP_SYS(faccessat), SCMP_SYS(faccessat2),
                     SCMP_SYS(readlink), SCMP_SYS(readlinkat), SCMP_SYS(statx)})
        if (call >= 0) seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EACCES), call, 0);
    // Writes only to the pipe and stderr; signals only to itself (abort()).
    for (int call : {SCMP_SYS(write), SCMP_SYS(writev)}) {
        for (int fd : {out, 2})
            ok = ok && seccomp_rule_add(ctx, SCMP_ACT_ALLOW, call, 1,
                                        SCMP_A0(SCMP_CMP_EQ, scmp_datum_t(fd))) == 0;
    }
    ok = ok && seccomp_rule_add(ctx, SCMP_ACT_ALLOW, SCMP_SYS(tgkill), 1,
                                SCMP_A0(SCMP_CMP_EQ, scmp_datum_t(getpid()))) == 0;
    ok = ok && seccomp_load(ctx) == 0;
    seccomp_release(ctx);
    return ok;
}

bool write_all(int fd, const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        done += std::size_t(n);
    }
    return true;
}

[[noreturn]] void child(int out, const std::function<Imported<ImportOutcome>()>& work,
                        const std::string& file, const SandboxLimits& limits, uint64_t mapped) {
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL, SIGXCPU}) std::signal(sig, SIG_DFL);
    limit(RLIMIT_CORE, 0, 0);
    const uint64_t room = uint64_t(limits.memory_mb) << 20;
    limit(RLIMIT_AS, mapped + room, mapped + room);
    limit(RLIMIT_CPU, limits.cpu_seconds, uint64_t(limits.cpu_seconds) + 1);
    out = keep_only(out);
    if (SANDBOX_FILTERS && !install_filter(out)) _exit(3);

    const ErrorSink sink(file);
    Imported<ImportOutcome> result = ImportOutcome{};
    try {
        result = work();
    } catch (const std::bad_alloc&) {
        result = sink.too_large("", "the importer needed more than its " +
                                        std::to_string(limits.memory_mb) + " MiB");
    } catch (...) {
        result = sink.invalid("", "the importer failed with an exception");
    }
    std::string bytes;
    try {
        bytes = encode_outcome(result);
    } catch (const std::bad_alloc&) {
        bytes = encode_outcome(sink.too_large(
            "", "the import's result needed more than " + std::to_string(limits.memory_mb) +
                    " MiB"));
    }
    _exit(write_all(out, bytes) ? 0 : 4);
}

// Step (server): read the result with a deadline, reap the child, say what stopped it.

enum class Stop : uint8_t { Done, Deadline, TooMuch, ReadError };

/// Reads the pipe until its end, the deadline or `cap` bytes.
Stop read_result(int fd, std::chrono::steady_clock::time_point deadline, std::size_t cap,
                 std::string& out) {
    std::vector<char> buffer(1 << 20);
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) return Stop::Deadline;
        pollfd p{fd, POLLIN, 0};
        const int ready = poll(&p, 1, int(std::min<int64_t>(left.count(), 1000)));
        if (ready < 0 && errno != EINTR) return Stop::ReadError;
        if (ready <= 0) continue;
        const ssize_t n = read(fd, buffer.data(), buffer.size());
        if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (n < 0) return Stop::ReadError;
        if (n == 0) return Stop::Done;
        if (out.size() + std::size_t(n) > cap) return Stop::TooMuch;
        out.append(buffer.data(), std::size_t(n));
    }
}

/// Waits for the child; kills it at the deadline if it has not ended by then.
int reap(pid_t pid, std::chrono::steady_clock::time_point deadline, Stop& stop) {
    int status = 0;
    for (;;) {
        const pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid) return status;
        if (w < 0 && errno != EINTR) return 0;
        if (std::chrono::steady_clock::now() >= deadline) {
            stop = Stop::Deadline;
            kill(pid, SIGKILL);
            while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
            }
            return status;
        }
        usleep(1000);
    }
}

std::string signal_name(int sig) {
    const char* abbrev = sigabbrev_np(sig);
    return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(sig);
}

/// Why the child ended without a result, for the problem's detail.
std::string death(Stop stop, int status, const SandboxLimits& limits) {
    if (stop == Stop::Deadline)
        return "the importer ran past its deadline of " + std::to_string(limits.deadline_ms) +
               " ms and was stopped";
    if (stop == Stop::TooMuch)
        return "the importer answered more than its " + std::to_string(limits.memory_mb) +
               " MiB and was stopped";
    if (WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        if (sig == SIGXCPU)
            return "the importer used more than its " + std::to_string(limits.cpu_seconds) +
                   " s of CPU time and was stopped";
        if (sig == SIGSYS)
            return "the importer made a system call its sandbox forbids and was stopped";
        if (sig == SIGKILL) return "the importer was killed (SIGKILL) before it finished";
        return "the importer crashed (" + signal_name(sig) + ") while reading it";
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 3)
        return "the importer's sandbox could not install its system call filter";
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
        return "the importer ended with status " + std::to_string(WEXITSTATUS(status));
    return "the importer ended without a result";
}

Unexpected<protocol::Problem> cannot_start(const std::string& what) {
    return Unexpected(protocol::make_problem(
        protocol::ProblemType::Internal,
        "the importer's sandbox could not start: " + what + ": " + std::strerror(errno)));
}

}  // namespace

Imported<ImportOutcome> run_sandboxed(const std::function<Imported<ImportOutcome>()>& work,
                                      const std::string& file, const SandboxLimits& limits) {
    if (!limits.enabled) return work();
    const ErrorSink sink(file);
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) return cannot_start("pipe");
    const uint64_t mapped = mapped_bytes();
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(limits.deadline_ms);
    const pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return cannot_start("fork");
    }
    if (pid == 0) {
        close(fds[0]);
        child(fds[1], work, file, limits, mapped);
    }
    close(fds[1]);
    if (limits.on_start) limits.on_start(pid);

    // The result cannot be larger than what the child could hold.
    std::string bytes;
    Stop stop = read_result(fds[0], deadline, (std::size_t(limits.memory_mb) << 20) + 4096, bytes);
    close(fds[0]);
    if (stop != Stop::Done) kill(pid, SIGKILL);
    const int status = reap(pid, deadline, stop);
    if (stop != Stop::Done || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return sink.invalid("", death(stop, status, limits) + "; nothing was imported");
    auto decoded = decode_outcome(bytes);
    if (!decoded)
        return sink.invalid("", "the importer's result is damaged (" + decoded.error() +
                                    "); nothing was imported");
    return std::move(decoded.value());
}

}  // namespace strata::assets
