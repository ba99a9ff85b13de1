#include "protocol/assets/archive_import.h"

#include <vector>

#include "protocol/assets/import.h"

namespace strata::assets {

namespace {

std::optional<AssetFormat> model_format(std::string_view path) {
    const std::size_t dot = path.rfind('.');
    const std::size_t slash = path.rfind('/');
    if (dot == std::string_view::npos || (slash != std::string_view::npos && dot < slash))
        return std::nullopt;
    return format_from_name(path.substr(dot + 1));
}

std::vector<std::string_view> split(std::string_view path) {
    std::vector<std::string_view> parts;
    while (!path.empty()) {
        const std::size_t slash = path.find('/');
        parts.push_back(path.substr(0, slash));
        path = slash == std::string_view::npos ? std::string_view() : path.substr(slash + 1);
    }
    return parts;
}

/// `path` relative to folder `folder` (both normal archive paths; "" is the archive's root).
std::string relative_to(std::string_view folder, std::string_view path) {
    const auto from = split(folder);
    const auto to = split(path);
    std::size_t common = 0;
    while (common < from.size() && common + 1 < to.size() && from[common] == to[common]) ++common;
    std::string out;
    for (std::size_t i = common; i < from.size(); ++i) out += "../";
    for (std::size_t i = common; i < to.size(); ++i) {
        out += to[i];
        if (i + 1 < to.size()) out += '/';
    }
    return out;
}

std::string quoted_list(const std::vector<const TarEntry*>& entries) {
    std::string out;
    for (std::size_t i = 0; i < entries.size() && i < 8; ++i)
        out += (i ? ", '" : "'") + printable_name(entries[i]->path) + "'";
    if (entries.size() > 8) out += " and " + std::to_string(entries.size() - 8) + " more";
    return out;
}

}  // namespace

Imported<ArchiveAsset> import_archive(std::span<const uint8_t> body, const std::string& archive,
                                      const ImportLimits& limits, const TarLimits& tar_limits) {
    const ErrorSink sink(archive);
    // Step 1: the archive's files.
    auto entries = read_tar(body, archive, tar_limits);
    if (!entries) return Unexpected(entries.error());

    // Step 2: exactly one model, by extension.
    std::vector<const TarEntry*> models;
    for (const TarEntry& e : entries.value())
        if (model_format(e.path)) models.push_back(&e);
    if (models.empty())
        return sink.invalid("", "the archive holds no model (a file with one of the extensions " +
                                    format_names() + ")" +
                                    std::string(entries.value().empty() ? ": it is empty" : ""));
    if (models.size() > 1)
        return sink.invalid("", "the archive holds " + std::to_string(models.size()) + " models (" +
                                    quoted_list(models) + "); upload one model per archive");
    const TarEntry& model = *models.front();

    // Step 3: the other files, by their path relative to the model's folder.
    const std::size_t slash = model.path.rfind('/');
    const std::string folder = slash == std::string::npos ? "" : model.path.substr(0, slash);
    SideFiles side;
    for (const TarEntry& e : entries.value())
        if (&e != &model)
            side.emplace(
                relative_to(folder, e.path),
                std::string(reinterpret_cast<const char*>(e.bytes.data()), e.bytes.size()));

    // Step 4: the import, its errors naming the archive and the model.
    ArchiveAsset out;
    out.format = *model_format(model.path);
    out.model = model.path;
    auto asset = import_asset(out.format, model.bytes, archive + ": " + printable_name(model.path),
                              limits, side);
    if (!asset) return Unexpected(asset.error());
    out.asset = std::move(asset.value());
    return out;
}

}  // namespace strata::assets
