/* A headless OpenGL 4.5 core context for the tests (and the example program): EGL on Mesa's
 * surfaceless platform (EGL_MESA_platform_surfaceless), software rendering (llvmpipe), no
 * window, no display server. Every GL entry point is loaded with eglGetProcAddress into a
 * table, so nothing links against libGL. All rendering goes to framebuffer objects.
 *
 * Debian 12 packages (scripts/install-deps.sh): libegl-dev (EGL headers and the libglvnd
 * loader), libgl-dev (GL/glcorearb.h), libegl-mesa0 (Mesa's EGL vendor library),
 * libgl1-mesa-dri (the llvmpipe driver). */
#ifndef IBL_GL_HARNESS_H
#define IBL_GL_HARNESS_H

#include <GL/glcorearb.h>
#include <stddef.h>

/* X(return-type-free name, PFN type): every GL function the tests and the example call. */
#define GLH_FUNCTIONS(X)                                                                        \
    X(GetString, PFNGLGETSTRINGPROC)                                                            \
    X(GetError, PFNGLGETERRORPROC)                                                              \
    X(GetIntegerv, PFNGLGETINTEGERVPROC)                                                        \
    X(Enable, PFNGLENABLEPROC)                                                                  \
    X(Disable, PFNGLDISABLEPROC)                                                                \
    X(Finish, PFNGLFINISHPROC)                                                                  \
    X(Viewport, PFNGLVIEWPORTPROC)                                                              \
    X(Clear, PFNGLCLEARPROC)                                                                    \
    X(ClearColor, PFNGLCLEARCOLORPROC)                                                          \
    X(PixelStorei, PFNGLPIXELSTOREIPROC)                                                        \
    X(ReadPixels, PFNGLREADPIXELSPROC)                                                          \
    X(CreateShader, PFNGLCREATESHADERPROC)                                                      \
    X(ShaderSource, PFNGLSHADERSOURCEPROC)                                                      \
    X(CompileShader, PFNGLCOMPILESHADERPROC)                                                    \
    X(GetShaderiv, PFNGLGETSHADERIVPROC)                                                        \
    X(GetShaderInfoLog, PFNGLGETSHADERINFOLOGPROC)                                              \
    X(DeleteShader, PFNGLDELETESHADERPROC)                                                      \
    X(CreateProgram, PFNGLCREATEPROGRAMPROC)                                                    \
    X(AttachShader, PFNGLATTACHSHADERPROC)                                                      \
    X(LinkProgram, PFNGLLINKPROGRAMPROC)                                                        \
    X(GetProgramiv, PFNGLGETPROGRAMIVPROC)                                                      \
    X(GetProgramInfoLog, PFNGLGETPROGRAMINFOLOGPROC)                                            \
    X(DeleteProgram, PFNGLDELETEPROGRAMPROC)                                                    \
    X(UseProgram, PFNGLUSEPROGRAMPROC)                                                          \
    X(GetUniformLocation, PFNGLGETUNIFORMLOCATIONPROC)                                          \
    X(Uniform1i, PFNGLUNIFORM1IPROC)                                                            \
    X(Uniform1f, PFNGLUNIFORM1FPROC)                                                            \
    X(Uniform2f, PFNGLUNIFORM2FPROC)                                                            \
    X(Uniform2i, PFNGLUNIFORM2IPROC)                                                            \
    X(Uniform4fv, PFNGLUNIFORM4FVPROC)                                                          \
    X(GetUniformBlockIndex, PFNGLGETUNIFORMBLOCKINDEXPROC)                                      \
    X(UniformBlockBinding, PFNGLUNIFORMBLOCKBINDINGPROC)                                        \
    X(GenBuffers, PFNGLGENBUFFERSPROC)                                                          \
    X(DeleteBuffers, PFNGLDELETEBUFFERSPROC)                                                    \
    X(BindBuffer, PFNGLBINDBUFFERPROC)                                                          \
    X(BindBufferBase, PFNGLBINDBUFFERBASEPROC)                                                  \
    X(BufferData, PFNGLBUFFERDATAPROC)                                                          \
    X(GetBufferSubData, PFNGLGETBUFFERSUBDATAPROC)                                              \
    X(DispatchCompute, PFNGLDISPATCHCOMPUTEPROC)                                                \
    X(MemoryBarrier, PFNGLMEMORYBARRIERPROC)                                                    \
    X(GenTextures, PFNGLGENTEXTURESPROC)                                                        \
    X(DeleteTextures, PFNGLDELETETEXTURESPROC)                                                  \
    X(BindTexture, PFNGLBINDTEXTUREPROC)                                                        \
    X(ActiveTexture, PFNGLACTIVETEXTUREPROC)                                                    \
    X(TexParameteri, PFNGLTEXPARAMETERIPROC)                                                    \
    X(TexImage2D, PFNGLTEXIMAGE2DPROC)                                                          \
    X(TexImage3D, PFNGLTEXIMAGE3DPROC)                                                          \
    X(CompressedTexImage2D, PFNGLCOMPRESSEDTEXIMAGE2DPROC)                                      \
    X(BindImageTexture, PFNGLBINDIMAGETEXTUREPROC)                                              \
    X(GetTexImage, PFNGLGETTEXIMAGEPROC)                                                        \
    X(GenFramebuffers, PFNGLGENFRAMEBUFFERSPROC)                                                \
    X(DeleteFramebuffers, PFNGLDELETEFRAMEBUFFERSPROC)                                          \
    X(BindFramebuffer, PFNGLBINDFRAMEBUFFERPROC)                                                \
    X(FramebufferTexture2D, PFNGLFRAMEBUFFERTEXTURE2DPROC)                                      \
    X(CheckFramebufferStatus, PFNGLCHECKFRAMEBUFFERSTATUSPROC)                                  \
    X(GenVertexArrays, PFNGLGENVERTEXARRAYSPROC)                                                \
    X(DeleteVertexArrays, PFNGLDELETEVERTEXARRAYSPROC)                                          \
    X(BindVertexArray, PFNGLBINDVERTEXARRAYPROC)                                                \
    X(DrawArrays, PFNGLDRAWARRAYSPROC)

typedef struct glh_gl {
#define GLH_MEMBER(name, type) type name;
    GLH_FUNCTIONS(GLH_MEMBER)
#undef GLH_MEMBER
} glh_gl;

typedef struct glh_context {
    void *display, *context; /* EGLDisplay, EGLContext */
    glh_gl gl;
    char renderer[128], version[128];
} glh_context;

/* Creates the context and makes it current on this thread. Returns 0 on success; otherwise
 * writes a one-line reason, naming the Debian package that is missing when one is, to
 * `why` and returns -1. */
int glh_create(glh_context *out, char *why, size_t why_size);
void glh_destroy(glh_context *c);
/* glh_create for a test: on failure prints why on stderr (the reason names the Debian package
 * to install: no silent skip) and returns non-zero. */
int glh_create_for_test(glh_context *out);

/* Compiles and links one program from shader stages (type, source) given as NULL-terminated
 * pairs: glh_program(c, log, n, GL_COMPUTE_SHADER, src, 0). Each source may be several
 * strings joined by the caller. Returns 0 and writes the compiler's log on failure. */
GLuint glh_program(const glh_context *c, char *log, size_t log_size, int stage_count,
                   const GLenum *types, const char *const *sources);

/* Reads a whole text file into a new NUL-terminated buffer (free()); NULL on failure. */
char *glh_read_text(const char *path);

/* dir/name read whole (free()); NULL, with a line on stderr naming the file, on failure. */
char *glh_read_shader(const char *dir, const char *name);

/* Writes the count parts, each followed by a newline, to path and runs validator (the path of
 * glslangValidator) with args on it; on failure prints the validator's log to stderr. Returns
 * the command's status: 0 when the text is valid. */
int glh_validate(const char *validator, const char *args, const char *path,
                 const char *const *parts, int count);

#endif
