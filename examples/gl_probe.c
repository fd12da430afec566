/* Uploading a probe for shaders/ibl.glsl (see gl_probe.h for the binding table). */
#include "gl_probe.h"

#include <stdlib.h>
#include <string.h>

static void clamp_and_filter(const glh_gl *gl, GLenum target, int levels)
{
    gl->TexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl->TexParameteri(target, GL_TEXTURE_MIN_FILTER,
                      levels > 1 ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR);
    gl->TexParameteri(target, GL_TEXTURE_BASE_LEVEL, 0);
    /* a chain that stops above 1x1 (e.g. at 4x4) is complete with MAX_LEVEL set */
    gl->TexParameteri(target, GL_TEXTURE_MAX_LEVEL, levels - 1);
}

GLuint glp_cube_texture(const glh_gl *gl, const ibl_cubemap *cube, int levels)
{
    GLuint t;
    gl->GenTextures(1, &t);
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, t);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (int k = 0; k < levels; k++) {
        int n = ibl_level_size(cube->size, k);
        /* ibl's faces are OpenGL's: +X -X +Y -Y +Z -Z, row 0 at t = 0 (cubemap.h) */
        for (int f = 0; f < 6; f++)
            gl->TexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)f, k, GL_RGBA32F, n, n, 0,
                           GL_RGBA, GL_FLOAT, ibl_cubemap_face(cube, k, f));
    }
    clamp_and_filter(gl, GL_TEXTURE_CUBE_MAP, levels);
    return t;
}

GLuint glp_image_texture(const glh_gl *gl, const ibl_image *im)
{
    GLuint t;
    gl->GenTextures(1, &t);
    gl->BindTexture(GL_TEXTURE_2D, t);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, im->width, im->height, 0, GL_RGBA, GL_FLOAT,
                   im->pixels);
    clamp_and_filter(gl, GL_TEXTURE_2D, 1);
    return t;
}

/* A table of `channels` floats per texel as RGBA32F (missing channels 0, alpha 1). */
static GLuint table_texture(const glh_gl *gl, GLenum target, const float *data, int channels,
                            int w, int h, int d)
{
    size_t count = (size_t)w * h * d;
    float *rgba = malloc(count * 4 * sizeof(float));
    if (!rgba) return 0;
    int ch = channels > 4 ? 4 : channels;
    for (size_t i = 0; i < count; i++)
        for (int c = 0; c < 4; c++)
            rgba[i * 4 + c] = c < ch ? data[i * (size_t)channels + c] : (c == 3 ? 1.0f : 0.0f);
    GLuint t;
    gl->GenTextures(1, &t);
    gl->BindTexture(target, t);
    if (target == GL_TEXTURE_3D)
        gl->TexImage3D(target, 0, GL_RGBA32F, w, h, d, 0, GL_RGBA, GL_FLOAT, rgba);
    else
        gl->TexImage2D(target, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, rgba);
    clamp_and_filter(gl, target, 1);
    free(rgba);
    return t;
}

ibl_status glp_probe_upload(const glh_gl *gl, ibl_context *ctx, const ibl_probe *p,
                            glp_probe *out)
{
    memset(out, 0, sizeof *out);
    ibl_status st = ibl_shader_probe_fill(ctx, p, &out->data);
    if (st != IBL_OK) return st;
    gl->Enable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
    /* the empty parts are 1x1 black so every sampler is complete */
    static const float black[6 * 4] = {0};
    ibl_cubemap none = {.size = 1, .levels = 1, .data = (float *)black};
    out->texture[GLP_UNIT_SPECULAR] = glp_cube_texture(gl, &p->specular, p->specular.levels);
    out->texture[GLP_UNIT_MIRROR] = glp_cube_texture(gl, p->mirror.data ? &p->mirror : &none, 1);
    out->texture[GLP_UNIT_IRRADIANCE] =
        glp_cube_texture(gl, p->irradiance.data ? &p->irradiance : &none, 1);
    const ibl_splitsum_view *ss = &p->splitsum;
    out->texture[GLP_UNIT_SPLITSUM] =
        ss->data ? table_texture(gl, GL_TEXTURE_2D, ss->data, ss->channels ? ss->channels : 2,
                                 ss->n_dot_v.count, ss->roughness.count, 1)
                 : table_texture(gl, GL_TEXTURE_2D, black, 4, 1, 1, 1);
    const ibl_ambient_brdf_view *ab = &p->ambient_brdf;
    out->texture[GLP_UNIT_AMBIENT_BRDF] =
        ab->data ? table_texture(gl, GL_TEXTURE_3D, ab->data, ab->channels ? ab->channels : 1,
                                 ab->n_dot_v.count, ab->shininess.count, ab->f0.count)
                 : table_texture(gl, GL_TEXTURE_3D, black, 4, 1, 1, 1);
    gl->GenBuffers(1, &out->block);
    gl->BindBuffer(GL_UNIFORM_BUFFER, out->block);
    gl->BufferData(GL_UNIFORM_BUFFER, sizeof out->data, &out->data, GL_STATIC_DRAW);
    for (int i = 0; i < GLP_UNIT_COUNT; i++)
        if (!out->texture[i] || gl->GetError() != GL_NO_ERROR) {
            glp_probe_free(gl, out);
            return IBL_ERR_OUT_OF_MEMORY;
        }
    return IBL_OK;
}

void glp_probe_bind(const glh_gl *gl, const glp_probe *p)
{
    static const GLenum targets[GLP_UNIT_COUNT] = {GL_TEXTURE_CUBE_MAP, GL_TEXTURE_CUBE_MAP,
                                                   GL_TEXTURE_CUBE_MAP, GL_TEXTURE_2D,
                                                   GL_TEXTURE_3D};
    for (int i = 0; i < GLP_UNIT_COUNT; i++) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)i);
        gl->BindTexture(targets[i], p->texture[i]);
    }
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, GLP_BLOCK_PROBE, p->block);
}

void glp_probe_free(const glh_gl *gl, glp_probe *p)
{
    for (int i = 0; i < GLP_UNIT_COUNT; i++)
        if (p->texture[i]) gl->DeleteTextures(1, &p->texture[i]);
    if (p->block) gl->DeleteBuffers(1, &p->block);
    memset(p, 0, sizeof *p);
}
