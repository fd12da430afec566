/* Tiled culling on the GPU (shaders/ibl_probe_cull.comp) over bench/probe_level.h's level:
 * 64 volumes, 1920x1080, 16x16 tiles, each of the write-up's three per-tile sorts,
 * conservative and exact; wall time of one dispatch to glFinish (best of REPEATS), the list
 * entries and the comparisons the sorts made, and whether the lists equal ibl_cull_probes's.
 * Headless OpenGL 4.5 through tests/support/gl_harness (on this machine: Mesa llvmpipe).
 *
 *   bench_probes_gpu [REPEATS]   (default 10) */
#include "gl_harness.h"
#include "ibl/probes.h"
#include "probe_level.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

typedef struct record { /* probes.bin's std430 layout (docs/PROBES.md), 240 bytes */
    float position_size[4], influence_center_radius[4], influence_half_extent_blend[4];
    float proxy_center_radius[4], proxy_half_extent_coverage[4];
    int32_t shapes_layer_priority[4];
    float sh[9][4];
} record;

static GLuint storage(const glh_gl *gl, const void *data, size_t bytes)
{
    GLuint b;
    gl->GenBuffers(1, &b);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)bytes, data, GL_DYNAMIC_DRAW);
    return b;
}

int main(int argc, char **argv)
{
    int repeats = argc > 1 ? atoi(argv[1]) : 10;
    glh_context c;
    char why[512];
    if (glh_create(&c, why, sizeof why) != 0) {
        fprintf(stderr, "bench_probes_gpu: %s\n", why);
        return 1;
    }
    const glh_gl *gl = &c.gl;
    char *src = glh_read_text(IBL_SHADER_SOURCE_DIR "/ibl_probe_cull.comp");
    const char *srcs[1] = {src};
    GLenum type = GL_COMPUTE_SHADER;
    char log[4096] = "";
    GLuint prog = src ? glh_program(&c, log, sizeof log, 1, &type, srcs) : 0;
    free(src);
    if (!prog) {
        fprintf(stderr, "bench_probes_gpu: ibl_probe_cull.comp: %s\n", log);
        return 1;
    }
    ibl_camera cam = level_camera();
    float *depth = level_depth(&cam);
    ibl_volume v[LEVEL_PROBES];
    level_volumes(v);
    record rec[LEVEL_PROBES];
    memset(rec, 0, sizeof rec);
    for (int i = 0; i < LEVEL_PROBES; i++) {
        float *cr = rec[i].influence_center_radius, *hb = rec[i].influence_half_extent_blend;
        cr[0] = v[i].center.x, cr[1] = v[i].center.y, cr[2] = v[i].center.z;
        cr[3] = v[i].shape == IBL_VOLUME_SPHERE ? v[i].radius : 0.0f;
        hb[0] = v[i].half_extent.x, hb[1] = v[i].half_extent.y, hb[2] = v[i].half_extent.z;
        rec[i].shapes_layer_priority[0] = v[i].shape == IBL_VOLUME_BOX;
        rec[i].shapes_layer_priority[2] = i;
    }
    int tx = (LEVEL_W + 15) / 16, ty = (LEVEL_H + 15) / 16, cap = LEVEL_PROBES;
    GLuint b[5];
    b[0] = storage(gl, rec, sizeof rec);
    b[1] = storage(gl, depth, sizeof(float) * LEVEL_W * LEVEL_H);
    b[2] = storage(gl, NULL, sizeof(int) * (size_t)tx * ty * cap);
    b[3] = storage(gl, NULL, sizeof(int) * (size_t)tx * ty);
    unsigned zero = 0;
    b[4] = storage(gl, &zero, sizeof zero);
    for (int i = 0; i < 5; i++) gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)i, b[i]);
    gl->UseProgram(prog);
    ibl_vec3 r, u, f;
    ibl_camera_basis(&cam, &r, &u, &f);
    float tany = tanf(cam.fov_y_degrees * 0.5f * 3.14159265358979f / 180.0f);
    float vecs[4][4] = {{cam.position.x, cam.position.y, cam.position.z, 0}, {r.x, r.y, r.z, 0},
                        {u.x, u.y, u.z, 0}, {f.x, f.y, f.z, 0}};
    const char *names[4] = {"u_position", "u_right", "u_up", "u_forward"};
    for (int i = 0; i < 4; i++) gl->Uniform4fv(gl->GetUniformLocation(prog, names[i]), 1, vecs[i]);
    gl->Uniform2f(gl->GetUniformLocation(prog, "u_tan"), tany * LEVEL_W / LEVEL_H, tany);
    gl->Uniform2i(gl->GetUniformLocation(prog, "u_size"), LEVEL_W, LEVEL_H);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_count"), LEVEL_PROBES);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_capacity"), cap);
    int *lists = malloc(sizeof(int) * (size_t)tx * ty * cap), *lengths = malloc(sizeof(int) * (size_t)tx * ty);
    ibl_context *ctx;
    ibl_context_create(&(ibl_context_desc){.threads = 1}, &ctx);
    static const char *sorts[3] = {"odd-even", "rank", "rank-copy"};
    printf("GPU tiled culling (%s), %d probes, %dx%d, 16x16 tiles, best of %d\n", c.renderer,
           LEVEL_PROBES, LEVEL_W, LEVEL_H, repeats);
    for (int exact = 0; exact < 2; exact++)
        for (int k = 0; k < 3; k++) {
            gl->Uniform1i(gl->GetUniformLocation(prog, "u_sort"), k);
            gl->Uniform1i(gl->GetUniformLocation(prog, "u_exact"), exact);
            double best = 1e30;
            unsigned compares = 0;
            for (int rep = 0; rep < repeats; rep++) {
                gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[4]);
                gl->BufferData(GL_SHADER_STORAGE_BUFFER, sizeof zero, &zero, GL_DYNAMIC_DRAW);
                gl->Finish();
                double t0 = now_ms();
                gl->DispatchCompute((GLuint)tx, (GLuint)ty, 1);
                gl->Finish();
                double t = now_ms() - t0;
                best = t < best ? t : best;
                gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
                gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof compares, &compares);
            }
            gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[2]);
            gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(int) * (size_t)tx * ty * cap), lists);
            gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[3]);
            gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(int) * (size_t)tx * ty), lengths);
            ibl_cull_desc d = {.tile_size = 16, .sort = (ibl_tile_sort)k, .exact = exact};
            ibl_tile_lists l;
            ibl_cull_stats st;
            ibl_cull_probes(ctx, &cam, depth, v, LEVEL_PROBES, &d, &l, &st);
            long long entries = 0;
            int same = 1;
            for (int t = 0; t < tx * ty; t++) {
                int n = l.offsets[t + 1] - l.offsets[t];
                entries += lengths[t];
                if (lengths[t] != n || memcmp(lists + (size_t)t * cap, l.indices + l.offsets[t], sizeof(int) * (size_t)n))
                    same = 0;
            }
            ibl_tile_lists_free(ctx, &l);
            printf("  %-12s %-9s %8.2f ms  entries %lld  compares %u  %s\n", exact ? "exact" : "conservative",
                   sorts[k], best, entries, compares, same ? "= C lists" : "DIFFERS from the C lists");
        }
    ibl_context_destroy(ctx);
    free(lists);
    free(lengths);
    free(depth);
    gl->DeleteBuffers(5, b);
    gl->DeleteProgram(prog);
    glh_destroy(&c);
    return 0;
}
