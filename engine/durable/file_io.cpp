#include "engine/durable/file_io.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace strata::durable {

std::string errno_message(const std::string& what) {
    return what + ": " + std::strerror(errno);
}

std::string join_path(const std::string& dir, const std::string& name) {
    if (dir.empty() || dir.back() == '/') return dir + name;
    return dir + "/" + name;
}

Status write_all(int fd, std::string_view data, const std::string& path, std::size_t* written) {
    std::size_t done = 0;
    while (done < data.size()) {
        const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            if (n == 0) errno = EIO;
            if (written) *written = done;
            return failure(ErrorCode::Storage, errno_message("cannot write " + path));
        }
        done += std::size_t(n);
    }
    if (written) *written = done;
    return {};
}

Status sync_file(int fd, const std::string& path) {
    if (::fdatasync(fd) != 0) return failure(ErrorCode::Storage, errno_message("fsync " + path));
    return {};
}

Status sync_directory(const std::string& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return failure(ErrorCode::Storage, errno_message("cannot open directory " + dir));
    const int rc = ::fsync(fd);
    const int err = errno;
    ::close(fd);
    errno = err;
    if (rc != 0) return failure(ErrorCode::Storage, errno_message("fsync directory " + dir));
    return {};
}

Result<std::string> read_whole_file(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return failure(ErrorCode::Storage, errno_message("cannot open " + path));
    std::string out;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && st.st_size > 0) out.reserve(std::size_t(st.st_size));
    char buffer[1 << 16];
    for (;;) {
        const ssize_t n = ::read(fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            const int err = errno;
            ::close(fd);
            errno = err;
            return failure(ErrorCode::Storage, errno_message("cannot read " + path));
        }
        if (n == 0) break;
        out.append(buffer, std::size_t(n));
    }
    ::close(fd);
    return out;
}

Result<std::vector<std::string>> list_files(const std::string& dir) {
    DIR* d = ::opendir(dir.c_str());
    if (!d) return failure(ErrorCode::Storage, errno_message("cannot list " + dir));
    std::vector<std::string> names;
    while (const dirent* e = ::readdir(d)) {
        const std::string name = e->d_name;
        if (name == "." || name == "..") continue;
        struct stat st {};
        if (::stat(join_path(dir, name).c_str(), &st) == 0 && S_ISREG(st.st_mode))
            names.push_back(name);
    }
    ::closedir(d);
    std::sort(names.begin(), names.end());
    return names;
}

Status write_file_atomically(const std::string& dir, const std::string& name,
                             std::string_view data) {
    const std::string path = join_path(dir, name);
    const std::string tmp = path + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return failure(ErrorCode::Storage, errno_message("cannot create " + tmp));
    Status s = write_all(fd, data, tmp);
    if (s) s = sync_file(fd, tmp);
    ::close(fd);
    if (s && ::rename(tmp.c_str(), path.c_str()) != 0)
        s = failure(ErrorCode::Storage, errno_message("cannot rename " + tmp + " to " + path));
    if (!s) {
        ::unlink(tmp.c_str());
        return s;
    }
    return sync_directory(dir);
}

}  // namespace strata::durable
