/* KTX2, KTX1 and DDS: round trips of every format x texture kind x mip chain, byte-level
 * checks against values worked out by hand from the specifications, and malformed inputs.
 * Goes through the internal encoders/decoders (io/io_internal.h) directly, and once through
 * the public file API (ibl_write_texture / ibl_read_texture). */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/pixel_format.h"
#include "io/io_internal.h"

typedef ibl_status (*encode_fn)(ibl_context *, const ibl_texture *, const ibl_write_desc *,
                                const char *, void **, size_t *);
typedef ibl_status (*decode_fn)(ibl_context *, const uint8_t *, size_t, const char *,
                                ibl_texture *, ibl_file_info *);

typedef struct container {
    const char *name; /* also the "file name" given to the codec */
    encode_fn encode;
    decode_fn decode;
    ibl_file_type type;
    int keeps_metadata;
} container;

static const container CONTAINERS[] = {
    {"test.ktx2", ibl__ktx2_encode, ibl__ktx2_decode, IBL_FILE_KTX2, 1},
    {"test.ktx", ibl__ktx1_encode, ibl__ktx1_decode, IBL_FILE_KTX1, 1},
    {"test.dds", ibl__dds_encode, ibl__dds_decode, IBL_FILE_DDS, 0},
};

static const ibl_format FORMATS[] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RGBA32F, IBL_FORMAT_RG11B10F,
                                     IBL_FORMAT_RGB9E5,  IBL_FORMAT_RG16F,   IBL_FORMAT_RG32F};

static uint32_t rng = 12345;
static uint32_t rnd(void)
{
    rng = rng * 1664525u + 1013904223u;
    return rng >> 8;
}

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t rd64(const uint8_t *p)
{
    return (uint64_t)rd32(p) | ((uint64_t)rd32(p + 4) << 32);
}
static void wr32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static void wr64(uint8_t *p, uint64_t v)
{
    wr32(p, (uint32_t)v);
    wr32(p + 4, (uint32_t)(v >> 32));
}

static int is_float_format(ibl_format f)
{
    return f == IBL_FORMAT_RGBA16F || f == IBL_FORMAT_RGBA32F || f == IBL_FORMAT_RG16F ||
           f == IBL_FORMAT_RG32F;
}

/* Random texels the format can hold exactly (16F: values that are halves; 32F: any finite
 * float incl. negatives and denormals) or, for the packed formats, positive HDR values. */
static void fill_random(ibl_texture *t, ibl_format f)
{
    size_t n = ibl_texture_floats(t->kind, t->width, t->height, t->depth, t->levels);
    for (size_t i = 0; i < n; i++) {
        float v;
        if (f == IBL_FORMAT_RGBA16F || f == IBL_FORMAT_RG16F) {
            uint16_t h = (uint16_t)rnd();
            if ((h & 0x7c00) == 0x7c00) h &= 0xbfff; /* keep it finite */
            v = ibl_half_to_float(h);
        } else if (f == IBL_FORMAT_RGBA32F || f == IBL_FORMAT_RG32F) {
            uint32_t b = (rnd() << 8) ^ rnd();
            if ((b & 0x7f800000u) == 0x7f800000u) b &= 0xbfffffffu;
            memcpy(&v, &b, 4);
        } else {
            v = ldexpf(1.0f + (float)(rnd() & 0xffff) / 65536.0f, (int)(rnd() % 30) - 18);
        }
        t->data[i] = v;
    }
}

static ibl_texture make_texture(ibl_context *ctx, ibl_texture_kind kind, int levels_full, ibl_format f)
{
    int w = kind == IBL_TEXTURE_CUBE ? 8 : kind == IBL_TEXTURE_3D ? 6 : 7;
    int h = kind == IBL_TEXTURE_CUBE ? 8 : kind == IBL_TEXTURE_3D ? 4 : 5;
    int d = kind == IBL_TEXTURE_3D ? 3 : 1;
    int levels = levels_full ? ibl_full_mip_count(w > h ? w : h) : 1;
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, kind, w, h, d, levels, &t), IBL_OK);
    fill_random(&t, f);
    t.format = f;
    return t;
}

static void add_metadata(ibl_context *ctx, ibl_texture *t)
{
    assert_int_equal(ibl_texture_set_metadata(ctx, t, "zeta", "\xc3\xbc"), IBL_OK); /* "ü" */
    assert_int_equal(ibl_texture_set_metadata(ctx, t, "ibl.sh_order", "3"), IBL_OK);
    assert_int_equal(ibl_texture_set_metadata(ctx, t, "a", "b"), IBL_OK);
}

static void assert_message_named(ibl_context *ctx, const char *name)
{
    const char *m = ibl_context_message(ctx);
    if (strncmp(m, name, strlen(name)) != 0 || m[strlen(name)] != ':')
        fail_msg("message \"%s\" does not start with \"%s:\"", m, name);
}

/* ---- round trips ---- */

static void round_trip_all(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static const ibl_texture_kind kinds[] = {IBL_TEXTURE_2D, IBL_TEXTURE_3D, IBL_TEXTURE_CUBE};
    for (size_t c = 0; c < sizeof CONTAINERS / sizeof CONTAINERS[0]; c++) {
        const container *ct = &CONTAINERS[c];
        for (size_t fi = 0; fi < sizeof FORMATS / sizeof FORMATS[0]; fi++) {
            ibl_format f = FORMATS[fi];
            for (int k = 0; k < 3; k++) {
                for (int full = 0; full < 2; full++) {
                    ibl_texture src = make_texture(ctx, kinds[k], full, f);
                    src.format = IBL_FORMAT_DEFAULT; /* the desc decides */
                    add_metadata(ctx, &src);
                    ibl_write_desc desc = {.format = f};
                    void *bytes = NULL;
                    size_t size = 0;
                    ibl_status st = ct->encode(ctx, &src, &desc, ct->name, &bytes, &size);
                    if (st != IBL_OK) fail_msg("%s encode: %s", ct->name, ibl_context_message(ctx));
                    ibl_texture out;
                    ibl_file_info info;
                    st = ct->decode(ctx, bytes, size, ct->name, &out, &info);
                    if (st != IBL_OK) fail_msg("%s decode: %s", ct->name, ibl_context_message(ctx));
                    assert_int_equal(out.kind, src.kind);
                    assert_int_equal(out.width, src.width);
                    assert_int_equal(out.height, src.height);
                    assert_int_equal(out.depth, src.depth);
                    assert_int_equal(out.levels, src.levels);
                    assert_int_equal(out.format, f);
                    assert_int_equal(info.type, ct->type);
                    assert_int_equal(info.format, f);
                    assert_int_equal(info.kind, src.kind);
                    assert_int_equal(info.levels, src.levels);
                    assert_int_equal(info.has_alpha, ibl_format_channels(f) == 4);
                    if (ct->keeps_metadata) {
                        assert_string_equal(ibl_texture_get_metadata(&out, "zeta"), "\xc3\xbc");
                        assert_string_equal(ibl_texture_get_metadata(&out, "ibl.sh_order"), "3");
                        assert_string_equal(ibl_texture_get_metadata(&out, "a"), "b");
                        assert_non_null(ibl_texture_get_metadata(&out, "KTXorientation"));
                    } else {
                        assert_int_equal(out.metadata_count, 0);
                    }
                    /* Texels: the container must not change a single bit of the stored
                     * encoding, so the result equals pack+unpack of the source exactly; for
                     * the float formats that is the source itself (bit-exact). */
                    size_t n = ibl_texture_floats(src.kind, src.width, src.height, src.depth,
                                                  src.levels) / 4;
                    int ch = ibl_format_channels(f);
                    for (size_t i = 0; i < n; i++) {
                        uint8_t enc[16];
                        float want[4];
                        ibl_pack_texels(f, src.data + i * 4, 1, enc);
                        ibl_unpack_texels(f, enc, 1, want);
                        for (int q = 0; q < 4; q++) {
                            float got = out.data[i * 4 + q];
                            if (fbits(got) != fbits(want[q]))
                                fail_msg("%s %s kind %d full %d texel %zu channel %d: %a, want %a",
                                         ct->name, ibl_format_name(f), k, full, i, q, (double)got,
                                         (double)want[q]);
                            if (q < ch && is_float_format(f))
                                assert_int_equal(fbits(got), fbits(src.data[i * 4 + q]));
                            if (q >= ch) assert_true(got == (q == 3 ? 1.0f : 0.0f));
                        }
                        if (f == IBL_FORMAT_RG11B10F) /* half an ulp: 2^-7 (G, R), 2^-6 (B) */
                            for (int q = 0; q < 3; q++)       /* relative; 2^-20 below 2^-14 */
                                assert_true(fabsf(out.data[i * 4 + q] - src.data[i * 4 + q]) <=
                                            fmaxf(src.data[i * 4 + q] * 0x1p-6f, 0x1p-20f));
                        if (f == IBL_FORMAT_RGB9E5) { /* 2^-9 of the largest channel (+ bump) */
                            float m = fmaxf(src.data[i * 4], fmaxf(src.data[i * 4 + 1], src.data[i * 4 + 2]));
                            for (int q = 0; q < 3; q++)
                                assert_true(fabsf(out.data[i * 4 + q] - src.data[i * 4 + q]) <=
                                            fmaxf(m * 0x1p-9f * 1.001f, 0x1p-25f));
                        }
                    }
                    ibl_free(ctx, bytes);
                    ibl_texture_free(ctx, &out);
                    ibl_texture_free(ctx, &src);
                }
            }
        }
    }
    ibl_context_destroy(ctx);
}

/* ---- KTX2 bytes, worked out by hand from the KTX 2.0 and Data Format specifications ---- */

static ibl_texture cube8(ibl_context *ctx, ibl_format f)
{
    /* 8x8 cube, full chain (4 levels); texel value encodes (level, face) for order checks */
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 8, 8, 1, 4, &t), IBL_OK);
    for (int l = 0; l < 4; l++)
        for (int face = 0; face < 6; face++) {
            float *p = ibl_texture_level(&t, l, face);
            int s = 8 >> l;
            for (int i = 0; i < s * s; i++) {
                p[i * 4 + 0] = (float)(l + 1);
                p[i * 4 + 1] = (float)(face + 1);
                p[i * 4 + 2] = 0.5f;
                p[i * 4 + 3] = 1.0f;
            }
        }
    t.format = f;
    add_metadata(ctx, &t);
    return t;
}

static void check_dfd_sample(const uint8_t *s, uint32_t offset, uint32_t length, uint32_t type,
                             uint32_t lower, uint32_t upper)
{
    /* bitOffset 16 bits, bitLength - 1 in 8 bits, channelType (id | F S E L) in 8 bits */
    assert_int_equal(rd32(s), offset | ((length - 1) << 16) | (type << 24));
    assert_int_equal(rd32(s + 4), 0); /* samplePosition0..3 */
    assert_int_equal(rd32(s + 8), lower);
    assert_int_equal(rd32(s + 12), upper);
}

static void ktx2_bytes_by_hand(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = cube8(ctx, IBL_FORMAT_RGBA16F);
    void *vb;
    size_t size;
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    const uint8_t *b = vb;
    static const uint8_t ident[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    assert_memory_equal(b, ident, 12);
    assert_int_equal(rd32(b + 12), 97); /* VK_FORMAT_R16G16B16A16_SFLOAT */
    assert_int_equal(rd32(b + 16), 2);  /* typeSize: 16-bit components */
    assert_int_equal(rd32(b + 20), 8);
    assert_int_equal(rd32(b + 24), 8);
    assert_int_equal(rd32(b + 28), 0);  /* pixelDepth 0 for cubes */
    assert_int_equal(rd32(b + 32), 0);  /* layerCount */
    assert_int_equal(rd32(b + 36), 6);  /* faceCount */
    assert_int_equal(rd32(b + 40), 4);  /* levelCount */
    assert_int_equal(rd32(b + 44), 0);  /* supercompressionScheme */
    /* DFD right after the 80-byte header and 4 x 24-byte level index: 176. One basic block of
     * 24 bytes + 4 samples x 16 = 88, plus the 4-byte dfdTotalSize: 92. */
    assert_int_equal(rd32(b + 48), 176);
    assert_int_equal(rd32(b + 52), 92);
    assert_int_equal(rd32(b + 56), 176 + 92);
    /* KVD: KTXorientation\0rd\0 (18 -> 4+20), KTXwriter\0ibl x.y.z\0, a\0b\0 (4 -> 4+4),
     * ibl.sh_order\03\0 (15 -> 4+16), zeta\0ü\0 (8 -> 4+8), sorted by code point ('K' < 'a'). */
    size_t writer = strlen("KTXwriter") + 1 + strlen("ibl " IBL_VERSION_STRING) + 1;
    uint32_t kvd_len = 24 + (uint32_t)(4 + ((writer + 3) & ~3u)) + 8 + 20 + 12;
    assert_int_equal(rd32(b + 60), kvd_len);
    assert_int_equal(rd64(b + 64), 0);
    assert_int_equal(rd64(b + 72), 0);
    const uint8_t *d = b + 176;
    assert_int_equal(rd32(d), 92);              /* dfdTotalSize */
    assert_int_equal(rd32(d + 4), 0);           /* vendorId 0 Khronos, descriptorType 0 basic */
    assert_int_equal(rd32(d + 8), 2u | (88u << 16)); /* version 2 (1.3), blockSize 88 */
    assert_int_equal(rd32(d + 12), 0x00010101); /* RGBSDA, BT709, LINEAR, flags 0 (straight) */
    assert_int_equal(rd32(d + 16), 0);          /* texelBlockDimension 0 = 1x1x1x1 */
    assert_int_equal(rd32(d + 20), 8);          /* bytesPlane0 = 8 */
    assert_int_equal(rd32(d + 24), 0);
    /* samples R G B A: 16 bits at 0/16/32/48, FLOAT (0x80) | SIGNED (0x40), -1.0f .. 1.0f */
    check_dfd_sample(d + 28, 0, 16, 0xC0, 0xBF800000u, 0x3F800000u);
    check_dfd_sample(d + 44, 16, 16, 0xC1, 0xBF800000u, 0x3F800000u);
    check_dfd_sample(d + 60, 32, 16, 0xC2, 0xBF800000u, 0x3F800000u);
    check_dfd_sample(d + 76, 48, 16, 0xCF, 0xBF800000u, 0x3F800000u); /* alpha id 15 */
    const uint8_t *kv = b + 268;
    assert_int_equal(rd32(kv), 18);
    assert_memory_equal(kv + 4, "KTXorientation\0rd\0\0\0", 20);
    assert_int_equal(rd32(kv + 24), (uint32_t)writer);
    assert_memory_equal(kv + 28, "KTXwriter\0ibl ", 14);
    const uint8_t *kv3 = kv + 24 + 4 + ((writer + 3) & ~3u);
    assert_int_equal(rd32(kv3), 4);
    assert_memory_equal(kv3 + 4, "a\0b\0", 4);
    assert_int_equal(rd32(kv3 + 8), 15);
    assert_memory_equal(kv3 + 12, "ibl.sh_order\0" "3\0\0", 16);
    assert_int_equal(rd32(kv3 + 28), 8);
    assert_memory_equal(kv3 + 32, "zeta\0\xc3\xbc\0", 8);
    /* Levels: smallest first, each aligned to lcm(8, 4) = 8 from the start of the file.
     * level 3: 1x1 x 6 faces x 8 B = 48; level 2: 192; level 1: 768; level 0: 3072. */
    uint64_t at = ((uint64_t)268 + kvd_len + 7) / 8 * 8;
    uint64_t lens[4] = {3072, 768, 192, 48}, offs[4];
    for (int l = 3; l >= 0; l--) {
        at = (at + 7) / 8 * 8;
        offs[l] = at;
        at += lens[l];
    }
    assert_int_equal(size, at);
    for (int l = 0; l < 4; l++) {
        const uint8_t *e = b + 80 + 24 * l;
        assert_int_equal(rd64(e), offs[l]);
        assert_int_equal(rd64(e + 8), lens[l]);
        assert_int_equal(rd64(e + 16), lens[l]);
        assert_true(offs[l] % 8 == 0);
        if (l > 0) assert_true(offs[l] < offs[l - 1]); /* smaller levels come first */
        /* the first texel of the level: R = level + 1 as a half, G = face 0 + 1 */
        uint16_t r = (uint16_t)(b[offs[l]] | (b[offs[l] + 1] << 8));
        assert_true(ibl_half_to_float(r) == (float)(l + 1));
        /* face 5's first texel sits 5/6 of the way into the level */
        const uint8_t *f5 = b + offs[l] + lens[l] / 6 * 5;
        assert_true(ibl_half_to_float((uint16_t)(f5[2] | (f5[3] << 8))) == 6.0f);
    }
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* RGBA32F: texel block 16 -> alignment lcm(16, 4) = 16 */
    t = cube8(ctx, IBL_FORMAT_RGBA32F);
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    b = vb;
    assert_int_equal(rd32(b + 12), 109);
    assert_int_equal(rd32(b + 16), 4);
    for (int l = 0; l < 4; l++) assert_true(rd64(b + 80 + 24 * l) % 16 == 0);
    assert_int_equal(rd64(b + 80 + 24 * 3), (268 + kvd_len + 15) / 16 * 16);
    check_dfd_sample(b + 176 + 28 + 48, 96, 32, 0xCF, 0xBF800000u, 0x3F800000u);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* E5B9G9R9: 6 samples (mantissa, exponent per channel) as in the Data Format spec's
     * shared-exponent example; DFD 4 + 24 + 96 = 124 bytes. */
    t = cube8(ctx, IBL_FORMAT_RGB9E5);
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    b = vb;
    assert_int_equal(rd32(b + 12), 123);
    assert_int_equal(rd32(b + 16), 4); /* _PACK32: 32 / 8 */
    assert_int_equal(rd32(b + 52), 124);
    d = b + 176;
    assert_int_equal(rd32(d + 8), 2u | (120u << 16));
    assert_int_equal(rd32(d + 20), 4);
    for (int c = 0; c < 3; c++) {
        check_dfd_sample(d + 28 + 32 * c, 9 * (uint32_t)c, 9, (uint32_t)c, 0, 8448);
        check_dfd_sample(d + 44 + 32 * c, 27, 5, (uint32_t)c | 0x20, 15, 31); /* EXPONENT */
    }
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* B10G11R11: R 11 bits at 0, G 11 at 11, B 10 at 22; FLOAT without SIGNED, 0.0 .. 1.0 */
    t = cube8(ctx, IBL_FORMAT_RG11B10F);
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    b = vb;
    assert_int_equal(rd32(b + 12), 122);
    assert_int_equal(rd32(b + 52), 4 + 24 + 48);
    d = b + 176;
    check_dfd_sample(d + 28, 0, 11, 0x80, 0, 0x3F800000u);
    check_dfd_sample(d + 44, 11, 11, 0x81, 0, 0x3F800000u);
    check_dfd_sample(d + 60, 22, 10, 0x82, 0, 0x3F800000u);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* RG16F (83) and RG32F (103): two samples; 2D and 3D headers */
    ibl_texture t2;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_3D, 4, 2, 3, 1, &t2), IBL_OK);
    t2.format = IBL_FORMAT_RG16F;
    assert_int_equal(ibl__ktx2_encode(ctx, &t2, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    b = vb;
    assert_int_equal(rd32(b + 12), 83);
    assert_int_equal(rd32(b + 28), 3); /* pixelDepth */
    assert_int_equal(rd32(b + 36), 1);
    assert_int_equal(rd32(b + 52), 4 + 24 + 32);
    check_dfd_sample(b + 80 + 24 + 28 + 16, 16, 16, 0xC1, 0xBF800000u, 0x3F800000u);
    assert_memory_equal(b + 80 + 24 + 60 + 4, "KTXorientation\0rdi\0", 19); /* 3D: "rdi" */
    ibl_free(ctx, vb);
    t2.format = IBL_FORMAT_RG32F;
    assert_int_equal(ibl__ktx2_encode(ctx, &t2, NULL, "hand.ktx2", &vb, &size), IBL_OK);
    assert_int_equal(rd32((uint8_t *)vb + 12), 103);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t2);
    ibl_context_destroy(ctx);
}

static void ktx1_bytes_by_hand(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = cube8(ctx, IBL_FORMAT_RG11B10F);
    void *vb;
    size_t size;
    /* KTX 1.1: 64-byte header; RG11B10F = GL_UNSIGNED_INT_10F_11F_11F_REV / GL_RGB /
     * GL_R11F_G11F_B10F; cube imageSize = ONE face */
    assert_int_equal(ibl__ktx1_encode(ctx, &t, NULL, "hand.ktx", &vb, &size), IBL_OK);
    const uint8_t *b = vb;
    static const uint8_t ident[12] = {0xAB, 'K', 'T', 'X', ' ', '1', '1', 0xBB, '\r', '\n', 0x1A, '\n'};
    assert_memory_equal(b, ident, 12);
    assert_int_equal(rd32(b + 12), 0x04030201);
    assert_int_equal(rd32(b + 16), 0x8C3B);
    assert_int_equal(rd32(b + 20), 4);
    assert_int_equal(rd32(b + 24), 0x1907);
    assert_int_equal(rd32(b + 28), 0x8C3A);
    assert_int_equal(rd32(b + 32), 0x1907);
    assert_int_equal(rd32(b + 36), 8);
    assert_int_equal(rd32(b + 40), 8);
    assert_int_equal(rd32(b + 44), 0);
    assert_int_equal(rd32(b + 48), 0);
    assert_int_equal(rd32(b + 52), 6);
    assert_int_equal(rd32(b + 56), 4);
    /* KTXorientation\0S=r,T=d\0 (23 -> 4+24), a (8), ibl.sh_order (20), zeta (12) */
    uint32_t kvd = 28 + 8 + 20 + 12;
    assert_int_equal(rd32(b + 60), kvd);
    assert_memory_equal(b + 68, "KTXorientation\0S=r,T=d\0", 23);
    size_t at = 64 + kvd, want_size = at;
    for (int l = 0; l < 4; l++) want_size += 4 + 6 * (size_t)(64 >> (2 * l)) * 4;
    assert_int_equal(size, want_size);
    for (int l = 0; l < 4; l++) {
        uint32_t face = (uint32_t)(64 >> (2 * l)) * 4;
        assert_int_equal(rd32(b + at), face);
        at += 4 + 6 * face;
    }
    ibl_free(ctx, vb);

    /* the cmgen form Filament's KTX1 reader needs: glType R11F_G11F_B10F, read back as the
     * same texels; and cmgen's pre-1.8 glFormat R11F_G11F_B10F is read too */
    void *vc;
    size_t csize;
    ibl_write_desc cmgen = {.ktx1_cmgen_types = 1};
    assert_int_equal(ibl__ktx1_encode(ctx, &t, &cmgen, "cmgen.ktx", &vc, &csize), IBL_OK);
    uint8_t *c = vc;
    assert_int_equal(rd32(c + 16), 0x8C3A);
    assert_int_equal(rd32(c + 24), 0x1907);
    assert_int_equal(rd32(c + 28), 0x8C3A);
    for (int old_format = 0; old_format < 2; old_format++) {
        if (old_format) wr32(c + 24, 0x8C3A);
        ibl_texture back;
        assert_int_equal(ibl__ktx1_decode(ctx, c, csize, "cmgen.ktx", &back, NULL), IBL_OK);
        assert_int_equal(back.format, IBL_FORMAT_RG11B10F);
        assert_int_equal(back.levels, 4);
        /* level 0 of face 3: R = level + 1 = 1, G = face + 1 = 4 (exact in 11-bit floats) */
        const float *px = ibl_texture_level(&back, 0, 3);
        assert_true(px[0] == 1.0f && px[1] == 4.0f);
        ibl_texture_free(ctx, &back);
    }
    ibl_free(ctx, vc);
    ibl_texture_free(ctx, &t);

    /* KTX1 format enums for the other formats */
    struct { ibl_format f; uint32_t type, size, format, internal; } gl[] = {
        {IBL_FORMAT_RGBA16F, 0x140B, 2, 0x1908, 0x881A}, {IBL_FORMAT_RGBA32F, 0x1406, 4, 0x1908, 0x8814},
        {IBL_FORMAT_RGB9E5, 0x8C3E, 4, 0x1907, 0x8C3D},  {IBL_FORMAT_RG16F, 0x140B, 2, 0x8227, 0x822F},
        {IBL_FORMAT_RG32F, 0x1406, 4, 0x8227, 0x8230}};
    for (size_t i = 0; i < sizeof gl / sizeof gl[0]; i++) {
        t = cube8(ctx, gl[i].f);
        assert_int_equal(ibl__ktx1_encode(ctx, &t, NULL, "hand.ktx", &vb, &size), IBL_OK);
        b = vb;
        assert_int_equal(rd32(b + 16), gl[i].type);
        assert_int_equal(rd32(b + 20), gl[i].size);
        assert_int_equal(rd32(b + 24), gl[i].format);
        assert_int_equal(rd32(b + 28), gl[i].internal);
        ibl_free(ctx, vb);
        ibl_texture_free(ctx, &t);
    }

    ibl_context_destroy(ctx);
}

static void dds_bytes_by_hand(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t;
    void *vb;
    size_t size;
    const uint8_t *b;
    /* DDS + DX10: cube, mips, face-major data order */
    ibl_write_desc dx10 = {.dds_header = IBL_DDS_HEADER_DX10};
    t = cube8(ctx, IBL_FORMAT_RGBA16F);
    assert_int_equal(ibl__dds_encode(ctx, &t, &dx10, "hand.dds", &vb, &size), IBL_OK);
    b = vb;
    assert_memory_equal(b, "DDS ", 4);
    assert_int_equal(rd32(b + 4), 124);
    /* CAPS|HEIGHT|WIDTH|PITCH|PIXELFORMAT|MIPMAPCOUNT */
    assert_int_equal(rd32(b + 8), 0x1u | 0x2u | 0x4u | 0x8u | 0x1000u | 0x20000u);
    assert_int_equal(rd32(b + 12), 8);
    assert_int_equal(rd32(b + 16), 8);
    assert_int_equal(rd32(b + 20), 8 * 8); /* pitch: 8 texels x 8 bytes */
    assert_int_equal(rd32(b + 28), 4);
    assert_int_equal(rd32(b + 76), 32);
    assert_int_equal(rd32(b + 80), 0x4); /* DDPF_FOURCC */
    assert_memory_equal(b + 84, "DX10", 4);
    assert_int_equal(rd32(b + 108), 0x1000u | 0x8u | 0x400000u); /* TEXTURE|COMPLEX|MIPMAP */
    assert_int_equal(rd32(b + 112), 0x200u | 0xFC00u);          /* CUBEMAP + six faces */
    assert_int_equal(rd32(b + 128), 10);  /* DXGI_FORMAT_R16G16B16A16_FLOAT */
    assert_int_equal(rd32(b + 132), 3);   /* TEXTURE2D */
    assert_int_equal(rd32(b + 136), 0x4); /* TEXTURECUBE */
    assert_int_equal(rd32(b + 140), 1);   /* arraySize: one cube */
    size_t face_bytes = (64 + 16 + 4 + 1) * 8;
    assert_int_equal(size, 148 + 6 * face_bytes);
    for (int face = 0; face < 6; face++) {
        size_t o = 148 + (size_t)face * face_bytes;
        for (int l = 0; l < 4; l++) {
            /* R = level + 1, G = face + 1 */
            assert_true(ibl_half_to_float((uint16_t)(b[o] | (b[o + 1] << 8))) == (float)(l + 1));
            assert_true(ibl_half_to_float((uint16_t)(b[o + 2] | (b[o + 3] << 8))) == (float)(face + 1));
            o += (size_t)(64 >> (2 * l)) * 8;
        }
    }
    ibl_free(ctx, vb);

    /* the default for a format with a FourCC: the legacy header (113), the same caps and data
     * with no DX10 block; a legacy request for a format without one is refused, AUTO falls
     * back to DX10 for it */
    assert_int_equal(ibl__dds_encode(ctx, &t, NULL, "legacy.dds", &vb, &size), IBL_OK);
    b = vb;
    assert_int_equal(rd32(b + 80), 0x4);
    assert_int_equal(rd32(b + 84), 113);
    assert_int_equal(rd32(b + 108), 0x1000u | 0x8u | 0x400000u);
    assert_int_equal(rd32(b + 112), 0x200u | 0xFC00u);
    assert_int_equal(size, 128 + 6 * face_bytes);
    ibl_texture back;
    assert_int_equal(ibl__dds_decode(ctx, b, size, "legacy.dds", &back, NULL), IBL_OK);
    assert_int_equal(back.kind, IBL_TEXTURE_CUBE);
    assert_int_equal(back.levels, 4);
    assert_memory_equal(back.data, t.data, ibl_cubemap_floats(8, 4) * sizeof(float));
    ibl_texture_free(ctx, &back);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);
    ibl_write_desc legacy = {.dds_header = IBL_DDS_HEADER_LEGACY};
    t = cube8(ctx, IBL_FORMAT_RG11B10F);
    assert_int_equal(ibl__dds_encode(ctx, &t, &legacy, "legacy.dds", &vb, &size), IBL_ERR_UNSUPPORTED);
    assert_message_named(ctx, "legacy.dds");
    assert_int_equal(ibl__dds_encode(ctx, &t, NULL, "auto.dds", &vb, &size), IBL_OK);
    assert_memory_equal((uint8_t *)vb + 84, "DX10", 4);
    assert_int_equal(rd32((uint8_t *)vb + 128), 26);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* DDS 3D: DEPTH flag, VOLUME caps, TEXTURE3D */
    ibl_texture v;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_3D, 4, 4, 2, 1, &v), IBL_OK);
    v.format = IBL_FORMAT_RG32F;
    assert_int_equal(ibl__dds_encode(ctx, &v, &dx10, "hand.dds", &vb, &size), IBL_OK);
    b = vb;
    assert_true(rd32(b + 8) & 0x800000u);
    assert_int_equal(rd32(b + 24), 2);
    assert_int_equal(rd32(b + 108), 0x1000u);   /* TEXTURE only: one surface */
    assert_int_equal(rd32(b + 112), 0x200000u); /* VOLUME */
    assert_int_equal(rd32(b + 128), 16);
    assert_int_equal(rd32(b + 132), 4);
    assert_int_equal(size, 148 + 4 * 4 * 2 * 8);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &v);
    ibl_context_destroy(ctx);
}

/* ---- orientation metadata and legacy DDS ---- */

static uint8_t *find_bytes(uint8_t *hay, size_t n, const char *needle, size_t len)
{
    for (size_t i = 0; i + len <= n; i++)
        if (memcmp(hay + i, needle, len) == 0) return hay + i;
    return NULL;
}

static void orientation_and_legacy(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_2D, 3, 2, 1, 1, &t), IBL_OK);
    for (int i = 0; i < 6; i++) t.data[i * 4] = (float)i; /* row 0: 0 1 2, row 1: 3 4 5 */
    t.format = IBL_FORMAT_RGBA32F;
    void *vb;
    size_t size;
    ibl_texture out;
    /* KTX2 "ru": rows stored bottom first; the reader turns them top first */
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "o.ktx2", &vb, &size), IBL_OK);
    uint8_t *o = find_bytes(vb, size, "KTXorientation\0rd", 17);
    assert_non_null(o);
    o[16] = 'u';
    assert_int_equal(ibl__ktx2_decode(ctx, vb, size, "o.ktx2", &out, NULL), IBL_OK);
    static const float flipped_y[6] = {3, 4, 5, 0, 1, 2};
    for (int i = 0; i < 6; i++) assert_true(out.data[i * 4] == flipped_y[i]);
    assert_string_equal(ibl_texture_get_metadata(&out, "KTXorientation"), "rd");
    ibl_texture_free(ctx, &out);
    o[15] = 'l';
    o[16] = 'd';
    assert_int_equal(ibl__ktx2_decode(ctx, vb, size, "o.ktx2", &out, NULL), IBL_OK);
    static const float flipped_x[6] = {2, 1, 0, 5, 4, 3};
    for (int i = 0; i < 6; i++) assert_true(out.data[i * 4] == flipped_x[i]);
    ibl_texture_free(ctx, &out);
    o[15] = 'x';
    assert_int_not_equal(ibl__ktx2_decode(ctx, vb, size, "o.ktx2", &out, NULL), IBL_OK);
    assert_message_named(ctx, "o.ktx2");
    ibl_free(ctx, vb);
    /* KTX1 "S=r,T=u" */
    assert_int_equal(ibl__ktx1_encode(ctx, &t, NULL, "o.ktx", &vb, &size), IBL_OK);
    o = find_bytes(vb, size, "S=r,T=d", 7);
    assert_non_null(o);
    o[6] = 'u';
    assert_int_equal(ibl__ktx1_decode(ctx, vb, size, "o.ktx", &out, NULL), IBL_OK);
    for (int i = 0; i < 6; i++) assert_true(out.data[i * 4] == flipped_y[i]);
    ibl_texture_free(ctx, &out);
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);
    /* a cube's orientation must be "rd" */
    t = cube8(ctx, IBL_FORMAT_RGBA16F);
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "o.ktx2", &vb, &size), IBL_OK);
    o = find_bytes(vb, size, "KTXorientation\0rd", 17);
    o[16] = 'u';
    assert_int_equal(ibl__ktx2_decode(ctx, vb, size, "o.ktx2", &out, NULL), IBL_ERR_FORMAT);
    assert_message_named(ctx, "o.ktx2");
    ibl_free(ctx, vb);
    ibl_texture_free(ctx, &t);

    /* Legacy DDS, no DX10 header: FourCC 113 (D3DFMT_A16B16G16R16F), 3x2, built by hand */
    uint8_t dds[128 + 6 * 8];
    memset(dds, 0, sizeof dds);
    memcpy(dds, "DDS ", 4);
    wr32(dds + 4, 124);
    wr32(dds + 8, 0x1 | 0x2 | 0x4 | 0x1000);
    wr32(dds + 12, 2); /* height */
    wr32(dds + 16, 3); /* width */
    wr32(dds + 76, 32);
    wr32(dds + 80, 0x4);
    wr32(dds + 84, 113);
    wr32(dds + 108, 0x1000);
    for (int i = 0; i < 6; i++) {
        uint16_t h[4] = {ibl_float_to_half((float)i), ibl_float_to_half(-0.5f), 0, 0x3C00};
        for (int c = 0; c < 4; c++) {
            dds[128 + i * 8 + c * 2] = (uint8_t)h[c];
            dds[128 + i * 8 + c * 2 + 1] = (uint8_t)(h[c] >> 8);
        }
    }
    ibl_file_info info;
    assert_int_equal(ibl__dds_decode(ctx, dds, sizeof dds, "legacy.dds", &out, &info), IBL_OK);
    assert_int_equal(out.width, 3);
    assert_int_equal(out.height, 2);
    assert_int_equal(out.levels, 1);
    assert_int_equal(info.format, IBL_FORMAT_RGBA16F);
    for (int i = 0; i < 6; i++) {
        assert_true(out.data[i * 4] == (float)i);
        assert_true(out.data[i * 4 + 1] == -0.5f);
        assert_true(out.data[i * 4 + 3] == 1.0f);
    }
    ibl_texture_free(ctx, &out);
    wr32(dds + 84, 116); /* A32B32G32R32F: now the data is too short */
    assert_int_equal(ibl__dds_decode(ctx, dds, sizeof dds, "legacy.dds", &out, NULL), IBL_ERR_FORMAT);
    assert_message_named(ctx, "legacy.dds");
    ibl_context_destroy(ctx);
}

/* ---- malformed input ---- */

static void expect_refused(ibl_context *ctx, const container *ct, const uint8_t *b, size_t n,
                           const char *what)
{
    ibl_texture out;
    ibl_status st = ct->decode(ctx, b, n, ct->name, &out, NULL);
    if (st == IBL_OK) {
        ibl_texture_free(ctx, &out);
        fail_msg("%s: %s was accepted", ct->name, what);
    }
    assert_null(out.data);
    assert_message_named(ctx, ct->name);
    /* refused before allocating: never a failure of the memory budget */
    assert_null(strstr(ibl_context_message(ctx), "memory budget"));
}

static void malformed_inputs(void **state)
{
    (void)state;
    ibl_context_desc cd = {.threads = 1, .max_bytes = 64u << 20};
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&cd, &ctx), IBL_OK);
    for (size_t c = 0; c < sizeof CONTAINERS / sizeof CONTAINERS[0]; c++) {
        const container *ct = &CONTAINERS[c];
        ibl_texture t = cube8(ctx, IBL_FORMAT_RGBA16F);
        void *vb;
        size_t size;
        /* DDS with the DX10 block: the mutations below reach its fields */
        ibl_write_desc dx10 = {.dds_header = IBL_DDS_HEADER_DX10};
        assert_int_equal(ct->encode(ctx, &t, ct->type == IBL_FILE_DDS ? &dx10 : NULL, ct->name,
                                    &vb, &size), IBL_OK);
        ibl_texture_free(ctx, &t);
        uint8_t *good = vb;
        uint8_t *bad = malloc(size);
        assert_non_null(bad);
        /* truncated anywhere, which covers every section boundary */
        for (size_t n = 0; n < size; n++) {
            memcpy(bad, good, n);
            expect_refused(ctx, ct, bad, n, "a truncated file");
        }
        /* wrong identifier / magic */
        memcpy(bad, good, size);
        bad[1] ^= 0x20;
        expect_refused(ctx, ct, bad, size, "a wrong identifier");
        if (ct->type == IBL_FILE_KTX2) {
            struct { size_t at; uint32_t v; const char *what; } pokes[] = {
                {36, 3, "faceCount 3"},
                {12, 37, "vkFormat R8G8B8A8_UNORM"},
                {16, 1, "a wrong typeSize"},
                {44, 2, "Zstandard supercompression"},
                {40, 5, "more levels than the chain has"},
                {20, 70000, "a width above the limit"},
                {32, 2, "an array texture"},
                {52, 96, "a DFD length that disagrees with dfdTotalSize"},
                {48, 0xFFFFFF00u, "a DFD outside the file"},
                {60, 0xFFFFFF00u, "KVD outside the file"},
            };
            for (size_t i = 0; i < sizeof pokes / sizeof pokes[0]; i++) {
                memcpy(bad, good, size);
                wr32(bad + pokes[i].at, pokes[i].v);
                expect_refused(ctx, ct, bad, size, pokes[i].what);
            }
            /* level 1 byteLength / uncompressedByteLength / offset inconsistent */
            memcpy(bad, good, size);
            wr64(bad + 80 + 24 + 8, rd64(good + 80 + 24 + 8) + 8);
            expect_refused(ctx, ct, bad, size, "a level length that does not match");
            memcpy(bad, good, size);
            wr64(bad + 80 + 24 + 16, 1);
            expect_refused(ctx, ct, bad, size, "an uncompressed length that does not match");
            memcpy(bad, good, size);
            wr64(bad + 80, UINT64_MAX - 8);
            expect_refused(ctx, ct, bad, size, "a level offset that overflows");
            /* dimensions whose data would overflow 32 bits: 65536^3 3D, 1 level, lengths to
             * match: refused because the data is not in the file, before any allocation */
            memcpy(bad, good, size);
            wr32(bad + 20, 65536);
            wr32(bad + 24, 65536);
            wr32(bad + 28, 65536);
            wr32(bad + 36, 1);
            wr32(bad + 40, 1);
            wr64(bad + 80 + 8, (uint64_t)65536 * 65536 * 65536 * 8);
            wr64(bad + 80 + 16, (uint64_t)65536 * 65536 * 65536 * 8);
            expect_refused(ctx, ct, bad, size, "65536^3 texels");
            /* a key/value entry whose length runs past the KVD */
            memcpy(bad, good, size);
            wr32(bad + rd32(good + 56), 0xFFFFFFF0u);
            expect_refused(ctx, ct, bad, size, "a key/value length past the end");
        } else if (ct->type == IBL_FILE_KTX1) {
            struct { size_t at; uint32_t v; const char *what; } pokes[] = {
                {52, 3, "numberOfFaces 3"},
                {28, 0x8058, "GL_RGBA8"},
                {12, 0x01020304, "big-endian"},
                {56, 9, "more levels than the chain has"},
                {36, 0x7FFFFFFF, "a width above the limit"},
                {48, 4, "an array texture"},
                {60, 0xFFFFFFF0u, "key/value data past the end"},
            };
            for (size_t i = 0; i < sizeof pokes / sizeof pokes[0]; i++) {
                memcpy(bad, good, size);
                wr32(bad + pokes[i].at, pokes[i].v);
                expect_refused(ctx, ct, bad, size, pokes[i].what);
            }
            memcpy(bad, good, size);
            size_t first = 64 + rd32(good + 60);
            wr32(bad + first, rd32(good + first) + 4);
            expect_refused(ctx, ct, bad, size, "an imageSize that does not match");
        } else {
            struct { size_t at; uint32_t v; const char *what; } pokes[] = {
                {128, 28, "DXGI R8G8B8A8_UNORM"},
                {140, 2, "an array of two cubes"},
                {140, 0, "arraySize 0"},
                {132, 7, "an invalid resource dimension"},
                {12, 65536 * 2, "a height above the limit"},
                {28, 9, "more levels than the chain has"},
                {4, 100, "a wrong header size"},
                {84, 0x31545844, "FourCC DXT1"},
            };
            for (size_t i = 0; i < sizeof pokes / sizeof pokes[0]; i++) {
                memcpy(bad, good, size);
                wr32(bad + pokes[i].at, pokes[i].v);
                expect_refused(ctx, ct, bad, size, pokes[i].what);
            }
            memcpy(bad, good, size);
            wr32(bad + 12, 65536);
            wr32(bad + 16, 65536);
            expect_refused(ctx, ct, bad, size, "65536^2 cube faces with a small file");
        }
        free(bad);
        ibl_free(ctx, good);
    }
    ibl_context_destroy(ctx);
}

/* Encoders refuse what they cannot write, with a message that names the file. */
static void encoder_refusals(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = cube8(ctx, IBL_FORMAT_RGBA16F);
    for (size_t c = 0; c < sizeof CONTAINERS / sizeof CONTAINERS[0]; c++) {
        const container *ct = &CONTAINERS[c];
        void *vb = NULL;
        size_t size = 0;
        ibl_write_desc d = {.format = IBL_FORMAT_RGBA8_SRGB};
        assert_int_equal(ct->encode(ctx, &t, &d, ct->name, &vb, &size), IBL_ERR_UNSUPPORTED);
        assert_message_named(ctx, ct->name);
        assert_null(vb);
        /* no format asked for: keep the texture's own, widen RGB32F, else RGBA16F */
        ibl_format own[4][2] = {{IBL_FORMAT_RGB9E5, IBL_FORMAT_RGB9E5}, {IBL_FORMAT_RGB32F, IBL_FORMAT_RGBA32F},
                                {IBL_FORMAT_RGB16F, IBL_FORMAT_RGBA16F}, {IBL_FORMAT_DEFAULT, IBL_FORMAT_RGBA16F}};
        for (int i = 0; i < 4; i++) {
            ibl_texture v = t;
            v.format = own[i][0];
            assert_int_equal(ct->encode(ctx, &v, NULL, ct->name, &vb, &size), IBL_OK);
            ibl_texture out;
            assert_int_equal(ct->decode(ctx, vb, size, ct->name, &out, NULL), IBL_OK);
            assert_int_equal(out.format, own[i][1]);
            ibl_texture_free(ctx, &out);
            ibl_free(ctx, vb);
            vb = NULL;
        }
        ibl_texture bad = t;
        bad.levels = 9; /* more than log2(8) + 1 */
        assert_int_equal(ct->encode(ctx, &bad, NULL, ct->name, &vb, &size), IBL_ERR_INVALID_ARGUMENT);
        assert_message_named(ctx, ct->name);
    }
    /* at most 4096 key/value entries, the container's own two included */
    for (int i = 0; i < 4095; i++) {
        char key[16];
        snprintf(key, sizeof key, "k%04d", i);
        assert_int_equal(ibl_texture_set_metadata(ctx, &t, key, "v"), IBL_OK);
    }
    void *vb = NULL;
    size_t size = 0;
    assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "many.ktx2", &vb, &size), IBL_ERR_INVALID_ARGUMENT);
    assert_message_named(ctx, "many.ktx2");
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);
}

/* Packing runs in fixed chunks of 65536 texels through the thread pool: the bytes and the
 * decoded texels must be identical at 1, 2 and 8 threads. */
static void identical_at_any_thread_count(void **state)
{
    (void)state;
    static const int threads[3] = {1, 2, 8};
    void *first = NULL;
    size_t first_size = 0;
    ibl_texture first_out = {0};
    for (int i = 0; i < 3; i++) {
        ibl_context *ctx = test_context(threads[i]);
        ibl_texture t;
        /* level 0 of a 128 cube is 98,304 texels: two chunks, the second one partial */
        assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 128, 128, 1, 2, &t), IBL_OK);
        rng = 99;
        fill_random(&t, IBL_FORMAT_RGB9E5);
        t.format = IBL_FORMAT_RGB9E5;
        void *vb;
        size_t size;
        assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "mt.ktx2", &vb, &size), IBL_OK);
        ibl_texture out;
        assert_int_equal(ibl__ktx2_decode(ctx, vb, size, "mt.ktx2", &out, NULL), IBL_OK);
        size_t n = ibl_texture_floats(out.kind, out.width, out.height, out.depth, out.levels);
        if (i == 0) {
            first = malloc(size);
            memcpy(first, vb, size);
            first_size = size;
            first_out.data = malloc(n * sizeof(float));
            memcpy(first_out.data, out.data, n * sizeof(float));
        } else {
            assert_int_equal(size, first_size);
            assert_memory_equal(vb, first, size);
            assert_memory_equal(out.data, first_out.data, n * sizeof(float));
        }
        ibl_free(ctx, vb);
        ibl_texture_free(ctx, &out);
        ibl_texture_free(ctx, &t);
        ibl_context_destroy(ctx);
    }
    free(first);
    free(first_out.data);
}

/* The KTX2 writer encodes a whole chain in one parallel loop over fixed chunks of texels:
 * every level and face must hold what the one-face encoders give it (ibl_pack_texels,
 * ibl_rgbm_encode texel by texel), and the clamped count must be the texels with a stored
 * channel past the format's largest value (|v| for the float formats, alpha included where
 * stored; v of R, G, B for RGBM), counted here one by one, at 1, 2 and 8 threads. Exact: the same functions on the same floats. */
static void chain_encoded_as_faces(void **state)
{
    (void)state;
    static const ibl_format formats[3] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RG11B10F, IBL_FORMAT_RGBM};
    static const int threads[3] = {1, 2, 8};
    for (int fi = 0; fi < 3; fi++) {
        ibl_format f = formats[fi];
        float max = f == IBL_FORMAT_RGBM ? IBL_RGBM_DEFAULT_RANGE : ibl_format_max_value(f);
        int channels = f == IBL_FORMAT_RGBM ? 3 : ibl_format_channels(f);
        for (int ti = 0; ti < 3; ti++) {
            ibl_context *ctx = test_context(threads[ti]);
            ibl_texture t;
            /* 8 levels: level 0 is 6 chunks of 16384 texels, the rest fit one chunk or less */
            assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 128, 128, 1, 8, &t), IBL_OK);
            size_t n = ibl_texture_floats(t.kind, t.width, t.height, 1, t.levels), over = 0;
            rng = 7;
            for (size_t i = 0; i < n; i++) /* 1 in 64 values far above every format's range */
                t.data[i] = (rnd() & 63) ? (float)(rnd() & 0xffff) / 4096.0f : 1.0e6f;
            for (size_t i = 0; i < n / 4; i++) {
                int o = 0;
                for (int c = 0; c < channels; c++) o |= fabsf(t.data[i * 4 + (size_t)c]) > max;
                over += (size_t)o;
            }
            ibl_write_report report = {0};
            ibl_write_desc desc = {.format = f, .report = &report};
            void *vb;
            size_t size;
            assert_int_equal(ibl__ktx2_encode(ctx, &t, &desc, "chain.ktx2", &vb, &size), IBL_OK);
            assert_int_equal(report.clamped_texels, over);
            const uint8_t *b = vb;
            size_t unit = f == IBL_FORMAT_RGBM ? 4 : ibl_format_texel_bytes(f);
            uint8_t *want = malloc(128 * 128 * 8);
            assert_non_null(want);
            for (int l = 0; l < t.levels; l++) {
                size_t at = (size_t)rd64(b + 80 + 24 * (size_t)l), edge = (size_t)128 >> l;
                for (int face = 0; face < 6; face++) {
                    const float *src = ibl_texture_level(&t, l, face);
                    if (f == IBL_FORMAT_RGBM)
                        for (size_t i = 0; i < edge * edge; i++)
                            ibl_rgbm_encode(src + 4 * i, IBL_RGBM_DEFAULT_RANGE, want + 4 * i);
                    else
                        ibl_pack_texels(f, src, edge * edge, want);
                    assert_memory_equal(b + at + (size_t)face * edge * edge * unit, want, edge * edge * unit);
                }
            }
            free(want);
            ibl_free(ctx, vb);
            ibl_texture_free(ctx, &t);
            ibl_context_destroy(ctx);
        }
    }
}

/* Through the public API (io/file.c): write to a file, read it back; the reader applies the
 * pixel policy (NaN and negatives become 0 and are counted) and names the file. */
static void public_api_files(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static const char *names[3] = {"api.ktx2", "api.ktx", "api.dds"};
    static const ibl_file_type types[3] = {IBL_FILE_KTX2, IBL_FILE_KTX1, IBL_FILE_DDS};
    for (int c = 0; c < 3; c++) {
        ibl_texture t = cube8(ctx, IBL_FORMAT_RGBA32F);
        float *p = ibl_texture_level(&t, 2, 3);
        p[0] = NAN;
        p[5] = -2.0f;
        const char *path = test_path(names[c]);
        assert_int_equal(ibl_write_texture(ctx, path, &t, NULL), IBL_OK);
        ibl_texture out;
        ibl_file_info info;
        assert_int_equal(ibl_read_texture(ctx, path, NULL, &out, &info), IBL_OK);
        assert_int_equal(info.type, types[c]);
        assert_int_equal(info.format, IBL_FORMAT_RGBA32F);
        assert_int_equal(info.kind, IBL_TEXTURE_CUBE);
        assert_int_equal(info.levels, 4);
        assert_int_equal(info.pixels.nan_count, 1);
        assert_int_equal(info.pixels.negative_count, 1);
        float *q = ibl_texture_level(&out, 2, 3);
        assert_true(q[0] == 0.0f && q[5] == 0.0f);
        assert_true(q[1] == 4.0f); /* face 3 + 1: untouched */
        if (types[c] != IBL_FILE_DDS) assert_string_equal(ibl_texture_get_metadata(&out, "ibl.sh_order"), "3");
        ibl_texture_free(ctx, &out);
        /* a flat image from a cube container is refused with the path in the message */
        ibl_image im;
        assert_int_not_equal(ibl_read_image(ctx, path, NULL, &im, NULL), IBL_OK);
        assert_message_named(ctx, path);
        ibl_texture_free(ctx, &t);
    }
    /* a one-level 2D KTX2 read as a flat image */
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 5, 3, &im), IBL_OK);
    for (int i = 0; i < 15 * 4; i++) im.pixels[i] = (float)i * 0.25f;
    const char *path = test_path("flat.ktx2");
    ibl_write_desc d = {.format = IBL_FORMAT_RGBA32F};
    assert_int_equal(ibl_write_image(ctx, path, &im, &d), IBL_OK);
    ibl_image back;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &back, NULL), IBL_OK);
    assert_int_equal(back.width, 5);
    assert_int_equal(back.height, 3);
    assert_memory_equal(back.pixels, im.pixels, 15 * 4 * sizeof(float));
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* If KTX-Software's `ktx` tool is installed (it is not packaged in Debian 12), it must accept
 * what we write; otherwise the check is skipped. */
static void ktx_tool_validates(void **state)
{
    (void)state;
    if (system("command -v ktx >/dev/null 2>&1") != 0) {
        skip();
        return;
    }
    ibl_context *ctx = test_context(1);
    for (size_t fi = 0; fi < sizeof FORMATS / sizeof FORMATS[0]; fi++) {
        ibl_texture t = cube8(ctx, FORMATS[fi]);
        void *vb;
        size_t size;
        assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "v.ktx2", &vb, &size), IBL_OK);
        const char *path = test_path("validate.ktx2");
        FILE *f = fopen(path, "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(vb, 1, size, f), size);
        fclose(f);
        char cmd[700];
        snprintf(cmd, sizeof cmd, "ktx validate '%s'", path);
        if (system(cmd) != 0) fail_msg("ktx validate refused the %s file", ibl_format_name(FORMATS[fi]));
        ibl_free(ctx, vb);
        ibl_texture_free(ctx, &t);
    }
    ibl_context_destroy(ctx);
}

/* Cross-check with an independent KTX2 implementation, ktx-parse (npm; glTF-Transform's
 * parser/serializer): it must read every file we write and, writing it back, produce the very
 * same bytes (layout, alignment, level order, DFD, sorted KVD and padding). ktx-parse is the
 * one tests/viewer installs (`npm ci` in scripts/install-deps.sh); IBL_KTX_PARSE_DIR names
 * another folder holding node_modules/ktx-parse. A missing ktx-parse or node fails the test. */
static void ktx_parse_cross_check(void **state)
{
    (void)state;
    const char *dir = getenv("IBL_KTX_PARSE_DIR");
    if (!dir) dir = IBL_TEST_DATA "/../viewer";
    char probe[600];
    snprintf(probe, sizeof probe, "%s/node_modules/ktx-parse/package.json", dir);
    if (!test_file_exists(probe)) fail_msg("no %s (run scripts/install-deps.sh)", probe);
    if (system("command -v node >/dev/null 2>&1") != 0) fail_msg("no node on the PATH (nodejs)");
    ibl_context *ctx = test_context(1);
    static const ibl_texture_kind kinds[] = {IBL_TEXTURE_2D, IBL_TEXTURE_3D, IBL_TEXTURE_CUBE};
    for (size_t fi = 0; fi < sizeof FORMATS / sizeof FORMATS[0]; fi++) {
        for (int k = 0; k < 3; k++) {
            ibl_texture t = make_texture(ctx, kinds[k], 1, FORMATS[fi]);
            add_metadata(ctx, &t);
            void *vb;
            size_t size;
            assert_int_equal(ibl__ktx2_encode(ctx, &t, NULL, "x.ktx2", &vb, &size), IBL_OK);
            const char *path = test_path("cross.ktx2");
            FILE *f = fopen(path, "wb");
            assert_non_null(f);
            assert_int_equal(fwrite(vb, 1, size, f), size);
            fclose(f);
            char cmd[1600];
            snprintf(cmd, sizeof cmd,
                     "cd '%s' && node --input-type=module -e \"import {read, write} from 'ktx-parse';"
                     "import fs from 'fs'; const b = new Uint8Array(fs.readFileSync(process.argv[1]));"
                     "const c = read(b); const r = write(c, {keepWriter: true});"
                     "const same = r.length === b.length && r.every((v, i) => v === b[i]);"
                     "process.exit(same && c.vkFormat === %u && c.levels.length === %d ? 0 : 3);\" '%s'",
                     dir, (unsigned)((const uint8_t *)vb)[12] | ((unsigned)((const uint8_t *)vb)[13] << 8),
                     t.levels, path);
            if (system(cmd) != 0)
                fail_msg("ktx-parse disagrees on the %s kind %d file", ibl_format_name(FORMATS[fi]), k);
            ibl_free(ctx, vb);
            ibl_texture_free(ctx, &t);
        }
    }
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(round_trip_all),
        cmocka_unit_test(ktx2_bytes_by_hand),
        cmocka_unit_test(ktx1_bytes_by_hand),
        cmocka_unit_test(dds_bytes_by_hand),
        cmocka_unit_test(orientation_and_legacy),
        cmocka_unit_test(malformed_inputs),
        cmocka_unit_test(encoder_refusals),
        cmocka_unit_test(identical_at_any_thread_count),
        cmocka_unit_test(chain_encoded_as_faces),
        cmocka_unit_test(public_api_files),
        cmocka_unit_test(ktx_tool_validates),
        cmocka_unit_test(ktx_parse_cross_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
