// Writes the starting corpus of the OpenEXR reader with OpenEXR's own C++ API: every
// compression, half/float/uint channels, grey, luminance/chroma, layers, scanline and tiled
// (one level, mipmaps, ripmaps), multi-part, data windows that differ from the display
// window, both line orders, and the attribute types the reader checks structurally.
// Usage: exr_variants OUT_DIR
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIntAttribute.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfPreviewImage.h>
#include <ImfRgbaFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringVectorAttribute.h>
#include <ImfTiledOutputFile.h>
#include <ImfTiledOutputPart.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace Imf;
using Imath::Box2i;
using Imath::V2i;

namespace {

std::string out_dir;

std::string path(const std::string &name) { return out_dir + "/" + name + ".exr"; }

// Planar samples for one channel over a window, smooth so that every codec compresses them.
struct Plane {
    PixelType type;
    std::vector<half> h;
    std::vector<float> f;
    std::vector<unsigned> u;
};

float value(int x, int y, int c) { return 0.05f + 0.5f * (1.0f + std::sin(0.3f * x + 0.2f * y + c)) * (c == 0 ? 40.0f : 1.0f); }

Plane make_plane(PixelType type, const Box2i &w, int c)
{
    Plane p;
    p.type = type;
    for (int y = w.min.y; y <= w.max.y; y++)
        for (int x = w.min.x; x <= w.max.x; x++) {
            float v = value(x, y, c);
            if (type == HALF) p.h.push_back(half(v));
            else if (type == FLOAT) p.f.push_back(v);
            else p.u.push_back(static_cast<unsigned>(v * 100.0f));
        }
    return p;
}

// A frame buffer over planes (one per channel name), for the window w.
FrameBuffer frame(const std::vector<std::string> &names, std::vector<Plane> &planes, const Box2i &w)
{
    FrameBuffer fb;
    const long width = w.max.x - w.min.x + 1;
    for (size_t i = 0; i < names.size(); i++) {
        Plane &p = planes[i];
        size_t bytes = p.type == HALF ? sizeof(half) : 4;
        char *base = p.type == HALF ? reinterpret_cast<char *>(p.h.data())
                     : p.type == FLOAT ? reinterpret_cast<char *>(p.f.data())
                                       : reinterpret_cast<char *>(p.u.data());
        base -= (static_cast<long>(w.min.x) + static_cast<long>(w.min.y) * width) * static_cast<long>(bytes);
        fb.insert(names[i], Slice(p.type, base, bytes, bytes * static_cast<size_t>(width)));
    }
    return fb;
}

void scanline(const std::string &name, Header h, const std::vector<std::string> &names,
              const std::vector<PixelType> &types)
{
    std::vector<Plane> planes;
    for (size_t i = 0; i < names.size(); i++) {
        h.channels().insert(names[i], Channel(types[i]));
        planes.push_back(make_plane(types[i], h.dataWindow(), static_cast<int>(i)));
    }
    OutputFile file(path(name).c_str(), h);
    file.setFrameBuffer(frame(names, planes, h.dataWindow()));
    file.writePixels(h.dataWindow().max.y - h.dataWindow().min.y + 1);
}

void tiled(const std::string &name, Header h, const TileDescription &td, const std::vector<std::string> &names,
           PixelType type)
{
    for (const std::string &n : names) h.channels().insert(n, Channel(type));
    h.setTileDescription(td);
    TiledOutputFile file(path(name).c_str(), h);
    for (int ly = 0; ly < file.numYLevels(); ly++)
        for (int lx = 0; lx < file.numXLevels(); lx++) {
            if (td.mode == MIPMAP_LEVELS && lx != ly) continue;
            Box2i w = file.dataWindowForLevel(lx, ly);
            std::vector<Plane> planes;
            for (size_t i = 0; i < names.size(); i++) planes.push_back(make_plane(type, w, static_cast<int>(i)));
            file.setFrameBuffer(frame(names, planes, w));
            file.writeTiles(0, file.numXTiles(lx) - 1, 0, file.numYTiles(ly) - 1, lx, ly);
        }
}

Header header(int w, int hgt, Compression c)
{
    Header h(w, hgt);
    h.compression() = c;
    return h;
}

const std::vector<std::string> RGBA = {"R", "G", "B", "A"}, RGB = {"R", "G", "B"};

} // namespace

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: exr_variants OUT_DIR\n");
        return 2;
    }
    out_dir = argv[1];
    const struct {
        Compression c;
        const char *name;
    } comps[] = {{NO_COMPRESSION, "none"}, {RLE_COMPRESSION, "rle"},   {ZIPS_COMPRESSION, "zips"},
                 {ZIP_COMPRESSION, "zip"},  {PIZ_COMPRESSION, "piz"},   {PXR24_COMPRESSION, "pxr24"},
                 {B44_COMPRESSION, "b44"},  {B44A_COMPRESSION, "b44a"}, {DWAA_COMPRESSION, "dwaa"},
                 {DWAB_COMPRESSION, "dwab"}};
    const std::vector<PixelType> half4(4, HALF), float3(3, FLOAT);
    // every compression, half RGBA, several chunks (40 lines)
    for (const auto &c : comps) scanline(std::string("comp_") + c.name, header(13, 40, c.c), RGBA, half4);
    // float and uint channels, through the fast path (ZIP, ZIPS, NONE) and OpenEXR's
    scanline("float_rgb_zip", header(9, 37, ZIP_COMPRESSION), RGB, float3);
    scanline("float_rgb_zips", header(9, 21, ZIPS_COMPRESSION), RGB, float3);
    scanline("float_rgb_none", header(6, 5, NO_COMPRESSION), RGB, float3);
    scanline("float_rgb_piz", header(9, 37, PIZ_COMPRESSION), RGB, float3);
    scanline("mixed_uint_alpha_zip", header(7, 19, ZIP_COMPRESSION), RGBA, {HALF, FLOAT, HALF, UINT});
    scanline("uint_rgb_rle", header(5, 6, RLE_COMPRESSION), RGB, {UINT, UINT, UINT});
    // grey, grey + alpha, layers, extra channels
    scanline("grey_y_zip", header(11, 20, ZIP_COMPRESSION), {"Y"}, {HALF});
    scanline("grey_ya_piz", header(11, 20, PIZ_COMPRESSION), {"A", "Y"}, {HALF, HALF});
    scanline("layer_diffuse_zip", header(8, 18, ZIP_COMPRESSION),
             {"diffuse.R", "diffuse.G", "diffuse.B", "depth.Z"}, {HALF, HALF, HALF, FLOAT});
    scanline("extra_channels_zips", header(6, 9, ZIPS_COMPRESSION), {"B", "G", "R", "Z", "mask"},
             {HALF, HALF, HALF, FLOAT, UINT});
    {
        // luminance / chroma with subsampled chroma, through RgbaOutputFile
        Header h = header(12, 10, PIZ_COMPRESSION);
        RgbaOutputFile file(path("luma_chroma_piz").c_str(), h, WRITE_YCA);
        std::vector<Rgba> px(12 * 10);
        for (int i = 0; i < 120; i++) px[i] = Rgba(value(i % 12, i / 12, 0), value(i % 12, i / 12, 1), 0.3f, 1.0f);
        file.setFrameBuffer(px.data(), 1, 12);
        file.writePixels(10);
    }
    // windows: data inside the display window, around it, and shifted to negative coordinates
    {
        Header h(Box2i(V2i(0, 0), V2i(15, 11)), Box2i(V2i(3, 2), V2i(9, 8)));
        h.compression() = ZIP_COMPRESSION;
        scanline("window_data_inside", h, RGBA, half4);
        Header g(Box2i(V2i(2, 2), V2i(6, 5)), Box2i(V2i(-3, -1), V2i(9, 8)));
        g.compression() = RLE_COMPRESSION;
        scanline("window_data_around", g, RGB, float3);
        Header k(Box2i(V2i(-4, -6), V2i(3, 5)), Box2i(V2i(-4, -6), V2i(3, 5)));
        k.compression() = PIZ_COMPRESSION;
        k.lineOrder() = DECREASING_Y;
        scanline("window_negative_decreasing", k, RGB, half4);
        Header d(Box2i(V2i(0, 0), V2i(7, 7)), Box2i(V2i(5, 6), V2i(12, 20)));
        d.compression() = ZIP_COMPRESSION;
        scanline("window_disjoint", d, RGB, float3);
    }
    // tiled: one level, mipmaps (both roundings), ripmaps, random tile order
    tiled("tiled_one_level_zip", header(20, 13, ZIP_COMPRESSION), TileDescription(8, 8, ONE_LEVEL), RGBA, HALF);
    tiled("tiled_mipmap_piz", header(17, 9, PIZ_COMPRESSION), TileDescription(4, 4, MIPMAP_LEVELS, ROUND_DOWN), RGB, HALF);
    tiled("tiled_mipmap_up_none", header(9, 9, NO_COMPRESSION), TileDescription(4, 2, MIPMAP_LEVELS, ROUND_UP), RGB, FLOAT);
    tiled("tiled_ripmap_rle", header(8, 6, RLE_COMPRESSION), TileDescription(4, 4, RIPMAP_LEVELS), RGB, HALF);
    tiled("tiled_dwaa", header(40, 33, DWAA_COMPRESSION), TileDescription(32, 16, ONE_LEVEL), RGB, HALF);
    tiled("tiled_b44", header(10, 10, B44_COMPRESSION), TileDescription(4, 4, ONE_LEVEL), RGBA, HALF);
    {
        Header h = header(12, 12, ZIPS_COMPRESSION);
        h.lineOrder() = RANDOM_Y;
        tiled("tiled_random_order_zips", h, TileDescription(5, 3, ONE_LEVEL), {"Y"}, HALF);
    }
    // attributes the reader checks by structure: preview, string vector, chromaticities, long names
    {
        Header h = header(8, 8, ZIP_COMPRESSION);
        PreviewRgba pv[4] = {{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}, {9, 9, 9, 9}};
        h.setPreviewImage(PreviewImage(2, 2, pv));
        StringVector sv = {"left", "", "right"};
        h.insert("multiView", StringVectorAttribute(sv));
        addChromaticities(h, Chromaticities());
        addOwner(h, "ibl corpus");
        h.insert("a_rather_long_attribute_name_beyond_31", IntAttribute(7));
        scanline("attributes_long_names", h, RGB, half4);
    }
    {
        // two parts: scanline, then tiled (the reader takes part 0)
        Header a = header(6, 20, ZIP_COMPRESSION), b = header(6, 20, PIZ_COMPRESSION);
        a.setName("beauty");
        a.setType(SCANLINEIMAGE);
        b.setName("tiles");
        b.setType(TILEDIMAGE);
        b.setTileDescription(TileDescription(4, 4, ONE_LEVEL));
        for (const std::string &n : RGB) {
            a.channels().insert(n, Channel(HALF));
            b.channels().insert(n, Channel(HALF));
        }
        std::vector<Header> headers = {a, b};
        MultiPartOutputFile file(path("multipart_scan_tiled").c_str(), headers.data(), 2);
        std::vector<Plane> pa, pb;
        for (int i = 0; i < 3; i++) {
            pa.push_back(make_plane(HALF, a.dataWindow(), i));
            pb.push_back(make_plane(HALF, b.dataWindow(), i + 1));
        }
        OutputPart p0(file, 0);
        p0.setFrameBuffer(frame(RGB, pa, a.dataWindow()));
        p0.writePixels(20);
        TiledOutputPart p1(file, 1);
        p1.setFrameBuffer(frame(RGB, pb, b.dataWindow()));
        p1.writeTiles(0, p1.numXTiles(0) - 1, 0, p1.numYTiles(0) - 1);
    }
    return 0;
}
