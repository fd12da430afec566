/* The memory budget (ibl_context_desc.max_bytes): a cap on the total the context holds, kept
 * across threads, with a peak counter; inputs whose declared size the file cannot hold, or
 * the budget cannot, refused before any large allocation with one line naming the file; and
 * the CLI's --max-memory as that total. Every file here is generated and small. */
#include "test_support.h"

#include <errno.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <pthread.h>
#include <stdatomic.h>

static const uint64_t KiB = 1024, MiB = 1024 * 1024;

static ibl_context *budget_context(uint64_t max_bytes, int threads)
{
    ibl_context_desc d = {0};
    d.threads = threads;
    d.max_bytes = max_bytes;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    return ctx;
}

static void spit(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
}

static uint8_t *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)n);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return b;
}

/* One line that starts with the file's name. */
static void assert_names_file(ibl_context *ctx, const char *path)
{
    const char *m = ibl_context_message(ctx);
    if (strncmp(m, path, strlen(path)) != 0 || strchr(m, '\n'))
        fail_msg("message does not start with %s on one line: \"%s\"", path, m);
}

/* ---- the budget ---------------------------------------------------------------------- */

static void budget_counts_the_total(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(MiB, 1);
    assert_int_equal(ibl_context_max_bytes(ctx), MiB);
    void *a = ibl_alloc(ctx, 600 * KiB);
    assert_non_null(a);
    assert_int_equal(ibl_context_current_bytes(ctx), 600 * KiB);
    /* each alone fits, together they do not */
    assert_null(ibl_alloc(ctx, 500 * KiB));
    assert_int_equal(ibl_context_status(ctx), IBL_ERR_TOO_LARGE);
    assert_string_equal(ibl_context_message(ctx),
                        "needs 500.0 KiB more with 600.0 KiB in use, over the memory budget of 1.0 MiB");
    assert_null(ibl_calloc(ctx, 500, KiB));
    assert_int_equal(ibl_context_current_bytes(ctx), 600 * KiB);
    /* freeing gives the bytes back: the whole budget in one block, then nothing more */
    ibl_free(ctx, a);
    assert_int_equal(ibl_context_current_bytes(ctx), 0);
    uint8_t *all = ibl_calloc(ctx, MiB, 1);
    assert_non_null(all);
    assert_int_equal(all[MiB - 1], 0);
    assert_null(ibl_alloc(ctx, 1));
    assert_int_equal(ibl_context_peak_bytes(ctx), MiB);
    ibl_free(ctx, all);
    assert_int_equal(ibl_context_current_bytes(ctx), 0);
    assert_int_equal(ibl_context_peak_bytes(ctx), MiB); /* the peak stays */
    /* sizes the address space cannot hold are refused too */
    assert_null(ibl_alloc(ctx, SIZE_MAX - 8));
    assert_int_equal(ibl_context_status(ctx), IBL_ERR_TOO_LARGE);
    ibl_context_destroy(ctx);
}

static void budget_default(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(0, 1);
    uint64_t physical = (uint64_t)sysconf(_SC_PHYS_PAGES) * (uint64_t)sysconf(_SC_PAGESIZE);
    assert_int_equal(ibl_context_max_bytes(ctx), ibl_default_max_bytes());
    assert_true(ibl_default_max_bytes() > 0);
    assert_true(ibl_default_max_bytes() <= physical / 2);
    ibl_context_destroy(ctx);
    /* blocks keep 64-byte alignment and free with a NULL context when allocated with one */
    void *p = ibl_alloc(NULL, 100);
    assert_non_null(p);
    assert_int_equal((uintptr_t)p % 64, 0);
    ibl_free(NULL, p);
}

/* A block freed through another context (same allocator) is freed, and neither count wraps:
 * the bytes stay counted where they were allocated. */
static void freed_through_another_context(void **state)
{
    (void)state;
    ibl_context *a = budget_context(MiB, 1), *b = budget_context(MiB, 1);
    void *p = ibl_alloc(a, 100 * KiB), *q = ibl_alloc(b, 10 * KiB);
    ibl_free(b, p);
    assert_int_equal(ibl_context_current_bytes(b), 10 * KiB);
    assert_int_equal(ibl_context_current_bytes(a), 100 * KiB);
    assert_non_null(p = ibl_alloc(b, 1000 * KiB)); /* b's count did not wrap */
    ibl_free(b, p);
    ibl_free(b, q);
    assert_int_equal(ibl_context_current_bytes(b), 0);
    ibl_context_destroy(a);
    ibl_context_destroy(b);
}

/* Worker threads allocating at once never take the total over the budget, and every byte
 * comes back. 64 tasks each try to hold 8 blocks of 1 MiB under a 20 MiB budget. */
typedef struct churn_job {
    ibl_context *ctx;
    int refused[64];
} churn_job;

static void churn_task(void *arg, int index)
{
    churn_job *j = arg;
    void *held[8];
    for (int round = 0; round < 20; round++) {
        for (int k = 0; k < 8; k++) {
            held[k] = ibl_alloc(j->ctx, MiB);
            if (!held[k]) j->refused[index]++;
            else memset(held[k], index, 4096);
        }
        for (int k = 0; k < 8; k++) ibl_free(j->ctx, held[k]);
    }
}

static void budget_across_threads(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(20 * MiB, 4);
    static churn_job job;
    memset(&job, 0, sizeof job);
    job.ctx = ctx;
    ibl_parallel_for(ctx, 64, churn_task, &job);
    assert_int_equal(ibl_context_current_bytes(ctx), 0);
    assert_true(ibl_context_peak_bytes(ctx) <= 20 * MiB);
    assert_true(ibl_context_peak_bytes(ctx) >= 8 * MiB);
    int refused = 0;
    for (int i = 0; i < 64; i++) refused += job.refused[i];
    /* with four threads holding up to 32 MiB at once some were refused (unless the threads
     * never overlapped, which one core can do) */
    if (ibl_context_threads(ctx) == 1) assert_int_equal(refused, 0);
    if (refused) assert_int_equal(ibl_context_status(ctx), IBL_ERR_TOO_LARGE);
    ibl_context_destroy(ctx);
}

/* The peak of a real decode counts the image and the file, and freeing returns to zero. */
static void peak_of_a_read(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(0, 2);
    ibl_image im;
    assert_int_equal(ibl_read_image(ctx, test_data("city.exr"), NULL, &im, NULL), IBL_OK);
    uint64_t image = (uint64_t)im.width * (uint64_t)im.height * 16;
    assert_true(ibl_context_current_bytes(ctx) >= image);
    assert_true(ibl_context_peak_bytes(ctx) >= image + 200 * KiB); /* + the 213 KB file */
    ibl_image_free(ctx, &im);
    assert_int_equal(ibl_context_current_bytes(ctx), 0);
    ibl_context_destroy(ctx);
}

/* ---- bombs: declared sizes the file cannot hold -------------------------------------- */

/* Reads path, expects `status`, a message naming the file, and no block near the size. */
static void expect_refused(const char *path, ibl_status status)
{
    ibl_context *ctx = budget_context(0, 2);
    ibl_texture t;
    ibl_status s = ibl_read_texture(ctx, path, NULL, &t, NULL);
    if (s == IBL_OK) {
        ibl_texture_free(ctx, &t);
        fail_msg("%s was accepted", path);
    }
    assert_int_equal(s, status);
    assert_names_file(ctx, path);
    if (ibl_context_peak_bytes(ctx) > MiB)
        fail_msg("%s: %llu bytes held before refusing", path,
                 (unsigned long long)ibl_context_peak_bytes(ctx));
    assert_int_equal(ibl_context_current_bytes(ctx), 0);
    ibl_context_destroy(ctx);
}

static uint32_t crc32_of(const uint8_t *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
}

static size_t put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8), p[3] = (uint8_t)v;
    return 4;
}

static size_t png_chunk(uint8_t *out, const char *type, const uint8_t *data, uint32_t len)
{
    size_t n = put_be32(out, len);
    memcpy(out + n, type, 4);
    if (len) memcpy(out + n + 4, data, len);
    n += 4 + len;
    return n + put_be32(out + n, crc32_of(out + 4, 4 + (size_t)len));
}

/* A JPEG of 64x32 written by ibl whose frame header then claims 16000x8000: 3 KB. */
static void jpeg_bomb(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(0, 1);
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &im), IBL_OK);
    for (int i = 0; i < 64 * 32 * 4; i++) im.pixels[i] = (float)(i % 7) * 0.1f;
    const char *small = test_path("small.jpg");
    assert_int_equal(ibl_write_image(ctx, small, &im, NULL), IBL_OK);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
    size_t n;
    uint8_t *b = slurp(small, &n);
    size_t pos = 2;
    while (pos + 9 < n && !(b[pos] == 0xFF && b[pos + 1] >= 0xC0 && b[pos + 1] <= 0xC2))
        pos += 2 + ((size_t)b[pos + 2] << 8 | b[pos + 3]);
    assert_true(pos + 9 < n);
    b[pos + 5] = 8000 >> 8, b[pos + 6] = 8000 & 255, b[pos + 7] = 16000 >> 8, b[pos + 8] = 16000 & 255;
    const char *bomb = test_path("bomb.jpg");
    spit(bomb, b, n);
    free(b);
    expect_refused(bomb, IBL_ERR_FORMAT);
}

/* A PNG header claiming 16000x8000 RGB with 1000 bytes of image data (it needs 372093). */
static void png_bomb(void **state)
{
    (void)state;
    static uint8_t b[2048];
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    uint8_t ihdr[13] = {0};
    put_be32(ihdr, 16000);
    put_be32(ihdr + 4, 8000);
    ihdr[8] = 8, ihdr[9] = 2;
    uint8_t idat[1000];
    memset(idat, 0, sizeof idat);
    idat[0] = 0x78, idat[1] = 0xDA;
    size_t n = 8;
    memcpy(b, signature, 8);
    n += png_chunk(b + n, "IHDR", ihdr, 13);
    n += png_chunk(b + n, "IDAT", idat, sizeof idat);
    n += png_chunk(b + n, "IEND", NULL, 0);
    const char *bomb = test_path("bomb.png");
    spit(bomb, b, n);
    expect_refused(bomb, IBL_ERR_FORMAT);
}


/* A legitimate PNG of zeros compresses about 1000 to 1: it loads within the budget, and a
 * budget too small for it refuses it before decoding. */
static void png_of_zeros(void **state)
{
    (void)state;
    const int w = 4096, h = 2048;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    test_bytes m = {NULL, 0, 0};
    test_png_write_to_memory(png, &m);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 9);
    png_write_info(png, info);
    png_bytep row = calloc((size_t)w, 3);
    for (int y = 0; y < h; y++) png_write_row(png, row);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    free(row);
    assert_true(m.n < 64 * KiB); /* 25 MB of samples */
    const char *path = test_path("zeros.png");
    spit(path, m.b, m.n);
    free(m.b);

    ibl_context *ctx = budget_context(0, 2);
    ibl_texture t;
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &t, NULL), IBL_OK);
    assert_int_equal(t.width, w);
    assert_true(t.data[0] == 0.0f && t.data[(size_t)w * h * 4 - 4] == 0.0f && t.data[3] == 1.0f);
    /* the samples were decoded inside the float image: no second buffer of their size */
    assert_true(ibl_context_peak_bytes(ctx) < (uint64_t)w * h * 16 + 2 * MiB);
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);

    ctx = budget_context(64 * MiB, 2);
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &t, NULL), IBL_ERR_TOO_LARGE);
    assert_names_file(ctx, path);
    assert_non_null(strstr(ibl_context_message(ctx), "over the memory budget of 64.0 MiB"));
    assert_true(ibl_context_peak_bytes(ctx) < MiB);
    ibl_context_destroy(ctx);
}

/* Uncompressed scanline OpenEXR (R, G, B float) with the given windows; each chunk stores
 * `stored` bytes (its real size when 0). */
static size_t exr_file(uint8_t *b, const int32_t data[4], const int32_t display[4], int32_t stored)
{
    size_t n = 0;
#define PUT(p, len) (memcpy(b + n, (p), (len)), n += (len))
    static const uint8_t magic[8] = {0x76, 0x2F, 0x31, 0x01, 2, 0, 0, 0};
    PUT(magic, 8);
    uint8_t ch[64];
    size_t cn = 0;
    for (int c = 0; c < 3; c++) {
        ch[cn++] = (uint8_t)"BGR"[c];
        ch[cn++] = 0;
        const int32_t fields[4] = {2, 0, 1, 1};
        memcpy(ch + cn, fields, 16), cn += 16;
    }
    ch[cn++] = 0;
    const struct {
        const char *name, *type;
        const void *value;
        int32_t len;
    } attrs[] = {
        {"channels", "chlist", ch, (int32_t)cn},
        {"compression", "compression", "\0", 1},
        {"dataWindow", "box2i", data, 16},
        {"displayWindow", "box2i", display, 16},
        {"lineOrder", "lineOrder", "\0", 1},
        {"pixelAspectRatio", "float", (const float[]){1.0f}, 4},
        {"screenWindowCenter", "v2f", (const float[]){0.0f, 0.0f}, 8},
        {"screenWindowWidth", "float", (const float[]){1.0f}, 4},
    };
    for (size_t i = 0; i < sizeof attrs / sizeof attrs[0]; i++) {
        PUT(attrs[i].name, strlen(attrs[i].name) + 1);
        PUT(attrs[i].type, strlen(attrs[i].type) + 1);
        PUT(&attrs[i].len, 4);
        PUT(attrs[i].value, (size_t)attrs[i].len);
    }
    b[n++] = 0;
    int32_t w = data[2] - data[0] + 1, h = data[3] - data[1] + 1;
    int32_t line = stored ? stored : w * 12;
    uint64_t at = n + (uint64_t)h * 8;
    for (int32_t y = 0; y < h; y++, at += 8 + (uint64_t)line) PUT(&at, 8);
    for (int32_t y = 0; y < h; y++) {
        int32_t yy = data[1] + y;
        PUT(&yy, 4);
        PUT(&line, 4);
        memset(b + n, 0, (size_t)line), n += (size_t)line;
    }
#undef PUT
    return n;
}

static void exr_bombs(void **state)
{
    (void)state;
    uint8_t *b = malloc(2 * MiB);
    assert_non_null(b);
    /* a 1x1 data window in a 16000x8000 display window: 2 GiB of zeros from 341 bytes */
    const int32_t one[4] = {0, 0, 0, 0}, wide[4] = {0, 0, 15999, 7999};
    size_t n = exr_file(b, one, wide, 0);
    const char *path = test_path("window.exr");
    spit(path, b, n);
    expect_refused(path, IBL_ERR_UNSUPPORTED);
    /* a data window covering 1/16 of a 2048x1024 display window is filled with zeros; one
     * line less is refused */
    const int32_t display[4] = {0, 0, 2047, 1023};
    for (int32_t rows = 128; rows >= 127; rows--) {
        const int32_t part[4] = {512, 300, 1535, 300 + rows - 1};
        n = exr_file(b, part, display, 0);
        ibl_context *ctx = budget_context(0, 1);
        ibl_texture t;
        ibl_status s = ibl_decode_texture(ctx, b, n, "part.exr", NULL, &t, NULL);
        if (rows == 128) {
            assert_int_equal(s, IBL_OK);
            assert_int_equal(t.width, 2048);
            assert_int_equal(t.height, 1024);
            assert_true(t.data[3] == 0.0f);                                /* outside: 0 */
            assert_true(t.data[((size_t)300 * 2048 + 512) * 4 + 3] == 1.0f); /* data: alpha 1 */
            ibl_texture_free(ctx, &t);
        } else {
            assert_int_equal(s, IBL_ERR_UNSUPPORTED);
            assert_names_file(ctx, "part.exr");
        }
        ibl_context_destroy(ctx);
    }
    /* scanlines 60001 texels wide whose chunks store 4 bytes each */
    const int32_t lines[4] = {0, 0, 60000, 3};
    n = exr_file(b, lines, lines, 4);
    path = test_path("lines.exr");
    spit(path, b, n);
    expect_refused(path, IBL_ERR_FORMAT);
    free(b);
}

static void hdr_bomb(void **state)
{
    (void)state;
    static const char text[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 65536 +X 65536\n\x02\x02\x01\x00";
    const char *path = test_path("bomb.hdr");
    spit(path, text, sizeof text - 1);
    expect_refused(path, IBL_ERR_FORMAT);
}

/* Devices and pipes are sniffed from their first bytes: /dev/zero is not an image. A pipe
 * carrying a real file (longer than the first 64 KiB piece) reads whole. */
typedef struct pipe_job {
    const char *fifo;
    const uint8_t *bytes;
    size_t size;
} pipe_job;

static void *pipe_writer(void *arg)
{
    pipe_job *j = arg;
    FILE *f = fopen(j->fifo, "wb");
    if (!f) return (void *)1;
    size_t done = fwrite(j->bytes, 1, j->size, f);
    fclose(f);
    return done == j->size ? NULL : (void *)1;
}

static void devices_and_pipes(void **state)
{
    (void)state;
    expect_refused("/dev/zero", IBL_ERR_FORMAT);
    const char *fifo = test_path("pipe.exr");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    pipe_job job = {fifo, NULL, 0};
    uint8_t *file = slurp(test_data("city.exr"), &job.size); /* 213 KB: four pieces */
    job.bytes = file;
    pthread_t writer;
    assert_int_equal(pthread_create(&writer, NULL, pipe_writer, &job), 0);
    ibl_context *ctx = budget_context(0, 2);
    ibl_texture t;
    assert_int_equal(ibl_read_texture(ctx, fifo, NULL, &t, NULL), IBL_OK);
    void *r = NULL;
    pthread_join(writer, &r);
    assert_null(r);
    ibl_texture direct;
    assert_int_equal(ibl_read_texture(ctx, test_data("city.exr"), NULL, &direct, NULL), IBL_OK);
    assert_int_equal(t.width, direct.width);
    assert_memory_equal(t.data, direct.data, (size_t)t.width * t.height * 16);
    ibl_texture_free(ctx, &t);
    ibl_texture_free(ctx, &direct);
    ibl_context_destroy(ctx);
    free(file);
}

/* Every reader refuses an image the budget cannot hold before decoding it, naming the file. */
static void every_reader_checks_the_budget(void **state)
{
    (void)state;
    ibl_context *ctx = budget_context(0, 2);
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 512, 256, &im), IBL_OK);
    for (size_t i = 0; i < (size_t)512 * 256 * 4; i++) im.pixels[i] = (float)(i % 13) * 0.25f;
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 128, 1, &cube), IBL_OK);
    test_fill_cube(&cube, 0.5f, 1.0f, 2.0f);
    ibl_texture tex = ibl_texture_from_cubemap(&cube);
    static const char *const flat[] = {"b.hdr", "b.exr", "b.pfm", "b.png", "b.jpg"};
    static const char *const containers[] = {"b.ktx2", "b.ktx", "b.dds"};
    for (int i = 0; i < 5; i++)
        assert_int_equal(ibl_write_image(ctx, test_path(flat[i]), &im, NULL), IBL_OK);
    for (int i = 0; i < 3; i++)
        assert_int_equal(ibl_write_texture(ctx, test_path(containers[i]), &tex, NULL), IBL_OK);
    ibl_image_free(ctx, &im);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
    /* 2 MiB and 1.5 MiB of floats: a budget of 1 MiB holds neither */
    for (int i = 0; i < 8; i++) {
        const char *path = test_path(i < 5 ? flat[i] : containers[i - 5]);
        ctx = budget_context(MiB, 2);
        ibl_texture t;
        ibl_status s = ibl_read_texture(ctx, path, NULL, &t, NULL);
        if (s == IBL_OK) fail_msg("%s was read within 1 MiB", path);
        assert_int_equal(s, IBL_ERR_TOO_LARGE);
        assert_names_file(ctx, path);
        assert_non_null(strstr(ibl_context_message(ctx), "over the memory budget of 1.0 MiB"));
        assert_int_equal(ibl_context_current_bytes(ctx), 0);
        ibl_context_destroy(ctx);
    }
}

/* ---- the CLI ------------------------------------------------------------------------- */

/* --max-memory caps the total: the 256 GGX chain of city.exr holds 29-30 MiB at its peak in
 * blocks of at most 8 MiB (when --max-memory capped one block, 40 let it through), so 24
 * refuses it (one line, exit 1, no output) and 200 does not. */
static void cli_max_memory_is_a_total(void **state)
{
    (void)state;
    const char *text;
    const char *out = test_path("chain.ktx2");
    int rc = test_run_cli(&text, "prefilter -q '%s' -o '%s' --size 256 --max-memory 24",
                          test_data("city.exr"), out);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(text, "over the memory budget of 24.0 MiB"));
    assert_int_equal(strchr(text, '\n') - text + 1, (long)strlen(text)); /* one line */
    assert_false(test_file_exists(out));
    rc = test_run_cli(&text, "prefilter -q '%s' -o '%s' --size 256 --max-memory 200",
                      test_data("city.exr"), out);
    assert_int_equal(rc, 0);
    assert_true(test_file_exists(out));
    /* a reader's refusal names the file */
    rc = test_run_cli(&text, "info '%s' --max-memory 4", test_data("city.exr"));
    assert_int_equal(rc, 1);
    assert_non_null(strstr(text, "city.exr: "));
    assert_non_null(strstr(text, "over the memory budget of 4.0 MiB"));
}

/* An allocator whose blocks are dirty (0xab bytes), as a reused block is. */
static void *dirty_alloc(size_t bytes, void *user)
{
    (void)user;
    void *p = malloc(bytes ? bytes : 1);
    if (p) memset(p, 0xab, bytes);
    return p;
}

static void plain_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

/* A context on `threads` threads whose allocator hands out dirty blocks. */
static ibl_context *dirty_context(int threads)
{
    ibl_context_desc d = {0};
    d.threads = threads;
    d.allocator.alloc = dirty_alloc;
    d.allocator.free = plain_free;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    return ctx;
}

static int all_zero(const float *p, size_t n)
{
    static const float zero[1024];
    for (size_t i = 0; i < n; i += 1024)
        if (memcmp(p + i, zero, (n - i < 1024 ? n - i : 1024) * sizeof(float)) != 0) return 0;
    return 1;
}

/* Images, cubes and textures come zeroed, whatever the allocator gave, at any thread count:
 * large ones are zeroed in parallel chunks (core/image.c), small ones by one memset; the
 * sizes straddle the 4 MiB switch and end in partial chunks. */
static void new_pixels_are_zero(void **state)
{
    (void)state;
    static const int threads[3] = {1, 2, 8};
    for (int t = 0; t < 3; t++) {
        ibl_context *ctx = dirty_context(threads[t]);
        ibl_cubemap cube;
        assert_int_equal(ibl_cubemap_alloc(ctx, 300, 9, &cube), IBL_OK); /* 11.5 MB */
        assert_true(all_zero(cube.data, ibl_cubemap_floats(300, 9)));
        ibl_cubemap_free(ctx, &cube);
        assert_int_equal(ibl_cubemap_alloc(ctx, 100, 1, &cube), IBL_OK); /* 0.96 MB */
        assert_true(all_zero(cube.data, ibl_cubemap_floats(100, 1)));
        ibl_cubemap_free(ctx, &cube);
        ibl_image im;
        assert_int_equal(ibl_image_alloc(ctx, 1031, 257, &im), IBL_OK); /* 4.24 MB */
        assert_true(all_zero(im.pixels, (size_t)1031 * 257 * 4));
        ibl_image_free(ctx, &im);
        ibl_texture tex;
        assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_3D, 64, 64, 70, 1, &tex), IBL_OK);
        assert_true(all_zero(tex.data, (size_t)64 * 64 * 70 * 4)); /* 4.59 MB */
        ibl_texture_free(ctx, &tex);
        ibl_context_destroy(ctx);
    }
}

typedef struct nested_job {
    ibl_context *ctx;
    int zeroed[4];
} nested_job;

/* Each task allocates a cube large enough to be zeroed by a parallel loop of its own. */
static void nested_task(void *arg, int index)
{
    nested_job *j = arg;
    ibl_cubemap cube;
    if (ibl_cubemap_alloc(j->ctx, 300, 9, &cube) != IBL_OK) return;
    j->zeroed[index] = all_zero(cube.data, ibl_cubemap_floats(300, 9));
    ibl_cubemap_free(j->ctx, &cube);
}

/* A parallel loop started from inside a task of the context's pool (here: the parallel
 * zeroing of a large cube allocated in a task) runs beside the outer loop: this returns, and
 * every cube still comes zeroed, on 1, 2 and 8 threads. */
static void parallel_loop_inside_a_task(void **state)
{
    (void)state;
    static const int threads[3] = {1, 2, 8};
    for (int t = 0; t < 3; t++) {
        nested_job job = {.ctx = dirty_context(threads[t])};
        ibl_parallel_for(job.ctx, 4, nested_task, &job);
        for (int i = 0; i < 4; i++) assert_int_equal(job.zeroed[i], 1);
        ibl_context_destroy(job.ctx);
    }
}

/* Many short jobs, some after a pause long enough for the pool's workers to fall asleep (a
 * worker woken after the caller took every index does not join that job, and must not run
 * the next one's indices with this one's task): every index of every job runs once, with its
 * own job's argument, on 2 and 8 threads. */
typedef struct tally_job {
    int id;
    _Atomic int runs[32];
    _Atomic int wrong_job;
} tally_job;

static void tally_task(void *arg, int index)
{
    tally_job *j = arg;
    atomic_fetch_add(&j->runs[index], 1);
    if (j->id < 0) atomic_fetch_add(&j->wrong_job, 1);
}

static void every_index_once_across_jobs(void **state)
{
    (void)state;
    static const int threads[2] = {2, 8};
    for (int t = 0; t < 2; t++) {
        ibl_context *ctx = budget_context(MiB, threads[t]);
        for (int round = 0; round < 600; round++) {
            tally_job job = {.id = round};
            int count = 1 + round % 32;
            for (int i = 0; i < 32; i++) atomic_init(&job.runs[i], 0);
            atomic_init(&job.wrong_job, 0);
            struct timespec pause = {0, 300000}; /* longer than a worker spins before sleeping */
            if (round % 7 == 0) nanosleep(&pause, NULL);
            ibl_parallel_for(ctx, count, tally_task, &job);
            job.id = -1; /* a late run of this job's task would count as wrong */
            for (int i = 0; i < 32; i++) assert_int_equal(atomic_load(&job.runs[i]), i < count);
            assert_int_equal(atomic_load(&job.wrong_job), 0);
        }
        ibl_context_destroy(ctx);
    }
}

/* A loop started inside a task runs on every thread: the outer loop's other index returns at
 * once, and its thread must then help the inner loop, whose first task waits (up to 10 s)
 * until a second thread has run one of its tasks. A pool that ran nested loops on the calling
 * thread alone fails this. */
typedef struct helped_job {
    ibl_context *ctx;
    pthread_mutex_t lock;
    pthread_t first;
    int threads_seen;
    _Atomic int two_seen, timed_out;
} helped_job;

static void helped_inner_task(void *arg, int index)
{
    (void)index;
    helped_job *j = arg;
    pthread_mutex_lock(&j->lock);
    if (j->threads_seen == 0) {
        j->first = pthread_self();
        j->threads_seen = 1;
    } else if (!pthread_equal(j->first, pthread_self())) {
        j->threads_seen = 2;
        atomic_store(&j->two_seen, 1);
    }
    pthread_mutex_unlock(&j->lock);
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    while (!atomic_load(&j->two_seen) && !atomic_load(&j->timed_out)) {
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (now.tv_sec - start.tv_sec > 10) {
            atomic_store(&j->timed_out, 1);
            return;
        }
    }
}

static void helped_outer_task(void *arg, int index)
{
    helped_job *j = arg;
    if (index == 0) ibl_parallel_for(j->ctx, 64, helped_inner_task, j);
}

static void nested_loop_runs_on_every_thread(void **state)
{
    (void)state;
    helped_job job = {.ctx = budget_context(MiB, 2)};
    pthread_mutex_init(&job.lock, NULL);
    atomic_init(&job.two_seen, 0);
    atomic_init(&job.timed_out, 0);
    ibl_parallel_for(job.ctx, 2, helped_outer_task, &job);
    assert_int_equal(atomic_load(&job.timed_out), 0);
    assert_int_equal(job.threads_seen, 2);
    pthread_mutex_destroy(&job.lock);
    ibl_context_destroy(job.ctx);
}

/* Loops three deep, of many sizes, posted from every thread at once: every index of every
 * loop runs once, on 2 and 8 threads, over many rounds (a lost wake-up hangs it, a job
 * retired while another thread still reads it trips ASan or TSan). */
enum { NEST_OUTER = 6, NEST_INNER = 26, NEST_LEAF = 3 };
typedef struct deep_job {
    ibl_context *ctx;
    _Atomic int runs[NEST_OUTER][NEST_INNER][NEST_LEAF];
} deep_job;

typedef struct deep_inner {
    deep_job *job;
    int outer, inner;
} deep_inner;

static void deep_leaf_task(void *arg, int index)
{
    deep_inner *d = arg;
    atomic_fetch_add(&d->job->runs[d->outer][d->inner][index], 1);
}

typedef struct deep_middle {
    deep_job *job;
    int outer;
} deep_middle;

static void deep_inner_task(void *arg, int index)
{
    deep_middle *m = arg;
    deep_inner d = {m->job, m->outer, index};
    ibl_parallel_for(m->job->ctx, NEST_LEAF, deep_leaf_task, &d);
}

static void deep_outer_task(void *arg, int index)
{
    deep_job *j = arg;
    deep_middle m = {j, index};
    ibl_parallel_for(j->ctx, 1 + index * 5, deep_inner_task, &m); /* 1 to 26 */
}

static void nested_loops_every_index_once(void **state)
{
    (void)state;
    static const int threads[2] = {2, 8};
    for (int t = 0; t < 2; t++) {
        deep_job *job = calloc(1, sizeof *job);
        assert_non_null(job);
        job->ctx = budget_context(MiB, threads[t]);
        for (int round = 0; round < 200; round++) {
            for (int o = 0; o < NEST_OUTER; o++)
                for (int i = 0; i < NEST_INNER; i++)
                    for (int k = 0; k < NEST_LEAF; k++) atomic_init(&job->runs[o][i][k], 0);
            ibl_parallel_for(job->ctx, NEST_OUTER, deep_outer_task, job);
            for (int o = 0; o < NEST_OUTER; o++)
                for (int i = 0; i < NEST_INNER; i++)
                    for (int k = 0; k < NEST_LEAF; k++)
                        assert_int_equal(atomic_load(&job->runs[o][i][k]), i < 1 + o * 5);
        }
        ibl_context_destroy(job->ctx);
        free(job);
    }
}

/* An allocator that hands out page-aligned blocks filled with 0xab and keeps a list of them,
 * so a test can see which bytes ibl_alloc wrote and that ibl_free gives back each block it
 * got, once. Pool tasks allocate too: a mutex. */
enum { RECORDED_BLOCKS = 512 };
typedef struct recording_allocator {
    pthread_mutex_t lock;
    void *start[RECORDED_BLOCKS];
    size_t bytes[RECORDED_BLOCKS];
    int live, unknown_frees;
} recording_allocator;

static void *recording_alloc(size_t bytes, void *user)
{
    recording_allocator *r = user;
    size_t rounded = (bytes + 4095) & ~(size_t)4095;
    void *p = aligned_alloc(4096, rounded ? rounded : 4096);
    if (!p) return NULL;
    memset(p, 0xab, bytes);
    pthread_mutex_lock(&r->lock);
    if (r->live == RECORDED_BLOCKS) fail_msg("more than %d blocks at once", RECORDED_BLOCKS);
    r->start[r->live] = p;
    r->bytes[r->live++] = bytes;
    pthread_mutex_unlock(&r->lock);
    return p;
}

static void recording_free(void *ptr, void *user)
{
    recording_allocator *r = user;
    pthread_mutex_lock(&r->lock);
    int i = 0;
    while (i < r->live && r->start[i] != ptr) i++;
    if (i == r->live) {
        r->unknown_frees++;
    } else {
        r->live--;
        r->start[i] = r->start[r->live];
        r->bytes[i] = r->bytes[r->live];
        free(ptr);
    }
    pthread_mutex_unlock(&r->lock);
}

/* Whether the allocator block holding p still has every byte it was handed out with. */
static int untouched_block(recording_allocator *r, const void *p)
{
    for (int i = 0; i < r->live; i++) {
        const uint8_t *b = r->start[i];
        if ((const uint8_t *)p < b || (const uint8_t *)p >= b + r->bytes[i]) continue;
        for (size_t k = 0; k < r->bytes[i]; k++)
            if (b[k] != 0xab) return 0;
        return 1;
    }
    fail_msg("no block holds %p", p);
    return 0;
}

static ibl_context *recording_context(recording_allocator *r, int threads)
{
    ibl_context_desc d = {0};
    d.threads = threads;
    d.max_bytes = 64 * MiB;
    d.allocator.alloc = recording_alloc;
    d.allocator.free = recording_free;
    d.allocator.user = r;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    return ctx;
}

typedef struct swap_job {
    ibl_context *ctx;
    void *from_caller[8]; /* freed by the tasks */
    void *from_tasks[8];  /* allocated by them */
} swap_job;

static void swap_task(void *arg, int index)
{
    swap_job *j = arg;
    ibl_free(j->ctx, j->from_caller[index]);
    j->from_tasks[index] = ibl_alloc(j->ctx, MiB + (size_t)index * 4096);
    if (j->from_tasks[index]) memset(j->from_tasks[index], index, MiB);
}

/* Large blocks (64 KiB and more) carry no header: ibl_alloc writes nothing into them, so
 * their first page is first touched by whoever fills it (a small block's header shows that
 * the check sees a write). Their bytes are counted and given back when freed on a pool's
 * thread, allocated on another; through another context they are freed and stay counted in
 * the first; past the context's table of them (256) they take a header and count the same. */
static void large_blocks_keep_no_header(void **state)
{
    (void)state;
    static recording_allocator r = {.lock = PTHREAD_MUTEX_INITIALIZER};
    ibl_context *ctx = recording_context(&r, 2), *other = recording_context(&r, 1);
    uint8_t *small = ibl_alloc(ctx, 1000), *large = ibl_alloc(ctx, 3 * MiB + 5);
    assert_non_null(small);
    assert_non_null(large);
    assert_false(untouched_block(&r, small));
    assert_true(untouched_block(&r, large));
    assert_int_equal(ibl_context_current_bytes(ctx), 1000 + 3 * MiB + 5);

    static swap_job job;
    job.ctx = ctx;
    for (int i = 0; i < 8; i++) assert_non_null(job.from_caller[i] = ibl_alloc(ctx, 2 * MiB + (size_t)i));
    ibl_parallel_for(ctx, 8, swap_task, &job);
    uint64_t tasks_bytes = 0;
    for (int i = 0; i < 8; i++) {
        assert_non_null(job.from_tasks[i]);
        tasks_bytes += MiB + (uint64_t)i * 4096;
    }
    assert_int_equal(ibl_context_current_bytes(ctx), 1000 + 3 * MiB + 5 + tasks_bytes);
    for (int i = 0; i < 8; i++) ibl_free(ctx, job.from_tasks[i]);
    assert_int_equal(ibl_context_current_bytes(ctx), 1000 + 3 * MiB + 5);

    ibl_free(other, large); /* freed, still counted where it was allocated */
    assert_int_equal(ibl_context_current_bytes(ctx), 1000 + 3 * MiB + 5);
    assert_int_equal(ibl_context_current_bytes(other), 0);
    ibl_free(ctx, small);
    assert_int_equal(ibl_context_current_bytes(ctx), 3 * MiB + 5);
    assert_int_equal(r.live, 2); /* the two contexts */

    static void *many[300];
    for (int i = 0; i < 300; i++) assert_non_null(many[i] = ibl_alloc(other, 64 * KiB));
    assert_int_equal(ibl_context_current_bytes(other), 300 * 64 * KiB);
    for (int i = 0; i < 300; i++) ibl_free(other, many[i]);
    assert_int_equal(ibl_context_current_bytes(other), 0);
    ibl_context_destroy(ctx);
    ibl_context_destroy(other);
    assert_int_equal(r.live, 0);
    assert_int_equal(r.unknown_frees, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(budget_counts_the_total),
        cmocka_unit_test(new_pixels_are_zero),
        cmocka_unit_test(parallel_loop_inside_a_task),
        cmocka_unit_test(budget_default),
        cmocka_unit_test(freed_through_another_context),
        cmocka_unit_test(large_blocks_keep_no_header),
        cmocka_unit_test(every_index_once_across_jobs),
        cmocka_unit_test(nested_loop_runs_on_every_thread),
        cmocka_unit_test(nested_loops_every_index_once),
        cmocka_unit_test(budget_across_threads),
        cmocka_unit_test(peak_of_a_read),
        cmocka_unit_test(jpeg_bomb),
        cmocka_unit_test(png_bomb),
        cmocka_unit_test(png_of_zeros),
        cmocka_unit_test(exr_bombs),
        cmocka_unit_test(hdr_bomb),
        cmocka_unit_test(devices_and_pipes),
        cmocka_unit_test(every_reader_checks_the_budget),
        cmocka_unit_test(cli_max_memory_is_a_total),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
