#pragma once
// Tar archives for the archive tests: written by GNU tar itself from a scratch folder, or built
// header by header to make the malformed ones tar never writes.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace strata::assets::test {

/// A scratch folder, removed with its contents when the object goes.
class ScratchDir {
public:
    ScratchDir();
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::filesystem::path& path() const { return m_path; }
    /// Writes `bytes` to `relative`, creating its folders.
    void write(const std::string& relative, const std::string& bytes) const;

private:
    std::filesystem::path m_path;
};

/// What `tar <options> -cf - -C <dir> <members>` writes to stdout ("" when tar fails).
std::string run_tar(const std::filesystem::path& dir, const std::string& options,
                    const std::string& members);

/// One ustar header block with a correct checksum (unless the caller breaks it later).
std::string tar_header(const std::string& name, uint64_t size, char type = '0',
                       const std::string& link = "");
/// `data` padded with NULs to a whole number of 512-byte blocks.
std::string tar_padded(const std::string& data);
/// A regular file entry: header and padded data.
std::string tar_file(const std::string& name, const std::string& data);
/// The end-of-archive marker: two zero blocks.
std::string tar_end();
/// Rewrites the checksum of the header starting at `offset` after an edit.
void tar_fix_checksum(std::string& archive, std::size_t offset);

}  // namespace strata::assets::test
