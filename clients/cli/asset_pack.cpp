#include "clients/cli/asset_pack.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace strata::cli {

namespace fs = std::filesystem;

namespace {

bool read_whole(const fs::path& path, std::string& out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return !in.bad();
}

std::string lower_extension(const fs::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::vector<std::string> tokens(const std::string& line) {
    std::istringstream in(line);
    std::vector<std::string> out;
    for (std::string t; in >> t;) out.push_back(t);
    return out;
}

/// `%XX` decoded (glTF URIs are URI references).
std::string percent_decode(const std::string& s) {
    std::string out;
    for (std::size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '%' && i + 2 < s.size() &&
            std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
            out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

/// Collects the side files a model names, as absolute, lexically normal paths.
class Collector {
public:
    explicit Collector(fs::path model) : m_model(std::move(model)) {}

    /// `reference`, named by `who` (for messages), resolved against each folder of `bases` in
    /// turn; the first that exists is kept. False (and `error`) when none does.
    bool add(const std::string& reference, const std::string& who,
             const std::vector<fs::path>& bases, std::string& error, fs::path* resolved = nullptr) {
        std::string r = reference;
        std::replace(r.begin(), r.end(), '\\', '/');
        if (r.empty()) return true;
        if (r.front() == '/' || (r.size() >= 2 && r[1] == ':')) {
            error = who + " names '" + reference +
                    "', an absolute path: the server looks side files up only inside the "
                    "upload; make the reference relative";
            return false;
        }
        std::string tried;
        for (const fs::path& base : bases) {
            const fs::path p = (base / r).lexically_normal();
            std::error_code ec;
            if (fs::is_regular_file(p, ec)) {
                // A model from elsewhere must not make the upload carry any file it likes
                // (../../.ssh/id_rsa): outside the model's folder, only the kinds of file a
                // model names are packed.
                const std::string ext = lower_extension(p);
                const fs::path rel = p.lexically_relative(m_model.parent_path());
                const bool inside = !rel.empty() && *rel.begin() != "..";
                if (!inside && ext != ".mtl" && ext != ".bin" && ext != ".png" && ext != ".jpg" &&
                    ext != ".jpeg") {
                    error = who + " names '" + reference + "' (" + p.string() +
                            "): outside the model's folder only .mtl, .bin, .png and .jpg files "
                            "are packed";
                    return false;
                }
                if (resolved) *resolved = p;
                if (std::find(m_files.begin(), m_files.end(), p) == m_files.end() && p != m_model)
                    m_files.push_back(p);
                return true;
            }
            tried += (tried.empty() ? "" : " or ") + p.string();
        }
        error = who + " names '" + reference + "', which is not a readable file (" + tried + ")";
        return false;
    }

    const std::vector<fs::path>& files() const { return m_files; }

private:
    fs::path m_model;
    std::vector<fs::path> m_files;
};

bool collect_obj(const fs::path& model, const std::string& text, Collector& c, std::string& error) {
    const fs::path dir = model.parent_path();
    std::istringstream in(text);
    std::vector<fs::path> mtls;
    for (std::string line; std::getline(in, line);) {
        auto t = tokens(line);
        if (t.size() < 2 || t[0] != "mtllib") continue;
        for (std::size_t i = 1; i < t.size(); ++i) {
            fs::path mtl;
            if (!c.add(t[i], model.filename().string() + " (mtllib)", {dir}, error, &mtl))
                return false;
            if (std::find(mtls.begin(), mtls.end(), mtl) == mtls.end()) mtls.push_back(mtl);
        }
    }
    for (const fs::path& mtl : mtls) {
        std::string mtl_text;
        if (!read_whole(mtl, mtl_text)) {
            error = "cannot read '" + mtl.string() + "'";
            return false;
        }
        std::istringstream lines(mtl_text);
        for (std::string line; std::getline(lines, line);) {
            auto t = tokens(line);
            // The importer binds map_Kd only; the file name is its last word (after options).
            if (t.size() < 2 || t[0] != "map_Kd") continue;
            if (!c.add(t.back(), mtl.filename().string() + " (map_Kd)", {mtl.parent_path(), dir},
                       error))
                return false;
        }
    }
    return true;
}

bool collect_gltf(const fs::path& model, const std::string& text, Collector& c,
                  std::string& error) {
    const nlohmann::json doc = nlohmann::json::parse(text, nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return true;  // the server names what is wrong
    for (const char* kind : {"buffers", "images"}) {
        const auto it = doc.find(kind);
        if (it == doc.end() || !it->is_array()) continue;
        for (std::size_t i = 0; i < it->size(); ++i) {
            const auto& item = (*it)[i];
            if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
            const std::string uri = item["uri"].get<std::string>();
            if (uri.rfind("data:", 0) == 0) continue;
            const std::string who =
                model.filename().string() + " (" + kind + "[" + std::to_string(i) + "])";
            if (!c.add(percent_decode(uri), who, {model.parent_path()}, error)) return false;
        }
    }
    return true;
}

/// The deepest folder that holds every path.
fs::path common_root(const std::vector<fs::path>& paths) {
    fs::path root = paths.front().parent_path();
    for (const fs::path& p : paths) {
        for (;;) {
            const fs::path rel = p.parent_path().lexically_relative(root);
            if (!rel.empty() && *rel.begin() != "..") break;
            if (root.parent_path() == root) break;
            root = root.parent_path();
        }
    }
    return root;
}

void put_octal(std::string& h, std::size_t offset, std::size_t width, uint64_t value) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%0*llo", int(width - 1),
                  static_cast<unsigned long long>(value));
    std::memcpy(h.data() + offset, buffer, width - 1);
}

std::string header(const std::string& name, const std::string& prefix, uint64_t size, char type,
                   bool gnu) {
    std::string h(512, '\0');
    std::memcpy(h.data(), name.data(), std::min<std::size_t>(name.size(), 100));
    put_octal(h, 100, 8, 0644);
    put_octal(h, 108, 8, 0);
    put_octal(h, 116, 8, 0);
    put_octal(h, 124, 12, size);
    put_octal(h, 136, 12, 0);
    h[156] = type;
    std::memcpy(h.data() + 257,
                gnu ? "ustar  "
                    : "ustar\0"
                      "00",
                8);
    if (!gnu) std::memcpy(h.data() + 345, prefix.data(), std::min<std::size_t>(prefix.size(), 155));
    std::memset(h.data() + 148, ' ', 8);
    unsigned sum = 0;
    for (char c : h) sum += static_cast<unsigned char>(c);
    std::snprintf(h.data() + 148, 8, "%06o", sum);
    h[155] = ' ';
    return h;
}

void pad(std::string& out) {
    out.resize((out.size() + 511) / 512 * 512, '\0');
}

}  // namespace

std::string write_tar(const std::vector<std::pair<std::string, std::string>>& files) {
    std::string out;
    for (const auto& [path, bytes] : files) {
        if (path.size() <= 100) {
            out += header(path, "", bytes.size(), '0', false);
        } else {
            // ustar's prefix/name split at a '/', else a GNU long-name entry before the header.
            const std::size_t slash = path.find('/', path.size() > 101 ? path.size() - 101 : 0);
            if (slash != std::string::npos && slash <= 155 && path.size() - slash - 1 <= 100 &&
                slash > 0) {
                out +=
                    header(path.substr(slash + 1), path.substr(0, slash), bytes.size(), '0', false);
            } else {
                out += header("././@LongLink", "", path.size() + 1, 'L', true);
                out += path;
                out += '\0';
                pad(out);
                out += header(path.substr(0, 100), "", bytes.size(), '0', true);
            }
        }
        out += bytes;
        pad(out);
    }
    out.append(1024, '\0');
    return out;
}

bool pack_asset(const std::string& file, PackedAsset& out, std::string& error) {
    const fs::path model = fs::absolute(fs::path(file)).lexically_normal();
    std::string bytes;
    if (!read_whole(model, bytes)) {
        error = "cannot open '" + file + "'";
        return false;
    }
    // Step 1: the files the model names (only .obj and .gltf name any).
    Collector c(model);
    const std::string ext = lower_extension(model);
    if (ext == ".obj" && !collect_obj(model, bytes, c, error)) return false;
    if (ext == ".gltf" && !collect_gltf(model, bytes, c, error)) return false;
    out = {};
    if (c.files().empty()) {
        out.bytes = std::move(bytes);
        out.model_path = model.filename().string();
        return true;
    }
    // Step 2: one archive, every file at its path under the deepest folder holding them all.
    std::vector<fs::path> all = {model};
    all.insert(all.end(), c.files().begin(), c.files().end());
    const fs::path root = common_root(all);
    std::vector<std::pair<std::string, std::string>> entries;
    for (const fs::path& p : all) {
        std::string data;
        if (p == model) {
            data = bytes;
        } else if (!read_whole(p, data)) {
            error = "cannot read '" + p.string() + "'";
            return false;
        }
        const std::string path = p.lexically_relative(root).generic_string();
        if (p == model)
            out.model_path = path;
        else
            out.side_files.push_back(path);
        entries.emplace_back(path, std::move(data));
    }
    out.bytes = write_tar(entries);
    out.archive = true;
    return true;
}

}  // namespace strata::cli
