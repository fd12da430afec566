/* Headless OpenGL 4.5 core on Mesa llvmpipe through EGL's surfaceless platform
 * (EGL_MESA_platform_surfaceless, EGL_KHR_surfaceless_context, EGL_KHR_create_context).
 * Specs: the Khronos EGL 1.5 specification and the extension texts of the same names. */
#include "gl_harness.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int fail(char *why, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (why && n) vsnprintf(why, n, fmt, ap);
    va_end(ap);
    return -1;
}

static int has_extension(const char *list, const char *name)
{
    size_t len = strlen(name);
    for (const char *p = list; p && (p = strstr(p, name)) != NULL; p += len)
        if ((p == list || p[-1] == ' ') && (p[len] == ' ' || p[len] == '\0')) return 1;
    return 0;
}

static int open_display(glh_context *c, char *why, size_t n)
{
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client || !has_extension(client, "EGL_MESA_platform_surfaceless"))
        return fail(why, n,
                    "EGL has no surfaceless platform (EGL_MESA_platform_surfaceless): install "
                    "Debian's libegl-mesa0 (Mesa's EGL vendor library) and libegl-dev");
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (!get_display) return fail(why, n, "EGL lacks eglGetPlatformDisplayEXT: install libegl-mesa0");
    EGLDisplay d = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    EGLint major = 0, minor = 0;
    if (d == EGL_NO_DISPLAY || !eglInitialize(d, &major, &minor))
        return fail(why, n,
                    "cannot initialise the EGL surfaceless display (EGL error 0x%x): install "
                    "Debian's libgl1-mesa-dri (the llvmpipe driver) and libegl-mesa0",
                    (unsigned)eglGetError());
    c->display = d;
    const char *ext = eglQueryString(d, EGL_EXTENSIONS);
    if (!has_extension(ext, "EGL_KHR_surfaceless_context"))
        return fail(why, n, "EGL lacks EGL_KHR_surfaceless_context (Mesa %d.%d): install libegl-mesa0",
                    major, minor);
    return 0;
}

static int create_context(glh_context *c, char *why, size_t n)
{
    EGLDisplay d = c->display;
    if (!eglBindAPI(EGL_OPENGL_API))
        return fail(why, n, "EGL cannot bind desktop OpenGL: install libgl1-mesa-dri");
    /* EGL_SURFACE_TYPE defaults to EGL_WINDOW_BIT, which a surfaceless display never offers */
    static const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                            EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config;
    EGLint count = 0;
    if (!eglChooseConfig(d, config_attribs, &config, 1, &count) || count < 1)
        return fail(why, n, "EGL offers no desktop OpenGL config: install libgl1-mesa-dri");
    static const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                         EGL_CONTEXT_MINOR_VERSION, 5,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                         EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                         EGL_NONE};
    EGLContext ctx = eglCreateContext(d, config, EGL_NO_CONTEXT, ctx_attribs);
    if (ctx == EGL_NO_CONTEXT)
        return fail(why, n,
                    "cannot create an OpenGL 4.5 core context (EGL error 0x%x): Mesa's llvmpipe "
                    "in libgl1-mesa-dri (Mesa >= 20) provides it",
                    (unsigned)eglGetError());
    c->context = ctx;
    if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx))
        return fail(why, n, "eglMakeCurrent failed (EGL error 0x%x)", (unsigned)eglGetError());
    return 0;
}

int glh_create(glh_context *c, char *why, size_t n)
{
    memset(c, 0, sizeof *c);
    /* the software rasteriser whatever GPU the machine has, so results do not depend on it */
    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);
    setenv("GALLIUM_DRIVER", "llvmpipe", 1);
    if (open_display(c, why, n) != 0 || create_context(c, why, n) != 0) {
        glh_destroy(c);
        return -1;
    }
#define GLH_LOAD(name, type)                                                                   \
    c->gl.name = (type)eglGetProcAddress("gl" #name);                                          \
    if (!c->gl.name) {                                                                         \
        glh_destroy(c);                                                                        \
        return fail(why, n, "the GL driver lacks gl" #name ": install libgl1-mesa-dri");       \
    }
    GLH_FUNCTIONS(GLH_LOAD)
#undef GLH_LOAD
    const char *r = (const char *)c->gl.GetString(GL_RENDERER);
    const char *v = (const char *)c->gl.GetString(GL_VERSION);
    snprintf(c->renderer, sizeof c->renderer, "%s", r ? r : "?");
    snprintf(c->version, sizeof c->version, "%s", v ? v : "?");
    GLint major = 0, minor = 0;
    c->gl.GetIntegerv(GL_MAJOR_VERSION, &major);
    c->gl.GetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45) {
        glh_destroy(c);
        return fail(why, n, "the driver gives OpenGL %d.%d, 4.5 is needed (libgl1-mesa-dri)",
                    major, minor);
    }
    return 0;
}

void glh_destroy(glh_context *c)
{
    if (c->display) {
        eglMakeCurrent(c->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (c->context) eglDestroyContext(c->display, c->context);
        /* no eglTerminate: the surfaceless display is one per process and EGL reclaims it at
         * exit, while Mesa 22.3's terminate unloads the driver and leaks 128 bytes inside
         * libxcb-dri2 (LeakSanitizer then reports an <unknown module> no suppression can
         * name). Destroying the context frees everything the tests made. */
        eglReleaseThread();
    }
    memset(c, 0, sizeof *c);
}

GLuint glh_program(const glh_context *c, char *log, size_t log_size, int stage_count,
                   const GLenum *types, const char *const *sources)
{
    const glh_gl *gl = &c->gl;
    GLuint prog = gl->CreateProgram();
    GLint ok = 0;
    for (int i = 0; i < stage_count; i++) {
        GLuint sh = gl->CreateShader(types[i]);
        gl->ShaderSource(sh, 1, &sources[i], NULL);
        gl->CompileShader(sh);
        gl->GetShaderiv(sh, GL_COMPILE_STATUS, &ok);
        if (!ok) {
            if (log && log_size) gl->GetShaderInfoLog(sh, (GLsizei)log_size, NULL, log);
            gl->DeleteShader(sh);
            gl->DeleteProgram(prog);
            return 0;
        }
        gl->AttachShader(prog, sh);
        gl->DeleteShader(sh); /* freed with the program */
    }
    gl->LinkProgram(prog);
    gl->GetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        if (log && log_size) gl->GetProgramInfoLog(prog, (GLsizei)log_size, NULL, log);
        gl->DeleteProgram(prog);
        return 0;
    }
    return prog;
}

char *glh_read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    if (fseek(f, 0, SEEK_END) == 0) {
        long size = ftell(f);
        if (size >= 0 && fseek(f, 0, SEEK_SET) == 0 && (buf = malloc((size_t)size + 1)) != NULL) {
            if (fread(buf, 1, (size_t)size, f) != (size_t)size) {
                free(buf);
                buf = NULL;
            } else {
                buf[size] = '\0';
            }
        }
    }
    fclose(f);
    return buf;
}

char *glh_read_shader(const char *dir, const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char *text = glh_read_text(path);
    if (!text) fprintf(stderr, "cannot read %s\n", path);
    return text;
}

int glh_validate(const char *validator, const char *args, const char *path,
                 const char *const *parts, int count)
{
    FILE *o = fopen(path, "wb");
    if (!o) return -1;
    for (int i = 0; i < count; i++) fprintf(o, "%s\n", parts[i]);
    if (fclose(o) != 0) return -1;
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s' %s '%s' > '%s.log' 2>&1", validator, args, path, path);
    int rc = system(cmd);
    if (rc != 0) {
        char log_path[1100];
        snprintf(log_path, sizeof log_path, "%s.log", path);
        char *log = glh_read_text(log_path);
        fprintf(stderr, "glslangValidator %s %s failed:\n%s\n", args, path, log ? log : "");
        free(log);
    }
    return rc;
}

int glh_create_for_test(glh_context *out)
{
    char why[512];
    if (glh_create(out, why, sizeof why) == 0) return 0;
    fprintf(stderr, "no headless OpenGL 4.5 context: %s\n", why);
    return -1;
}
