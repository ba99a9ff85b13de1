#include "engine/image/exr.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>

#include <Iex.h>
#include <Imath/half.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIDManifest.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfThreading.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {

namespace {

/// zlib level of ZIP compression: 1 is about twice as fast as OpenEXR's default 4 and only a few
/// percent larger on rendered frames (tests/bench/NOTES.md).
constexpr int ZIP_LEVEL = 1;

/// Appends to (and seeks within) a byte string: OpenEXR seeks back to fill in its offset table.
class StringOStream final : public Imf::OStream {
public:
    explicit StringOStream(std::string& out) : Imf::OStream("<memory>"), m_out(out) {}

    void write(const char c[], int n) override {
        const std::size_t end = m_pos + std::size_t(n);
        if (end > m_out.size()) m_out.resize(end);
        std::memcpy(m_out.data() + m_pos, c, std::size_t(n));
        m_pos = end;
    }
    uint64_t tellp() override { return m_pos; }
    void seekp(uint64_t pos) override { m_pos = std::size_t(pos); }

private:
    std::string& m_out;
    std::size_t m_pos = 0;
};

/// Reads from a caller-owned buffer.
class MemoryIStream final : public Imf::IStream {
public:
    MemoryIStream(const uint8_t* data, std::size_t size)
        : Imf::IStream("<memory>"), m_data(data), m_size(size) {}

    bool read(char c[], int n) override {
        if (n < 0 || m_pos + std::size_t(n) > m_size)
            throw Iex::InputExc("unexpected end of EXR data");
        std::memcpy(c, m_data + m_pos, std::size_t(n));
        m_pos += std::size_t(n);
        return m_pos < m_size;
    }
    uint64_t tellg() override { return m_pos; }
    void seekg(uint64_t pos) override { m_pos = std::size_t(std::min<uint64_t>(pos, m_size)); }

private:
    const uint8_t* m_data;
    std::size_t m_size;
    std::size_t m_pos = 0;
};

Imf::PixelType imf_type(ExrPixel p) {
    switch (p) {
        case ExrPixel::Uint:
            return Imf::UINT;
        case ExrPixel::Half:
            return Imf::HALF;
        case ExrPixel::Float:
            return Imf::FLOAT;
    }
    return Imf::HALF;
}

Imf::Compression imf_compression(ExrCompression c) {
    switch (c) {
        case ExrCompression::None:
            return Imf::NO_COMPRESSION;
        case ExrCompression::Zip:
            return Imf::ZIP_COMPRESSION;
        case ExrCompression::Piz:
            return Imf::PIZ_COMPRESSION;
    }
    return Imf::ZIP_COMPRESSION;
}

/// Once per process: OpenEXR compresses line blocks on its own thread pool (the file's bytes do
/// not depend on the thread count).
void init_exr_threads() {
    static std::once_flag once;
    std::call_once(once, [] {
        const unsigned n = std::thread::hardware_concurrency();
        Imf::setGlobalThreadCount(int(std::clamp(n, 1u, 16u)));
    });
}

Imath::M44f imath_matrix(const glm::mat4& m) {
    Imath::M44f out;
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) out[i][j] = m[i][j];
    }
    return out;
}

void add_attributes(Imf::Header& header, const ExrAttributes& a) {
    if (a.world_to_camera) Imf::addWorldToCamera(header, imath_matrix(*a.world_to_camera));
    if (a.world_to_ndc) Imf::addWorldToNDC(header, imath_matrix(*a.world_to_ndc));
    if (a.ids.empty()) return;
    Imf::IDManifest manifest;
    for (const ExrIdTable& table : a.ids) {
        Imf::IDManifest::ChannelGroupManifest& group = manifest.add(table.channel);
        group.setComponent(table.component);
        group.setLifetime(Imf::IDManifest::LIFETIME_FRAME);
        group.setHashScheme(Imf::IDManifest::NOTHASHED);
        group.setEncodingScheme(Imf::IDManifest::ID_SCHEME);
        for (const auto& [id, text] : table.entries) group.insert(id, text);
    }
    Imf::addIDManifest(header, Imf::CompressedIDManifest(manifest));
}

/// `count` floats (every `stride`-th of `src`) as halves, rounded to nearest even.
std::vector<half> to_half(const float* src, std::size_t stride, std::size_t count) {
    std::vector<half> out(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1u << 15),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              out[i] = half(src[i * stride]);
                      });
    return out;
}

}  // namespace

const DecodedExrChannel* DecodedExr::find(const std::string& name) const {
    for (const DecodedExrChannel& c : channels) {
        if (c.name == name) return &c;
    }
    return nullptr;
}

Result<std::string> encode_exr(uint32_t width, uint32_t height,
                               const std::vector<ExrChannel>& channels, ExrCompression compression,
                               const ExrAttributes& attributes) {
    if (width == 0 || height == 0 || width > uint32_t(std::numeric_limits<int>::max()) ||
        height > uint32_t(std::numeric_limits<int>::max()))
        return failure(ErrorCode::InvalidArgument, "EXR needs a non-empty image");
    for (const ExrChannel& c : channels) {
        const bool has_data = c.type == ExrPixel::Uint ? c.u32 != nullptr : c.f32 != nullptr;
        if (!has_data || c.name.empty() || (c.stride == 0 && c.type != ExrPixel::Half))
            return failure(ErrorCode::InvalidArgument,
                           "EXR channel '" + c.name + "' has no name, no data or a bad stride");
    }
    std::string out;
    try {
        init_exr_threads();
        Imf::Header header(static_cast<int>(width), static_cast<int>(height));
        header.compression() = imf_compression(compression);
        header.zipCompressionLevel() = ZIP_LEVEL;
        add_attributes(header, attributes);
        Imf::FrameBuffer frame;
        // OpenEXR writes only from slices of the file's own type: half channels are converted
        // here first (in parallel), float and uint channels are read in place.
        std::vector<std::vector<half>> halves;
        halves.reserve(channels.size());
        for (const ExrChannel& c : channels) {
            header.channels().insert(c.name, Imf::Channel(imf_type(c.type)));
            const char* base = nullptr;
            std::size_t elem = 0, stride = c.stride;
            if (c.type == ExrPixel::Half) {
                // Zero strides are not supported on output: a constant is expanded too.
                halves.push_back(to_half(c.f32, c.stride, std::size_t(width) * height));
                base = reinterpret_cast<const char*>(halves.back().data());
                elem = sizeof(half);
                stride = 1;
            } else if (c.type == ExrPixel::Float) {
                base = reinterpret_cast<const char*>(c.f32);
                elem = sizeof(float);
            } else {
                base = reinterpret_cast<const char*>(c.u32);
                elem = sizeof(uint32_t);
            }
            frame.insert(c.name, Imf::Slice(imf_type(c.type), const_cast<char*>(base),
                                            elem * stride, elem * stride * width));
        }
        // Room for the uncompressed pixels, so the vector never grows by copying (pages that
        // compression leaves unused are never touched).
        std::size_t raw = 0;
        for (const ExrChannel& c : channels) raw += c.type == ExrPixel::Half ? 2 : 4;
        out.reserve(raw * width * height + 8 * std::size_t(height) + 65536);
        StringOStream stream(out);
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(frame);
        file.writePixels(int(height));
    } catch (const std::exception& e) {
        return failure(ErrorCode::Internal, std::string("OpenEXR failed to encode: ") + e.what());
    }
    return out;
}

Result<DecodedExr> decode_exr(const uint8_t* data, std::size_t size) {
    DecodedExr image;
    try {
        MemoryIStream stream(data, size);
        Imf::InputFile file(stream);
        const Imf::Header& header = file.header();
        const Imath::Box2i window = header.dataWindow();
        image.width = uint32_t(window.max.x - window.min.x + 1);
        image.height = uint32_t(window.max.y - window.min.y + 1);
        switch (header.compression()) {
            case Imf::NO_COMPRESSION:
                image.compression = ExrCompression::None;
                break;
            case Imf::ZIP_COMPRESSION:
                image.compression = ExrCompression::Zip;
                break;
            case Imf::PIZ_COMPRESSION:
                image.compression = ExrCompression::Piz;
                break;
            default:
                break;
        }
        const std::size_t n = std::size_t(image.width) * image.height;
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            DecodedExrChannel& c = image.channels.emplace_back();
            c.name = it.name();
            c.type = it.channel().type == Imf::UINT    ? ExrPixel::Uint
                     : it.channel().type == Imf::FLOAT ? ExrPixel::Float
                                                       : ExrPixel::Half;
        }
        Imf::FrameBuffer frame;
        for (DecodedExrChannel& c : image.channels) {
            if (c.type == ExrPixel::Uint) {
                c.u32.resize(n);
                frame.insert(c.name, Imf::Slice::Make(Imf::UINT, c.u32.data(), window));
            } else {
                c.f32.resize(n);
                frame.insert(c.name, Imf::Slice::Make(Imf::FLOAT, c.f32.data(), window));
            }
        }
        if (Imf::hasIDManifest(header)) {
            const Imf::IDManifest manifest(Imf::idManifest(header));
            for (std::size_t g = 0; g < manifest.size(); ++g) {
                const Imf::IDManifest::ChannelGroupManifest& group = manifest[g];
                ExrIdTable& table = image.ids.emplace_back();
                if (!group.getChannels().empty()) table.channel = *group.getChannels().begin();
                if (!group.getComponents().empty()) table.component = group.getComponents()[0];
                for (auto it = group.begin(); it != group.end(); ++it) {
                    if (it.id() > UINT32_MAX)
                        return failure(ErrorCode::InvalidArgument,
                                       "EXR ID manifest holds an id beyond 32 bits");
                    table.entries.emplace_back(uint32_t(it.id()),
                                               it.text().empty() ? std::string() : it.text()[0]);
                }
            }
        }
        file.setFrameBuffer(frame);
        file.readPixels(window.min.y, window.max.y);
    } catch (const std::exception& e) {
        return failure(ErrorCode::InvalidArgument, std::string("not a readable EXR: ") + e.what());
    }
    return image;
}

}  // namespace strata
