/* The starting corpora of the block-reader targets (fuzz/fuzz_decode.c: fuzz_bc6h_blocks,
 * fuzz_astc_blocks): a 2-byte header (columns of blocks - 1, BC6H signedness, ASTC footprint,
 * texels cut from the last column and row) and whole 16-byte blocks. BC6H: the test vectors
 * of every mode, signed and unsigned (ibl_bc6h_test_vectors), and encoder blocks of a padded
 * gradient at each quality; ASTC: astcenc's blocks of a padded HDR gradient at every
 * footprint. Usage: blocks OUT_DIR (writes OUT_DIR/bc6h and OUT_DIR/astc). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ibl/ibl.h"

static int write_input(const char *dir, const char *name, uint8_t h0, uint8_t h1, const uint8_t *blocks,
                       size_t count)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.bin", dir, name);
    FILE *f = fopen(path, "wb");
    uint8_t head[2] = {h0, h1};
    int bad = !f || fwrite(head, 1, 2, f) != 2 || fwrite(blocks, 16, count, f) != count;
    if (f && fclose(f) != 0) bad = 1;
    if (bad) fprintf(stderr, "cannot write %s\n", path);
    return bad;
}

/* An HDR gradient with a bright corner: w x h RGBA. */
static float *gradient(int w, int h)
{
    float *p = malloc((size_t)w * (size_t)h * 4 * sizeof *p);
    if (!p) return NULL;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *t = p + ((size_t)y * (size_t)w + (size_t)x) * 4;
            t[0] = 0.01f + (float)x * 0.3f;
            t[1] = 0.2f + (float)(x * y) * 0.05f;
            t[2] = (x + y) % 5 == 0 ? 900.0f : 0.5f;
            t[3] = 1.0f;
        }
    return p;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: blocks OUT_DIR\n");
        return 2;
    }
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) return 1;
    char bc6h[1024], astc[1024];
    snprintf(bc6h, sizeof bc6h, "%s/bc6h", argv[1]);
    snprintf(astc, sizeof astc, "%s/astc", argv[1]);
    int bad = 0;
    uint8_t blocks[64 * 16];
    uint16_t halves[64 * 48];
    for (int s = 0; s < 2; s++) /* 56 vectors: every mode four times, as 8 x 7 blocks */
        for (int seed = 0; seed < 2; seed++) {
            char name[64];
            ibl_bc6h_test_vectors((uint64_t)(seed + 1), 56, s, blocks, halves);
            snprintf(name, sizeof name, "vectors_%s_%d", s ? "signed" : "unsigned", seed);
            bad |= write_input(bc6h, name, (uint8_t)(7 | s << 4), 0, blocks, 56);
        }
    float *g = gradient(14, 11); /* 4 x 3 blocks of 4x4, the last column and row cut */
    for (int q = 0; q < 3 && g; q++)
        for (int s = 0; s < 2; s++) {
            ibl_bc6h_desc d = {s, (ibl_quality)q};
            char name[64];
            if (ibl_bc6h_encode(ctx, &d, g, 14, 11, blocks) != IBL_OK) return 1;
            snprintf(name, sizeof name, "gradient_%s_%s", ibl_quality_name((ibl_quality)q), s ? "signed" : "unsigned");
            bad |= write_input(bc6h, name, (uint8_t)(3 | s << 4), (uint8_t)(2 | 1 << 3), blocks, 12);
        }
    free(g);
    static const int footprints[8][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
    for (int i = 0; i < 8; i++) {
        int bw = footprints[i][0], bh = footprints[i][1], w = 3 * bw - 1, h = 2 * bh - 1;
        float *p = gradient(w, h);
        ibl_astc_desc d = {bw, bh, IBL_QUALITY_FAST};
        char name[64];
        if (!p || ibl_astc_encode(ctx, &d, p, w, h, blocks) != IBL_OK) return 1;
        snprintf(name, sizeof name, "gradient_%dx%d", bw, bh);
        bad |= write_input(astc, name, (uint8_t)(2 | i << 5), (uint8_t)(1 | 1 << 3), blocks, 6);
        free(p);
    }
    ibl_context_destroy(ctx);
    return bad;
}
