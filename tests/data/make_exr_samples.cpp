// Generates the small OpenEXR samples in tests/data (exr_*.exr) with the OpenEXR C++ library,
// from the analytic pattern that tests/test_io.c recomputes. Not part of the build; run once:
//   g++ -std=c++17 make_exr_samples.cpp $(pkg-config --cflags --libs OpenEXR) -o make && ./make
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfTiledRgbaFile.h>
#include <cmath>
#include <string>
#include <vector>

static const int W = 32, H = 24;

// Keep in step with exr_pattern() in tests/test_io.c.
static void pattern(int x, int y, float *rgb)
{
    rgb[0] = 0.5f + 0.25f * std::sin(x / 5.0f);
    rgb[1] = (y + 1) / 16.0f;
    rgb[2] = 0.1f + 0.05f * (float)((x + 2 * y) % 7);
}

static void scanline(const char *name, Imf::Compression c, Imf::PixelType type)
{
    Imf::Header h(W, H);
    h.compression() = c;
    for (const char *ch : {"R", "G", "B"}) h.channels().insert(ch, Imf::Channel(type));
    std::vector<float> px(W * H * 3);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) pattern(x, y, &px[(y * W + x) * 3]);
    std::vector<half> hx(px.begin(), px.end()); // the writer wants the file's pixel type
    Imf::OutputFile f(name, h);
    Imf::FrameBuffer fb;
    for (int c2 = 0; c2 < 3; c2++) {
        std::string n(1, "RGB"[c2]);
        if (type == Imf::HALF) fb.insert(n, Imf::Slice(Imf::HALF, (char *)&hx[c2], 6, 6 * W));
        else fb.insert(n, Imf::Slice(Imf::FLOAT, (char *)&px[c2], 12, 12 * W));
    }
    f.setFrameBuffer(fb);
    f.writePixels(H);
}

static std::vector<Imf::Rgba> rgba()
{
    std::vector<Imf::Rgba> px(W * H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float v[3];
            pattern(x, y, v);
            px[y * W + x] = Imf::Rgba(v[0], v[1], v[2], 1.0f);
        }
    return px;
}

int main()
{
    const struct {
        const char *name;
        Imf::Compression c;
    } comps[] = {{"exr_none.exr", Imf::NO_COMPRESSION}, {"exr_rle.exr", Imf::RLE_COMPRESSION},
                 {"exr_zips.exr", Imf::ZIPS_COMPRESSION}, {"exr_zip.exr", Imf::ZIP_COMPRESSION},
                 {"exr_piz.exr", Imf::PIZ_COMPRESSION}, {"exr_pxr24.exr", Imf::PXR24_COMPRESSION},
                 {"exr_b44.exr", Imf::B44_COMPRESSION}, {"exr_b44a.exr", Imf::B44A_COMPRESSION},
                 {"exr_dwaa.exr", Imf::DWAA_COMPRESSION}, {"exr_dwab.exr", Imf::DWAB_COMPRESSION}};
    for (const auto &c : comps) scanline(c.name, c.c, Imf::HALF);
    scanline("exr_pxr24_float.exr", Imf::PXR24_COMPRESSION, Imf::FLOAT);
    scanline("exr_dwaa_float.exr", Imf::DWAA_COMPRESSION, Imf::FLOAT);
    std::vector<Imf::Rgba> px = rgba();
    {   // tiled, mip-mapped: the reader returns level 0
        Imf::Header h(W, H);
        h.compression() = Imf::ZIP_COMPRESSION;
        Imf::TiledRgbaOutputFile f("exr_tiled_mip.exr", h, Imf::WRITE_RGB, 8, 8, Imf::MIPMAP_LEVELS,
                                   Imf::ROUND_DOWN);
        for (int l = 0; l < f.numLevels(); l++) {
            int lw = f.levelWidth(l), lh = f.levelHeight(l);
            std::vector<Imf::Rgba> lv(lw * lh);
            for (int y = 0; y < lh; y++)
                for (int x = 0; x < lw; x++) lv[y * lw + x] = px[(y << l) * W + (x << l)];
            f.setFrameBuffer(lv.data(), 1, lw);
            f.writeTiles(0, f.numXTiles(l) - 1, 0, f.numYTiles(l) - 1, l);
        }
    }
    {   // luminance / chroma (subsampled chroma, lossy by design)
        Imf::Header h(W, H);
        h.compression() = Imf::PIZ_COMPRESSION;
        Imf::RgbaOutputFile f("exr_yc.exr", h, Imf::WRITE_YC);
        f.setFrameBuffer(px.data(), 1, W);
        f.writePixels(H);
    }
    {   // a named layer only ("diffuse.R" ...)
        Imf::Header h(W, H);
        for (const char *ch : {"diffuse.R", "diffuse.G", "diffuse.B", "zdepth.Z"})
            h.channels().insert(ch, Imf::Channel(Imf::FLOAT));
        std::vector<float> v(W * H * 4);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                pattern(x, y, &v[(y * W + x) * 4]);
                v[(y * W + x) * 4 + 3] = 7.0f;
            }
        Imf::OutputFile f("exr_layer.exr", h);
        Imf::FrameBuffer fb;
        const char *names[4] = {"diffuse.R", "diffuse.G", "diffuse.B", "zdepth.Z"};
        for (int c = 0; c < 4; c++) fb.insert(names[c], Imf::Slice(Imf::FLOAT, (char *)&v[c], 16, 16 * W));
        f.setFrameBuffer(fb);
        f.writePixels(H);
    }
    return 0;
}
