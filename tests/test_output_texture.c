/* A texture written level by level (ibl_output_set_begin_texture, src/io/output_texture.c)
 * against the same texture written whole (ibl_encode_texture): the same bytes for every
 * texel format, a block format and a 2D texture of odd edges, whatever the order the levels
 * come in and however many threads give them at once; the same count of clamped texels. And
 * what goes wrong: a level given twice or out of range, a level never given, a
 * supercompressed or non-KTX2 file, a cancelled writer, a commit while a writer is open --
 * none of which leaves a file behind or touches the target. */
#include "test_io_helpers.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A texture with texels past the largest half (65504) and past the RGBM range, so the
 * formats clamp; seed varies it. */
static ibl_texture make_texture(ibl_context *ctx, ibl_texture_kind kind, int width, int height,
                                int levels, unsigned seed)
{
    ibl_texture t = {0};
    t.kind = kind;
    t.width = width;
    t.height = height;
    t.depth = 1;
    t.levels = levels;
    size_t floats = ibl_texture_floats(kind, width, height, 1, levels);
    t.data = ibl_alloc(ctx, floats * sizeof(float));
    assert_non_null(t.data);
    for (size_t i = 0; i < floats; i += 4) {
        unsigned h = (unsigned)(i * 2654435761u) ^ seed;
        float v = (float)(h % 10007) / 97.0f;
        if (h % 4099 == 3) v = 70000.0f + (float)(h % 7);
        t.data[i + 0] = v;
        t.data[i + 1] = 0.5f * v + 0.25f;
        t.data[i + 2] = (float)((h >> 8) % 1000) / 999.0f;
        t.data[i + 3] = 1.0f;
    }
    assert_int_equal(ibl_texture_set_metadata(ctx, &t, "ibl.test", "level by level"), IBL_OK);
    return t;
}

typedef struct give_job {
    ibl_output_texture *writer;
    const ibl_texture *tex;
    const int *order;
    ibl_status status[IBL_MAX_LEVELS];
} give_job;

static void give_task(void *arg, int index)
{
    give_job *j = arg;
    int l = j->order[index];
    j->status[index] = ibl_output_texture_level(j->writer, l, ibl_texture_level(j->tex, l, 0));
}

/* Writes tex level by level (in `order`, all at once on ctx's threads) into path. */
static void write_by_levels(ibl_context *ctx, const char *path, const ibl_texture *tex,
                            const ibl_write_desc *wd, const int *order)
{
    ibl_output_set *set;
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    ibl_output_texture *w;
    ibl_texture shape = *tex;
    shape.data = NULL; /* the shape alone: the texels come with the levels */
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, wd, &w), IBL_OK);
    give_job j = {w, tex, order, {0}};
    ibl_parallel_for(ctx, tex->levels, give_task, &j);
    for (int l = 0; l < tex->levels; l++) assert_int_equal(j.status[l], IBL_OK);
    assert_int_equal(ibl_output_texture_finish(w), IBL_OK);
    assert_int_equal(ibl_output_set_commit(set), IBL_OK);
    ibl_output_set_destroy(set);
}

static void level_by_level_matches_the_whole_write(void **state)
{
    (void)state;
    ibl_context *one = test_context(1), *two = test_context(3);
    const ibl_format formats[] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RGBA32F, IBL_FORMAT_RG11B10F,
                                  IBL_FORMAT_RGB9E5,  IBL_FORMAT_RGBM,    IBL_FORMAT_BC6H};
    struct {
        ibl_texture_kind kind;
        int width, height, levels;
    } shapes[] = {{IBL_TEXTURE_CUBE, 64, 64, 7}, {IBL_TEXTURE_2D, 37, 19, 6}};
    const int in_order[] = {0, 1, 2, 3, 4, 5, 6}, scrambled[] = {3, 0, 6, 1, 5, 2, 4};
    const int scrambled6[] = {5, 2, 0, 4, 1, 3};
    const char *path = test_path("by_levels.ktx2");
    for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
        ibl_texture tex = make_texture(one, shapes[s].kind, shapes[s].width, shapes[s].height,
                                       shapes[s].levels, (unsigned)s * 77u);
        for (size_t k = 0; k < sizeof formats / sizeof formats[0]; k++) {
            ibl_write_report want_report = {0};
            ibl_write_desc wd = {.format = formats[k], .report = &want_report};
            void *want;
            size_t want_size;
            assert_int_equal(ibl_encode_texture(one, IBL_FILE_KTX2, &tex, &wd, &want, &want_size), IBL_OK);
            for (int variant = 0; variant < 2; variant++) {
                ibl_write_report got_report = {0};
                wd.report = &got_report;
                const int *order = variant == 0 ? in_order : tex.levels == 7 ? scrambled : scrambled6;
                write_by_levels(variant == 0 ? one : two, path, &tex, &wd, order);
                size_t got_size;
                uint8_t *got = slurp(path, &got_size);
                assert_int_equal(got_size, want_size);
                assert_memory_equal(got, want, want_size);
                assert_int_equal(got_report.clamped_texels, want_report.clamped_texels);
                free(got);
            }
            if (s == 0 && (formats[k] == IBL_FORMAT_RGBA16F || formats[k] == IBL_FORMAT_RGBM))
                assert_true(want_report.clamped_texels > 0);
            ibl_free(one, want);
        }
        ibl_texture_free(one, &tex);
    }
    remove(path);
    ibl_context_destroy(two);
    ibl_context_destroy(one);
}

/* The folder's entries whose name starts with prefix. */
static int count_entries(const char *folder, const char *prefix)
{
    DIR *d = opendir(folder);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
    closedir(d);
    return n;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void refusals_leave_the_target_alone(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_texture tex = make_texture(ctx, IBL_TEXTURE_CUBE, 16, 16, 5, 5u);
    ibl_texture shape = tex;
    shape.data = NULL;
    char folder[600], path[700];
    snprintf(folder, sizeof folder, "%s", test_path("by_levels_refusals"));
    mkdir(folder, 0777);
    snprintf(path, sizeof path, "%s/chain.ktx2", folder);
    write_text(path, "the old file");
    ibl_output_set *set;
    ibl_output_texture *w;

    /* a level twice, out of range, never given: refused by name, nothing committed */
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, NULL, &w), IBL_OK);
    assert_int_equal(ibl_output_texture_level(w, 1, ibl_texture_level(&tex, 1, 0)), IBL_OK);
    assert_int_equal(ibl_output_texture_level(w, 1, ibl_texture_level(&tex, 1, 0)), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "level 1 written twice"));
    assert_int_equal(ibl_output_texture_level(w, 5, ibl_texture_level(&tex, 1, 0)), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "chain.ktx2: level 5 of a texture of 5 levels"));
    assert_int_equal(ibl_output_set_commit(set), IBL_ERR_INVALID_ARGUMENT); /* still open */
    assert_non_null(strstr(ibl_context_message(ctx), "still being written"));
    assert_int_equal(ibl_output_texture_finish(w), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "chain.ktx2: level 0 was never written"));
    assert_int_equal(ibl_output_set_commit(set), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "not completely written"));
    ibl_output_set_destroy(set);

    /* cancelled: the same */
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, NULL, &w), IBL_OK);
    for (int l = 0; l < tex.levels; l++)
        assert_int_equal(ibl_output_texture_level(w, l, ibl_texture_level(&tex, l, 0)), IBL_OK);
    ibl_output_texture_cancel(w);
    assert_int_equal(ibl_output_set_commit(set), IBL_ERR_INVALID_ARGUMENT);
    ibl_output_set_destroy(set);

    /* a writer the set is destroyed around (the caller's error path skipped the finish) */
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, NULL, &w), IBL_OK);
    ibl_output_set_destroy(set);
    ibl_output_texture_cancel(NULL);

    /* files it cannot lay out before their texels: supercompressed, or not a KTX2 */
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    ibl_write_desc zstd = {.zstd_level = 3};
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, &zstd, &w), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "no supercompression"));
    assert_null(w);
    char dds[700];
    snprintf(dds, sizeof dds, "%s/chain.dds", folder);
    assert_int_equal(ibl_output_set_begin_texture(set, dds, &shape, NULL, &w), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "chain.dds: only a .ktx2"));
    ibl_texture bad = shape;
    bad.height = 8; /* a cube's faces are square */
    assert_int_equal(ibl_output_set_begin_texture(set, path, &bad, NULL, &w), IBL_ERR_INVALID_ARGUMENT);
    ibl_output_set_destroy(set);

    size_t size;
    uint8_t *old = slurp(path, &size);
    assert_int_equal(size, strlen("the old file"));
    assert_memory_equal(old, "the old file", size);
    free(old);
    assert_int_equal(count_entries(folder, ".chain.ktx2.tmp"), 0);

    /* and a complete one replaces it */
    assert_int_equal(ibl_output_set_create(ctx, &set), IBL_OK);
    assert_int_equal(ibl_output_set_begin_texture(set, path, &shape, NULL, &w), IBL_OK);
    for (int l = tex.levels - 1; l >= 0; l--)
        assert_int_equal(ibl_output_texture_level(w, l, ibl_texture_level(&tex, l, 0)), IBL_OK);
    assert_int_equal(ibl_output_texture_finish(w), IBL_OK);
    assert_int_equal(ibl_output_set_commit(set), IBL_OK);
    ibl_output_set_destroy(set);
    ibl_texture back;
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &back, NULL), IBL_OK);
    assert_int_equal(back.levels, tex.levels);
    assert_string_equal(ibl_texture_get_metadata(&back, "ibl.test"), "level by level");
    ibl_texture_free(ctx, &back);
    assert_int_equal(count_entries(folder, ".chain.ktx2.tmp"), 0);
    remove(path);
    rmdir(folder);
    ibl_texture_free(ctx, &tex);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(level_by_level_matches_the_whole_write),
        cmocka_unit_test(refusals_leave_the_target_alone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
