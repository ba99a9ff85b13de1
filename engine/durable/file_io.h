#pragma once
// The few POSIX file operations durability needs, as Status values whose messages name the path
// and the errno text. Nothing here throws.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"

namespace strata::durable {

/// "path: strerror(errno)" for the current errno.
std::string errno_message(const std::string& what);

/// Writes all of `data` at the descriptor's position, retrying short writes; on failure the
/// message names `path` and the cause (ENOSPC, EFBIG, ...). `written` gets what did land.
Status write_all(int fd, std::string_view data, const std::string& path,
                 std::size_t* written = nullptr);

/// fdatasync, as a Status naming `path`.
Status sync_file(int fd, const std::string& path);

/// fsyncs a directory, so that file creations, renames and removals in it are durable.
Status sync_directory(const std::string& dir);

/// The whole file.
Result<std::string> read_whole_file(const std::string& path);

/// Names of the regular files in `dir`, sorted.
Result<std::vector<std::string>> list_files(const std::string& dir);

/// Writes `data` to `path` atomically: `path.tmp`, fsync, rename, fsync the directory.
Status write_file_atomically(const std::string& dir, const std::string& name,
                             std::string_view data);

/// `dir/name`.
std::string join_path(const std::string& dir, const std::string& name);

}  // namespace strata::durable
