#include "tests/assets/tar_test_util.h"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>

namespace strata::assets::test {

ScratchDir::ScratchDir() {
    std::random_device rd;
    m_path = std::filesystem::temp_directory_path() /
             ("strata-tar-" + std::to_string(rd()) + "-" + std::to_string(rd()));
    std::filesystem::create_directories(m_path);
}

ScratchDir::~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
}

void ScratchDir::write(const std::string& relative, const std::string& bytes) const {
    const std::filesystem::path p = m_path / relative;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string run_tar(const std::filesystem::path& dir, const std::string& options,
                    const std::string& members) {
    const std::string command =
        "tar " + options + " -cf - -C '" + dir.string() + "' " + members + " 2>/dev/null";
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return "";
    std::string out;
    char buffer[65536];
    std::size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
    return pclose(pipe) == 0 ? out : "";
}

std::string tar_header(const std::string& name, uint64_t size, char type, const std::string& link) {
    std::string h(512, '\0');
    std::memcpy(h.data(), name.data(), std::min<std::size_t>(name.size(), 100));
    std::snprintf(h.data() + 100, 8, "%07o", 0644);
    std::snprintf(h.data() + 108, 8, "%07o", 0);
    std::snprintf(h.data() + 116, 8, "%07o", 0);
    std::snprintf(h.data() + 124, 12, "%011llo", static_cast<unsigned long long>(size));
    std::snprintf(h.data() + 136, 12, "%011o", 0);
    h[156] = type;
    std::memcpy(h.data() + 157, link.data(), std::min<std::size_t>(link.size(), 100));
    std::memcpy(h.data() + 257, "ustar", 6);  // POSIX magic "ustar\0", version "00"
    h[263] = '0';
    h[264] = '0';
    tar_fix_checksum(h, 0);
    return h;
}

std::string tar_padded(const std::string& data) {
    std::string out = data;
    out.resize((data.size() + 511) / 512 * 512, '\0');
    return out;
}

std::string tar_file(const std::string& name, const std::string& data) {
    return tar_header(name, data.size()) + tar_padded(data);
}

std::string tar_end() {
    return std::string(1024, '\0');
}

void tar_fix_checksum(std::string& archive, std::size_t offset) {
    std::memset(archive.data() + offset + 148, ' ', 8);
    unsigned sum = 0;
    for (std::size_t i = 0; i < 512; ++i) sum += static_cast<unsigned char>(archive[offset + i]);
    std::snprintf(archive.data() + offset + 148, 8, "%06o", sum);
    archive[offset + 155] = ' ';
}

}  // namespace strata::assets::test
