// The only C++ in the library: OpenEXR's C++ API behind the C functions of exr_bridge.h.
// Every entry point catches every exception and turns it into a status and a message.
#include "io/exr_bridge.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfRgbaFile.h>
#include <ImfVersion.h>
#include <Iex.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <set>
#include <string>
#include <vector>

#include "ibl/core.h"

namespace {

// An input stream over a caller-owned buffer.
class MemIStream : public Imf::IStream {
  public:
    MemIStream(const char *data, uint64_t size) : Imf::IStream("<memory>"), data_(data), size_(size) {}
    bool read(char c[], int n) override
    {
        if (n < 0 || pos_ > size_ || static_cast<uint64_t>(n) > size_ - pos_)
            throw Iex::InputExc("unexpected end of file");
        std::memcpy(c, data_ + pos_, static_cast<size_t>(n));
        pos_ += static_cast<uint64_t>(n);
        return pos_ < size_;
    }
    uint64_t tellg() override { return pos_; }
    void seekg(uint64_t pos) override { pos_ = pos; }

  private:
    const char *data_;
    uint64_t size_;
    uint64_t pos_ = 0;
};

// An output stream into a growing buffer (OpenEXR seeks back to fill the offset table).
class MemOStream : public Imf::OStream {
  public:
    MemOStream() : Imf::OStream("<memory>") {}
    void write(const char c[], int n) override
    {
        if (n <= 0) return;
        uint64_t end = pos_ + static_cast<uint64_t>(n);
        if (end > buf_.size()) buf_.resize(end);
        std::memcpy(buf_.data() + pos_, c, static_cast<size_t>(n));
        pos_ = end;
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = pos; }
    const std::vector<char> &bytes() const { return buf_; }

  private:
    std::vector<char> buf_;
    uint64_t pos_ = 0;
};

// Messages end up on one line of stderr: line breaks inside OpenEXR's become spaces.
void set_error(char *err, size_t err_size, const char *what)
{
    if (!err || !err_size) return;
    std::snprintf(err, err_size, "%s", what);
    for (char *c = err; *c; c++)
        if (*c == '\n' || *c == '\r') *c = ' ';
}

// Runs f, converting exceptions into a status.
template <typename F> int guarded(char *err, size_t err_size, F f)
{
    try {
        return f();
    } catch (const std::bad_alloc &) {
        set_error(err, err_size, "out of memory in OpenEXR");
        return IBL_ERR_OUT_OF_MEMORY;
    } catch (const std::exception &e) {
        set_error(err, err_size, e.what());
        return IBL_ERR_FORMAT;
    } catch (...) {
        set_error(err, err_size, "unknown OpenEXR failure");
        return IBL_ERR_FORMAT;
    }
}

bool has(const Imf::ChannelList &ch, const std::string &name) { return ch.findChannel(name) != nullptr; }

} // namespace

struct ibl__exr_reader {
    std::unique_ptr<MemIStream> stream;
    std::unique_ptr<Imf::InputFile> file;
    ibl__exr_header header;
};

// What ibl__exr_header says of a parsed header: windows, the channels read and their types.
// Returns 0 or a status with its message in err.
static int describe_header(const Imf::Header &h, ibl__exr_header &hd, char *err, size_t err_size)
{
    std::memset(&hd, 0, sizeof hd);
    const Imath::Box2i dw = h.dataWindow(), dsp = h.displayWindow();
    hd.data_min_x = dw.min.x;
    hd.data_min_y = dw.min.y;
    hd.data_max_x = dw.max.x;
    hd.data_max_y = dw.max.y;
    hd.display_min_x = dsp.min.x;
    hd.display_min_y = dsp.min.y;
    hd.display_max_x = dsp.max.x;
    hd.display_max_y = dsp.max.y;
    const Imf::ChannelList &ch = h.channels();
    std::string prefix;
    if (has(ch, "R") && has(ch, "G") && has(ch, "B")) {
        hd.layout = IBL__EXR_RGB;
    } else if (has(ch, "Y") && has(ch, "RY") && has(ch, "BY")) {
        hd.layout = IBL__EXR_LUMA_CHROMA;
    } else if (has(ch, "Y")) {
        hd.layout = IBL__EXR_GREY;
    } else {
        // No top-level colour: take the first layer (alphabetically) with R, G and B.
        std::set<std::string> layers;
        ch.layers(layers);
        for (const std::string &l : layers) {
            if (has(ch, l + ".R") && has(ch, l + ".G") && has(ch, l + ".B")) {
                prefix = l + ".";
                hd.layout = IBL__EXR_RGB;
                break;
            }
        }
        if (!hd.layout) {
            std::string names;
            int count = 0;
            for (Imf::ChannelList::ConstIterator it = ch.begin(); it != ch.end() && count < 6; ++it, ++count)
                names += std::string(count ? ", " : "") + it.name();
            std::string msg = "no R,G,B or Y channels (found: " + names + ")";
            set_error(err, err_size, msg.c_str());
            return IBL_ERR_UNSUPPORTED;
        }
        std::snprintf(hd.layer, sizeof hd.layer, "%s", prefix.substr(0, prefix.size() - 1).c_str());
    }
    hd.has_alpha = has(ch, prefix + "A") ? 1 : 0;
    hd.all_half = 1;
    const char *used_rgb[] = {"R", "G", "B", "A"};
    const char *used_y[] = {"Y", "RY", "BY", "A"};
    const char **used = hd.layout == IBL__EXR_RGB ? used_rgb : used_y;
    for (int i = 0; i < 4; i++) {
        const Imf::Channel *c = ch.findChannel(prefix + used[i]);
        if (!c) continue;
        if (c->type != Imf::HALF) hd.all_half = 0;
        if ((c->xSampling != 1 || c->ySampling != 1) && hd.layout != IBL__EXR_LUMA_CHROMA) {
            set_error(err, err_size, "subsampled colour channels are not supported");
            return IBL_ERR_UNSUPPORTED;
        }
    }
    return 0;
}

extern "C" int ibl__exr_open(const void *bytes, size_t size, ibl__exr_reader **out,
                             ibl__exr_header *header, char *err, size_t err_size)
{
    *out = nullptr;
    return guarded(err, err_size, [&]() -> int {
        std::unique_ptr<ibl__exr_reader> r(new ibl__exr_reader());
        r->stream.reset(new MemIStream(static_cast<const char *>(bytes), size));
        r->file.reset(new Imf::InputFile(*r->stream, 0));
        int rc = describe_header(r->file->header(), r->header, err, err_size);
        if (rc) return rc;
        *header = r->header;
        *out = r.release();
        return 0;
    });
}

extern "C" int ibl__exr_read_header(const void *bytes, size_t size, ibl__exr_header *header,
                                    char *err, size_t err_size)
{
    return guarded(err, err_size, [&]() -> int {
        MemIStream stream(static_cast<const char *>(bytes), size);
        // the magic number and version field (check_headers in exr.c vetted both)
        unsigned char head[8];
        stream.read(reinterpret_cast<char *>(head), 8);
        int version = static_cast<int>(static_cast<uint32_t>(head[4]) | static_cast<uint32_t>(head[5]) << 8 |
                                             static_cast<uint32_t>(head[6]) << 16 | static_cast<uint32_t>(head[7]) << 24);
        Imf::Header h;
        h.readFrom(stream, version); // a multi-part file's first header is part 0's
        if (!Imf::isMultiPart(version)) {
            // as InputFile does for a single-part file before it reads the offset table
            if (!Imf::isNonImage(version) && h.hasType())
                h.setType(Imf::isTiled(version) ? Imf::TILEDIMAGE : Imf::SCANLINEIMAGE);
            h.sanityCheck(Imf::isTiled(version));
        }
        ibl__exr_header hd;
        int rc = describe_header(h, hd, err, err_size);
        if (rc) return rc;
        *header = hd;
        return 0;
    });
}

// Reads rows [y0, y1] (data-window coordinates) of the RGB, grey or layer channels through
// `file` into rgba, which covers the whole data window.
static void read_rows(Imf::InputFile &file, const ibl__exr_header &hd, float *rgba, int y0, int y1)
{
    const Imath::Box2i dw(Imath::V2i(hd.data_min_x, hd.data_min_y), Imath::V2i(hd.data_max_x, hd.data_max_y));
    const size_t w = static_cast<size_t>(static_cast<int64_t>(hd.data_max_x) - hd.data_min_x + 1);
    std::string prefix = hd.layer[0] ? std::string(hd.layer) + "." : std::string();
    char *base = reinterpret_cast<char *>(rgba);
    const size_t xs = 4 * sizeof(float), ys = xs * w;
    Imf::FrameBuffer fb;
    if (hd.layout == IBL__EXR_RGB) {
        fb.insert(prefix + "R", Imf::Slice::Make(Imf::FLOAT, base, dw, xs, ys));
        fb.insert(prefix + "G", Imf::Slice::Make(Imf::FLOAT, base + 4, dw, xs, ys));
        fb.insert(prefix + "B", Imf::Slice::Make(Imf::FLOAT, base + 8, dw, xs, ys));
    } else {
        fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, base, dw, xs, ys));
    }
    // A missing alpha channel is filled with 1 (opaque).
    fb.insert(prefix + "A", Imf::Slice::Make(Imf::FLOAT, base + 12, dw, xs, ys, 1, 1, 1.0));
    file.setFrameBuffer(fb);
    file.readPixels(y0, y1);
    if (hd.layout == IBL__EXR_GREY) {
        float *p = rgba + static_cast<size_t>(static_cast<int64_t>(y0) - hd.data_min_y) * w * 4;
        for (size_t i = 0; i < static_cast<size_t>(y1 - y0 + 1) * w; i++) p[i * 4 + 1] = p[i * 4 + 2] = p[i * 4];
    }
}

extern "C" int ibl__exr_read(ibl__exr_reader *r, float *rgba, char *err, size_t err_size)
{
    return guarded(err, err_size, [&]() -> int {
        const ibl__exr_header &hd = r->header;
        const size_t w = static_cast<size_t>(static_cast<int64_t>(hd.data_max_x) - hd.data_min_x + 1);
        const size_t h = static_cast<size_t>(static_cast<int64_t>(hd.data_max_y) - hd.data_min_y + 1);
        if (hd.layout == IBL__EXR_LUMA_CHROMA) {
            // RgbaInputFile converts luminance/chroma to RGB (half precision, as stored).
            r->file.reset();
            r->stream->seekg(0);
            Imf::RgbaInputFile file(*r->stream, 0);
            std::vector<Imf::Rgba> buf(w * h);
            // base = &buf[0] - (min.x + min.y * w), formed on integers to stay defined.
            intptr_t base = reinterpret_cast<intptr_t>(buf.data()) -
                            (static_cast<intptr_t>(hd.data_min_x) + static_cast<intptr_t>(hd.data_min_y) * static_cast<intptr_t>(w)) *
                                static_cast<intptr_t>(sizeof(Imf::Rgba));
            file.setFrameBuffer(reinterpret_cast<Imf::Rgba *>(base), 1, w);
            file.readPixels(hd.data_min_y, hd.data_max_y);
            for (size_t i = 0; i < w * h; i++) {
                rgba[i * 4 + 0] = buf[i].r;
                rgba[i * 4 + 1] = buf[i].g;
                rgba[i * 4 + 2] = buf[i].b;
                rgba[i * 4 + 3] = hd.has_alpha ? static_cast<float>(buf[i].a) : 1.0f;
            }
            return 0;
        }
        read_rows(*r->file, hd, rgba, hd.data_min_y, hd.data_max_y);
        return 0;
    });
}

extern "C" int ibl__exr_read_rows(const void *bytes, size_t size, const ibl__exr_header *hd, float *rgba,
                                  int y0, int y1, char *err, size_t err_size)
{
    return guarded(err, err_size, [&]() -> int {
        // Its own stream and file: bands run on different threads, and every OpenEXR object
        // here is private to this call (the library's global state was set up by
        // ibl__exr_open, which ran first on the calling thread).
        MemIStream stream(static_cast<const char *>(bytes), size);
        Imf::InputFile file(stream, 0);
        read_rows(file, *hd, rgba, y0, y1);
        return 0;
    });
}

extern "C" void ibl__exr_close(ibl__exr_reader *r)
{
    try {
        delete r;
    } catch (...) {
    }
}

extern "C" int ibl__exr_write(const float *rgba, int width, int height, int channels, int half,
                              int compression, void *(*alloc)(void *user, size_t bytes),
                              void *alloc_user, void **out, size_t *out_size, char *err,
                              size_t err_size)
{
    *out = nullptr;
    *out_size = 0;
    return guarded(err, err_size, [&]() -> int {
        Imf::Header header(width, height);
        header.compression() = static_cast<Imf::Compression>(compression);
        static const char *names[4] = {"R", "G", "B", "A"};
        const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
        for (int c = 0; c < channels; c++) header.channels().insert(names[c], Imf::Channel(type));
        const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
        MemOStream os;
        {
            Imf::OutputFile file(os, header, 0);
            Imf::FrameBuffer fb;
            std::vector<::half> halves;
            if (half) {
                // Half tops out at 65504: clamp so that finite inputs never become infinite.
                halves.resize(n * static_cast<size_t>(channels));
                for (size_t i = 0; i < n; i++)
                    for (int c = 0; c < channels; c++) {
                        float v = rgba[i * 4 + static_cast<size_t>(c)];
                        v = v > 65504.0f ? 65504.0f : v < -65504.0f ? -65504.0f : v;
                        halves[i * static_cast<size_t>(channels) + static_cast<size_t>(c)] = ::half(v);
                    }
                const size_t xs = sizeof(::half) * static_cast<size_t>(channels);
                for (int c = 0; c < channels; c++)
                    fb.insert(names[c], Imf::Slice(Imf::HALF, reinterpret_cast<char *>(halves.data() + c), xs,
                                                   xs * static_cast<size_t>(width)));
            } else {
                const size_t xs = 4 * sizeof(float);
                char *base = const_cast<char *>(reinterpret_cast<const char *>(rgba));
                for (int c = 0; c < channels; c++)
                    fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + 4 * c, xs, xs * static_cast<size_t>(width)));
            }
            file.setFrameBuffer(fb);
            file.writePixels(height);
        }
        const std::vector<char> &b = os.bytes();
        void *dst = alloc(alloc_user, b.size());
        if (!dst) {
            set_error(err, err_size, "out of memory");
            return IBL_ERR_OUT_OF_MEMORY;
        }
        std::memcpy(dst, b.data(), b.size());
        *out = dst;
        *out_size = b.size();
        return 0;
    });
}
