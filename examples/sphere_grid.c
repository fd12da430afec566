/* The sphere grid on the GPU (see sphere_grid.h). */
#include "sphere_grid.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char vertex_shader[] =
    "#version 450 core\n"
    "void main() {\n" /* one triangle covering the screen, no vertex buffer */
    "  vec2 p = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));\n"
    "  gl_Position = vec4(p, 0.0, 1.0);\n"
    "}\n";

/* render.c's framing: at least 2 units above and below, 4.3 to each side at z = 0 */
static void framing(int w, int h, float *half_w, float *half_h)
{
    float aspect = (float)w / (float)h;
    *half_h = 2.0f;
    if (*half_h * aspect < 4.3f) *half_h = 4.3f / aspect;
    *half_w = *half_h * aspect;
}

static void set_materials(const glh_gl *gl, GLuint prog)
{
    ibl_render_object objects[64];
    int n = ibl_render_scene_objects(objects, 64);
    float params[21][4], base[21][4], f0[21][4];
    memset(params, 0, sizeof params);
    memset(base, 0, sizeof base);
    memset(f0, 0, sizeof f0);
    for (int i = 0; i < n && i < 21; i++) {
        const ibl_material *m = &objects[i].material;
        params[i][0] = (float)m->model;
        params[i][1] = m->metallic;
        params[i][2] = m->roughness;
        params[i][3] = m->shininess;
        memcpy(base[i], m->base_color, sizeof m->base_color);
        memcpy(f0[i], m->f0, sizeof m->f0);
    }
    gl->Uniform4fv(gl->GetUniformLocation(prog, "u_params"), 21, &params[0][0]);
    gl->Uniform4fv(gl->GetUniformLocation(prog, "u_base"), 21, &base[0][0]);
    gl->Uniform4fv(gl->GetUniformLocation(prog, "u_f0"), 21, &f0[0][0]);
}

ibl_status sg_render(const glh_context *c, ibl_context *ctx, const glp_probe *probe,
                     const ibl_shader_lights *lights, const char *ibl_glsl, const char *frag,
                     int w, int h, ibl_image *out, unsigned char *hit, char *log,
                     size_t log_size)
{
    const glh_gl *gl = &c->gl;
    memset(out, 0, sizeof *out);
    size_t len = strlen(ibl_glsl) + strlen(frag) + 64;
    char *src = malloc(len);
    if (!src) return IBL_ERR_OUT_OF_MEMORY;
    snprintf(src, len, "#version 450 core\n%s\n%s", ibl_glsl, frag);
    const GLenum types[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
    const char *sources[2] = {vertex_shader, src};
    GLuint prog = glh_program(c, log, log_size, 2, types, sources);
    free(src);
    if (!prog) return IBL_ERR_INVALID_ARGUMENT;
    ibl_status st = ibl_image_alloc(ctx, w, h, out);
    float *rows = st == IBL_OK ? malloc((size_t)w * h * 4 * sizeof(float)) : NULL;
    if (!rows) {
        gl->DeleteProgram(prog);
        ibl_image_free(ctx, out);
        return IBL_ERR_OUT_OF_MEMORY;
    }
    GLuint target, fbo, vao, light_block;
    ibl_shader_lights none;
    memset(&none, 0, sizeof none);
    gl->GenBuffers(1, &light_block);
    gl->BindBuffer(GL_UNIFORM_BUFFER, light_block);
    gl->BufferData(GL_UNIFORM_BUFFER, sizeof none, lights ? lights : &none, GL_STATIC_DRAW);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, 2, light_block);
    gl->GenTextures(1, &target);
    gl->BindTexture(GL_TEXTURE_2D, target);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, NULL);
    gl->GenFramebuffers(1, &fbo);
    gl->BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl->FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, target, 0);
    if (gl->CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        st = IBL_ERR_UNSUPPORTED;
    gl->GenVertexArrays(1, &vao);
    gl->BindVertexArray(vao);
    gl->Viewport(0, 0, w, h);
    gl->UseProgram(prog);
    glp_probe_bind(gl, probe);
    float hw, hh;
    framing(w, h, &hw, &hh);
    gl->Uniform2f(gl->GetUniformLocation(prog, "u_size"), (float)w, (float)h);
    gl->Uniform2f(gl->GetUniformLocation(prog, "u_half"), hw, hh);
    set_materials(gl, prog);
    gl->DrawArrays(GL_TRIANGLES, 0, 3);
    gl->PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl->ReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, rows);
    if (gl->GetError() != GL_NO_ERROR) st = IBL_ERR_UNSUPPORTED;
    /* OpenGL's row 0 is the bottom one; ibl_image's is the top */
    for (int y = 0; y < h && st == IBL_OK; y++)
        for (int x = 0; x < w; x++) {
            const float *s = rows + ((size_t)(h - 1 - y) * w + x) * 4;
            float *d = ibl_image_texel(out, x, y);
            memcpy(d, s, 3 * sizeof(float));
            d[3] = 1.0f;
            if (hit) hit[(size_t)y * w + x] = s[3] > 0.5f;
        }
    gl->UseProgram(0);
    gl->BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl->DeleteVertexArrays(1, &vao);
    gl->DeleteBuffers(1, &light_block);
    gl->DeleteFramebuffers(1, &fbo);
    gl->DeleteTextures(1, &target);
    gl->DeleteProgram(prog);
    free(rows);
    if (st != IBL_OK) ibl_image_free(ctx, out);
    return st;
}
