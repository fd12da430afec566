/* glTF 2.0 scenes through Assimp's C API (Debian libassimp-dev 5.2; cimport.h): every mesh,
 * with the node transforms applied (aiProcess_PreTransformVertices), triangulated, with
 * smooth normals where the file has none, and the metal/roughness materials (glTF 2.0
 * specification, section 3.9 "Materials"). Assimp 5.2 does not read
 * KHR_materials_emissive_strength, so this file reads that one number from the glTF JSON
 * itself (jansson) and multiplies the emissive factor by it: without it, emission is capped
 * at 1, far below the daylight of the built-in sky. Images are read with the library's own
 * readers (PNG and JPEG are decoded from sRGB, which base colour and emission are). */
#include "scene_internal.h"
#include "ibl/io.h"
#include "core/context_internal.h"
#include "io/json.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct loader {
    ibl_context *ctx;
    ibl__assimp api; /* loaded for the import (libraries.h) */
    const char *path;
    const struct aiScene *ai;
    double *strengths;   /* emissive strength per glTF material (1 without the extension) */
    int strength_count;
    ibl_image *textures;
    char (*texture_names)[512];
    int texture_count, texture_cap;
    int obj; /* a Wavefront OBJ (ibl_scene_load), not glTF */
} loader;

/* ---- KHR_materials_emissive_strength, from the JSON of a .gltf or the JSON chunk of a .glb - */

static ibl_status read_strengths(loader *l)
{
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(l->ctx, l->path, &bytes, &size);
    if (st != IBL_OK) return st;
    const unsigned char *b = bytes;
    const void *json = bytes;
    size_t json_size = size;
    if (size >= 20 && memcmp(b, "glTF", 4) == 0) { /* GLB: header, then the JSON chunk */
        uint32_t len = (uint32_t)b[12] | (uint32_t)b[13] << 8 | (uint32_t)b[14] << 16 |
                       (uint32_t)b[15] << 24;
        json = b + 20;
        json_size = len <= size - 20 ? len : size - 20;
    }
    json_t *root = NULL;
    if (l->obj) { /* Wavefront OBJ: no JSON, no emissive strengths */
        ibl_free(l->ctx, bytes);
        l->strengths = ibl_alloc(l->ctx, sizeof(double));
        return l->strengths ? IBL_OK : IBL_ERR_OUT_OF_MEMORY;
    }
    st = ibl__json_parse(l->ctx, json, json_size, l->path, &root);
    ibl_free(l->ctx, bytes);
    if (st != IBL_OK) return st;
    json_t *mats = json_object_get(root, "materials");
    size_t n = json_is_array(mats) ? json_array_size(mats) : 0;
    l->strengths = ibl_alloc(l->ctx, (n + 1) * sizeof(double));
    if (!l->strengths) {
        json_decref(root);
        return IBL_ERR_OUT_OF_MEMORY;
    }
    l->strength_count = (int)n;
    for (size_t i = 0; i < n; i++) {
        json_t *s = json_object_get(
            json_object_get(json_object_get(json_array_get(mats, i), "extensions"),
                            "KHR_materials_emissive_strength"),
            "emissiveStrength");
        l->strengths[i] = json_is_number(s) && json_number_value(s) >= 0 ? json_number_value(s) : 1.0;
    }
    json_decref(root);
    return IBL_OK;
}

/* ---- textures ------------------------------------------------------------------------------ */

static ibl_status texture_from_memory(loader *l, const struct aiTexture *t, ibl_image *out)
{
    if (t->mHeight != 0)
        return ibl__fail(l->ctx, IBL_ERR_UNSUPPORTED, "%s: uncompressed embedded textures are "
                         "not supported", l->path);
    ibl_texture tex;
    ibl_status st = ibl_decode_texture(l->ctx, t->pcData, t->mWidth, l->path, NULL, &tex, NULL);
    if (st != IBL_OK) return st;
    st = ibl_image_alloc(l->ctx, tex.width, tex.height, out);
    if (st == IBL_OK)
        memcpy(out->pixels, ibl_texture_level(&tex, 0, 0), (size_t)tex.width * tex.height * 16);
    ibl_texture_free(l->ctx, &tex);
    return st;
}

/* "*N" names the file's N-th embedded image (aiScene::GetEmbeddedTexture is C++ only) */
static const struct aiTexture *embedded_texture(const struct aiScene *s, const char *name)
{
    if (name[0] == '*') {
        char *end;
        long i = strtol(name + 1, &end, 10);
        return *end == '\0' && i >= 0 && i < (long)s->mNumTextures ? s->mTextures[i] : NULL;
    }
    for (unsigned i = 0; i < s->mNumTextures; i++)
        if (strcmp(s->mTextures[i]->mFilename.data, name) == 0) return s->mTextures[i];
    return NULL;
}

/* Index of the material's texture of a type (loaded once per file), or -1. */
static ibl_status texture_index(loader *l, const struct aiMaterial *m, enum aiTextureType type,
                                int *index)
{
    *index = -1;
    struct aiString name;
    if (l->api.aiGetMaterialTexture(m, type, 0, &name, NULL, NULL, NULL, NULL, NULL, NULL) != aiReturn_SUCCESS)
        return IBL_OK;
    for (int i = 0; i < l->texture_count; i++)
        if (strcmp(l->texture_names[i], name.data) == 0) {
            *index = i;
            return IBL_OK;
        }
    if (l->texture_count == l->texture_cap) {
        int cap = l->texture_cap ? 2 * l->texture_cap : 8;
        ibl_image *t = ibl_calloc(l->ctx, (size_t)cap, sizeof *t);
        char(*n)[512] = ibl_calloc(l->ctx, (size_t)cap, sizeof *n);
        if (!t || !n) {
            ibl_free(l->ctx, t);
            ibl_free(l->ctx, n);
            return IBL_ERR_OUT_OF_MEMORY;
        }
        if (l->texture_count) {
            memcpy(t, l->textures, (size_t)l->texture_count * sizeof *t);
            memcpy(n, l->texture_names, (size_t)l->texture_count * sizeof *n);
        }
        ibl_free(l->ctx, l->textures);
        ibl_free(l->ctx, l->texture_names);
        l->textures = t;
        l->texture_names = n;
        l->texture_cap = cap;
    }
    ibl_image *im = &l->textures[l->texture_count];
    ibl_status st;
    const struct aiTexture *embedded = embedded_texture(l->ai, name.data);
    if (strlen(name.data) >= sizeof l->texture_names[0])
        return ibl__fail(l->ctx, IBL_ERR_UNSUPPORTED, "%s: texture name too long", l->path);
    if (embedded) st = texture_from_memory(l, embedded, im);
    else {
        char full[1024];
        const char *slash = strrchr(l->path, '/');
        int dir_len = slash ? (int)(slash - l->path) + 1 : 0;
        if (snprintf(full, sizeof full, "%.*s%s", dir_len, l->path, name.data) >= (int)sizeof full)
            return ibl__fail(l->ctx, IBL_ERR_UNSUPPORTED, "%s: texture path too long", l->path);
        st = ibl_read_image(l->ctx, full, NULL, im, NULL);
    }
    if (st != IBL_OK) return st;
    memcpy(l->texture_names[l->texture_count], name.data, strlen(name.data) + 1);
    *index = l->texture_count++;
    return IBL_OK;
}

/* ---- materials ----------------------------------------------------------------------------- */

static float get_float(const loader *l, const struct aiMaterial *m, const char *key,
                       unsigned type, unsigned index, float fallback)
{
    ai_real v;
    unsigned max = 1;
    return l->api.aiGetMaterialFloatArray(m, key, type, index, &v, &max) == aiReturn_SUCCESS
               ? (float)v
               : fallback;
}

static ibl_status read_material(loader *l, int i, ibl_scene_material *out)
{
    const struct aiMaterial *m = l->ai->mMaterials[i];
    *out = ibl_scene_material_default();
    struct aiString name;
    if (l->api.aiGetMaterialString(m, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS)
        snprintf(out->name, sizeof out->name, "%.63s", name.data);
    struct aiColor4D c;
    if (l->api.aiGetMaterialColor(m, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS ||
        l->api.aiGetMaterialColor(m, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS)
        out->base_color[0] = c.r, out->base_color[1] = c.g, out->base_color[2] = c.b;
    out->metallic = get_float(l, m, AI_MATKEY_METALLIC_FACTOR, 1.0f);
    out->roughness = get_float(l, m, AI_MATKEY_ROUGHNESS_FACTOR, 1.0f);
    double strength = i < l->strength_count ? l->strengths[i] : 1.0;
    if (l->api.aiGetMaterialColor(m, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS) {
        out->emissive[0] = (float)(c.r * strength);
        out->emissive[1] = (float)(c.g * strength);
        out->emissive[2] = (float)(c.b * strength);
    }
    ibl_status st = texture_index(l, m, aiTextureType_BASE_COLOR, &out->base_color_texture);
    if (st == IBL_OK && out->base_color_texture < 0)
        st = texture_index(l, m, aiTextureType_DIFFUSE, &out->base_color_texture);
    /* glTF's metallicRoughnessTexture: assimp 5.2 files it as aiTextureType_UNKNOWN */
    if (st == IBL_OK) st = texture_index(l, m, aiTextureType_UNKNOWN, &out->metallic_roughness_texture);
    if (st == IBL_OK) st = texture_index(l, m, aiTextureType_EMISSIVE, &out->emissive_texture);
    if (out->emissive_texture >= 0 && out->emissive[0] == 0 && out->emissive[1] == 0 &&
        out->emissive[2] == 0)
        out->emissive_texture = -1;
    return st;
}

/* ---- geometry ------------------------------------------------------------------------------ */

typedef struct arrays {
    float *positions, *normals, *uvs;
    uint32_t *indices;
    int *material_ids;
    int vertices, triangles;
} arrays;

static ibl_status gather(loader *l, arrays *a)
{
    const struct aiScene *s = l->ai;
    size_t nv = 0, nt = 0;
    for (unsigned i = 0; i < s->mNumMeshes; i++) {
        const struct aiMesh *m = s->mMeshes[i];
        if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        nv += m->mNumVertices;
        nt += m->mNumFaces;
    }
    if (nv == 0 || nt == 0)
        return ibl__fail(l->ctx, IBL_ERR_FORMAT, "%s: the scene has no triangles", l->path);
    if (nv > 0x7fffffff / 3 || nt > 0x7fffffff / 3)
        return ibl__fail(l->ctx, IBL_ERR_TOO_LARGE, "%s: too many triangles", l->path);
    a->positions = ibl_alloc(l->ctx, nv * 3 * sizeof(float));
    a->normals = ibl_alloc(l->ctx, nv * 3 * sizeof(float));
    a->uvs = ibl_calloc(l->ctx, nv * 2, sizeof(float));
    a->indices = ibl_calloc(l->ctx, nt * 3, sizeof(uint32_t));
    a->material_ids = ibl_calloc(l->ctx, nt, sizeof(int));
    if (!a->positions || !a->normals || !a->uvs || !a->indices || !a->material_ids)
        return IBL_ERR_OUT_OF_MEMORY;
    for (unsigned i = 0; i < s->mNumMeshes; i++) {
        const struct aiMesh *m = s->mMeshes[i];
        if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        uint32_t base = (uint32_t)a->vertices;
        for (unsigned v = 0; v < m->mNumVertices; v++) {
            float *p = a->positions + 3 * (base + v), *n = a->normals + 3 * (base + v);
            p[0] = m->mVertices[v].x, p[1] = m->mVertices[v].y, p[2] = m->mVertices[v].z;
            if (m->mNormals) n[0] = m->mNormals[v].x, n[1] = m->mNormals[v].y, n[2] = m->mNormals[v].z;
            else n[0] = n[1] = n[2] = 0.0f;
            if (m->mTextureCoords[0]) {
                a->uvs[2 * (base + v)] = m->mTextureCoords[0][v].x;
                a->uvs[2 * (base + v) + 1] = m->mTextureCoords[0][v].y;
            }
        }
        for (unsigned f = 0; f < m->mNumFaces; f++) {
            if (m->mFaces[f].mNumIndices != 3) continue; /* points and lines left by the importer */
            uint32_t *t = a->indices + 3 * a->triangles;
            for (int k = 0; k < 3; k++) t[k] = base + m->mFaces[f].mIndices[k];
            a->material_ids[a->triangles++] = (int)m->mMaterialIndex;
        }
        a->vertices += (int)m->mNumVertices;
    }
    return IBL_OK;
}

/* Assimp's message on one line */
static ibl_status assimp_failure(loader *l)
{
    char msg[300];
    snprintf(msg, sizeof msg, "%s", l->api.aiGetErrorString());
    for (char *p = msg; *p; p++)
        if (*p == '\n' || *p == '\r' || *p == '\t') *p = ' ';
    size_t n = strlen(msg);
    while (n && msg[n - 1] == ' ') msg[--n] = '\0';
    return ibl__fail(l->ctx, IBL_ERR_FORMAT, "%s: not a %s Assimp can read (%s)", l->path,
                     l->obj ? "Wavefront OBJ mesh" : "glTF scene", n ? msg : "no reason given");
}

static void loader_free(loader *l, arrays *a, ibl_scene_material *mats)
{
    for (int i = 0; i < l->texture_count; i++) ibl_image_free(l->ctx, &l->textures[i]);
    ibl_free(l->ctx, l->textures);
    ibl_free(l->ctx, l->texture_names);
    ibl_free(l->ctx, l->strengths);
    ibl_free(l->ctx, mats);
    ibl_free(l->ctx, a->positions);
    ibl_free(l->ctx, a->normals);
    ibl_free(l->ctx, a->uvs);
    ibl_free(l->ctx, a->indices);
    ibl_free(l->ctx, a->material_ids);
    if (l->ai) l->api.aiReleaseImport(l->ai);
    ibl__assimp_unload(&l->api);
}

static ibl_status load_scene(ibl_context *ctx, const char *path, int obj, ibl_scene **out)
{
    if (!ctx || !path || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    loader l;
    memset(&l, 0, sizeof l);
    l.ctx = ctx;
    l.path = path;
    l.obj = obj;
    arrays a;
    memset(&a, 0, sizeof a);
    ibl_scene_material *mats = NULL;
    ibl_status st = read_strengths(&l); /* also the readable-file and JSON checks */
    if (st == IBL_OK) st = ibl__assimp_load(ctx, path, &l.api);
    if (st == IBL_OK) {
        l.ai = l.api.aiImportFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                            aiProcess_GenSmoothNormals | aiProcess_FlipUVs |
                                            aiProcess_ValidateDataStructure);
        if (!l.ai) st = assimp_failure(&l);
    }
    if (st == IBL_OK && l.ai->mNumMaterials == 0)
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: the scene has no material", path);
    if (st == IBL_OK) {
        mats = ibl_alloc(ctx, l.ai->mNumMaterials * sizeof *mats);
        if (!mats) st = IBL_ERR_OUT_OF_MEMORY;
    }
    for (unsigned i = 0; st == IBL_OK && i < l.ai->mNumMaterials; i++)
        st = read_material(&l, (int)i, &mats[i]);
    if (st == IBL_OK) st = gather(&l, &a);
    if (st == IBL_OK) {
        ibl_scene_desc d;
        memset(&d, 0, sizeof d);
        d.vertex_count = a.vertices;
        d.triangle_count = a.triangles;
        d.positions = a.positions;
        d.normals = a.normals;
        d.uvs = a.uvs;
        d.indices = a.indices;
        d.material_ids = a.material_ids;
        d.materials = mats;
        d.material_count = (int)l.ai->mNumMaterials;
        d.textures = l.textures;
        d.texture_count = l.texture_count;
        d.name = path;
        st = ibl_scene_create(ctx, &d, out);
    }
    loader_free(&l, &a, mats);
    return st;
}

ibl_status ibl_scene_load_gltf(ibl_context *ctx, const char *path, ibl_scene **out)
{
    return load_scene(ctx, path, 0, out);
}

ibl_status ibl_scene_load(ibl_context *ctx, const char *path, ibl_scene **out)
{
    size_t n = path ? strlen(path) : 0;
    int obj = n >= 4 && strcasecmp(path + n - 4, ".obj") == 0;
    return load_scene(ctx, path, obj, out);
}
