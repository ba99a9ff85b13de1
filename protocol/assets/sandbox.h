#pragma once
// The importers run in a child process, so that a parser that crashes, hangs or is subverted by a
// hostile file costs a 422 naming the file, never the server. The child is forked from the
// server (it shares the upload's pages copy-on-write; nothing is written to disk), and before it
// reads a byte of the upload it:
//   - has no core dumps, an address-space limit (what the server had mapped plus `memory_mb`)
//     and a CPU-time limit (`cpu_seconds`);
//   - closes every file descriptor but its end of the result pipe and stderr (no sockets, no
//     journal, no listening port);
//   - installs a seccomp filter (libseccomp): opening or probing a path fails with EACCES, and
//     any system call beyond memory management, writing the pipe and stderr, fstat, futexes,
//     signals to itself and the clock kills it: no socket, no exec, no ptrace. Builds with a
//     sanitizer skip the filter (their runtimes make calls of their own).
// The server reads the result (asset_wire.h) with a wall-clock deadline (`deadline_ms`), then
// checks it again as untrusted input. What each death means for the answer is in sandbox.cpp.
//
// Cost: a fork copies the server's page tables (about 2 MB per GB resident), then the child
// runs the importer as the server would have.

#include <cstdint>
#include <functional>
#include <string>

#include <sys/types.h>

#include "protocol/assets/asset_wire.h"

namespace strata::assets {

/// Whether the child installs its seccomp filter and meets its memory limit as bad_alloc: not
/// in builds with a sanitizer, whose runtimes make system calls of their own and report
/// allocation failures themselves.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool SANDBOX_FILTERS = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
inline constexpr bool SANDBOX_FILTERS = false;
#else
inline constexpr bool SANDBOX_FILTERS = true;
#endif
#else
inline constexpr bool SANDBOX_FILTERS = true;
#endif

/// What the child may use.
struct SandboxLimits {
    bool enabled = true;             ///< false: run the importer in the calling process
    uint32_t memory_mb = 2048;       ///< address space beyond what the server has mapped
    uint32_t cpu_seconds = 60;       ///< CPU time (SIGXCPU, then SIGKILL a second later)
    uint32_t deadline_ms = 60000;    ///< wall-clock time until the child is killed
    /// Tests: called in the server with the child's pid as soon as it is forked.
    std::function<void(pid_t)> on_start = {};
};

/// Runs `work` (an importer over bytes already in memory) under `limits`; `file` names the
/// upload in problems. A result `work` returns comes back as it is; a child that dies (a signal,
/// the seccomp filter, the memory or CPU limit, the deadline) is a 422 invalid-asset naming
/// `file` and what stopped it; a result that does not decode is a 422 too. A sandbox that cannot
/// start (fork or pipe fails) is a 500.
Imported<ImportOutcome> run_sandboxed(const std::function<Imported<ImportOutcome>()>& work,
                                      const std::string& file, const SandboxLimits& limits);

}  // namespace strata::assets
