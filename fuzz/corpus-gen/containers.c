/* Writes the starting corpus of the container readers with ibl's own encoders: KTX2, KTX1
 * and DDS, each of the six storage formats as a 2D texture with a partial mip chain (odd
 * size), a 3D texture with mips and a cube with mips, the block-compressed and 8-bit HDR
 * formats and Zstandard supercompression where the container stores them (a cube of 8 with
 * its chain to 1x1), plus a 1x1 texture and one carrying
 * metadata. Usage: containers OUT_DIR (writes OUT_DIR/{ktx2,ktx1,dds}/...). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ibl/ibl.h"

static const struct {
    ibl_format format;
    const char *name;
} formats[] = {
    {IBL_FORMAT_RGBA16F, "rgba16f"}, {IBL_FORMAT_RGBA32F, "rgba32f"}, {IBL_FORMAT_RG11B10F, "rg11b10f"},
    {IBL_FORMAT_RGB9E5, "rgb9e5"},   {IBL_FORMAT_RG16F, "rg16f"},     {IBL_FORMAT_RG32F, "rg32f"},
};

static const struct {
    ibl_file_type type;
    const char *dir, *ext;
} containers[] = {
    {IBL_FILE_KTX2, "ktx2", "ktx2"},
    {IBL_FILE_KTX1, "ktx1", "ktx"},
    {IBL_FILE_DDS, "dds", "dds"},
};

/* Smooth values over a wide range (tiny, ordinary and bright), alpha varying. */
static void fill(ibl_texture *t)
{
    size_t n = ibl_texture_floats(t->kind, t->width, t->height, t->depth, t->levels) / 4;
    for (size_t i = 0; i < n; i++) {
        float x = (float)i;
        t->data[i * 4 + 0] = 0.001f + 0.5f * (1.0f + sinf(x * 0.7f));
        t->data[i * 4 + 1] = 3.0f * (float)(i % 5);
        t->data[i * 4 + 2] = i % 11 == 0 ? 900.0f : 0.25f;
        t->data[i * 4 + 3] = (float)(i % 4) / 3.0f;
    }
}

static int emit_z(ibl_context *ctx, const char *out, int c, ibl_texture *t, ibl_format format,
                  int zstd, const char *stem)
{
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    wd.format = format;
    wd.zstd_level = zstd;
    void *bytes = NULL;
    size_t size = 0;
    if (ibl_encode_texture(ctx, containers[c].type, t, &wd, &bytes, &size) != IBL_OK) {
        fprintf(stderr, "%s: %s\n", stem, ibl_context_message(ctx));
        return 1;
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/%s/%s.%s", out, containers[c].dir, stem, containers[c].ext);
    FILE *f = fopen(path, "wb");
    int bad = !f || fwrite(bytes, 1, size, f) != size;
    if (f && fclose(f) != 0) bad = 1;
    ibl_free(ctx, bytes);
    if (bad) fprintf(stderr, "cannot write %s\n", path);
    return bad;
}

static int emit(ibl_context *ctx, const char *out, int c, ibl_texture *t, ibl_format format,
                const char *stem)
{
    return emit_z(ctx, out, c, t, format, 0, stem);
}

/* The block-compressed and 8-bit HDR formats, and Zstandard supercompression, where the
 * container stores them: a cube of 8 with its chain down to 1x1 (padded blocks). */
static int emit_compressed(ibl_context *ctx, const char *out, int c)
{
    static const struct {
        ibl_format format;
        int zstd;
        const char *name;
    } list[] = {
        {IBL_FORMAT_BC6H, 0, "bc6h"},         {IBL_FORMAT_BC6H_SIGNED, 0, "bc6h_signed"},
        {IBL_FORMAT_ASTC_4x4, 0, "astc4x4"},  {IBL_FORMAT_ASTC_6x5, 0, "astc6x5"},
        {IBL_FORMAT_RGBM, 0, "rgbm"},         {IBL_FORMAT_RGBD, 0, "rgbd"},
        {IBL_FORMAT_RGBE, 0, "rgbe"},         {IBL_FORMAT_BC6H, 3, "bc6h_zstd"},
        {IBL_FORMAT_RGBA16F, 3, "rgba16f_zstd"},
    };
    ibl_texture t;
    if (ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 8, 8, 1, 4, &t) != IBL_OK) return 1;
    fill(&t);
    int bad = 0;
    for (size_t i = 0; i < sizeof list / sizeof list[0]; i++) {
        if (!ibl_file_type_writes_format(containers[c].type, list[i].format) ||
            (list[i].zstd && containers[c].type != IBL_FILE_KTX2))
            continue;
        char stem[64];
        snprintf(stem, sizeof stem, "cube_%s", list[i].name);
        bad |= emit_z(ctx, out, c, &t, list[i].format, list[i].zstd, stem);
    }
    ibl_texture_free(ctx, &t);
    return bad;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: containers OUT_DIR\n");
        return 2;
    }
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) return 1;
    int bad = 0;
    static const struct {
        ibl_texture_kind kind;
        int w, h, d, levels;
        const char *name;
    } shapes[] = {
        {IBL_TEXTURE_2D, 5, 3, 1, 2, "2d"},
        {IBL_TEXTURE_3D, 4, 2, 3, 2, "3d"},
        {IBL_TEXTURE_CUBE, 4, 4, 1, 3, "cube"},
    };
    for (int c = 0; c < 3; c++) {
        for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
            ibl_texture t;
            if (ibl_texture_alloc(ctx, shapes[s].kind, shapes[s].w, shapes[s].h, shapes[s].d,
                                  shapes[s].levels, &t) != IBL_OK)
                return 1;
            fill(&t);
            for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
                char stem[64];
                snprintf(stem, sizeof stem, "%s_%s", shapes[s].name, formats[f].name);
                bad |= emit(ctx, argv[1], c, &t, formats[f].format, stem);
            }
            ibl_texture_free(ctx, &t);
        }
        ibl_texture t;
        if (ibl_texture_alloc(ctx, IBL_TEXTURE_2D, 1, 1, 1, 1, &t) != IBL_OK) return 1;
        fill(&t);
        bad |= emit(ctx, argv[1], c, &t, IBL_FORMAT_RGBA32F, "pixel_rgba32f");
        ibl_texture_free(ctx, &t);
        if (ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 2, 2, 1, 2, &t) != IBL_OK) return 1;
        fill(&t);
        ibl_texture_set_metadata(ctx, &t, "KTXorientation", "rd");
        ibl_texture_set_metadata(ctx, &t, "ibl.source", "corpus");
        bad |= emit(ctx, argv[1], c, &t, IBL_FORMAT_RGBA16F, "meta_cube_rgba16f");
        ibl_texture_free(ctx, &t);
        bad |= emit_compressed(ctx, argv[1], c);
        /* cube-map arrays (KTX2 layerCount, DDS arraySize): 2 cubes of 4 with 3 levels */
        if (ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE_ARRAY, 4, 4, 2, 3, &t) != IBL_OK) return 1;
        fill(&t);
        if (containers[c].type != IBL_FILE_KTX1) {
            bad |= emit(ctx, argv[1], c, &t, IBL_FORMAT_RGBA16F, "cube_array_rgba16f");
            bad |= emit(ctx, argv[1], c, &t, IBL_FORMAT_BC6H, "cube_array_bc6h");
        }
        ibl_texture_free(ctx, &t);
    }
    ibl_context_destroy(ctx);
    return bad;
}
