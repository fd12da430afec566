/* Internal: Embree and Assimp, loaded when a scene needs them (dlopen) rather than with the
 * program. Only the scene commands use them, and loading them with every process (with TBB
 * and Draco, which they pull in) took about 3 ms of each command's start-up, `ibl prefilter`
 * included: a serial 3% of the 256 GGX chain on two threads. Their headers still give the
 * types, the constants and the inline functions; the functions called come from these tables,
 * filled by name from the libraries named at build time (their sonames, CMakeLists.txt).
 *
 * The libraries stay loaded once loaded (RTLD_NODELETE: TBB does not support being unloaded),
 * so loading them again for the next scene costs a reference count and the name lookups. */
#ifndef IBL_SCENE_LIBRARIES_H
#define IBL_SCENE_LIBRARIES_H

#include "ibl/core.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <embree3/rtcore.h>

/* The functions each table holds, as X(name). */
#define IBL__EMBREE_FUNCTIONS(X)                                                              \
    X(rtcNewDevice) X(rtcReleaseDevice) X(rtcGetDeviceError) X(rtcNewScene) X(rtcReleaseScene) \
    X(rtcSetSceneFlags) X(rtcSetSceneBuildQuality) X(rtcCommitScene) X(rtcNewGeometry)         \
    X(rtcReleaseGeometry) X(rtcSetNewGeometryBuffer) X(rtcCommitGeometry) X(rtcAttachGeometry) \
    X(rtcIntersect1) X(rtcOccluded1)
#define IBL__ASSIMP_FUNCTIONS(X)                                                              \
    X(aiImportFile) X(aiReleaseImport) X(aiGetErrorString) X(aiGetMaterialTexture)             \
    X(aiGetMaterialFloatArray) X(aiGetMaterialString) X(aiGetMaterialColor)

/* Pointers typed as the headers declare the functions (__typeof__: GCC and Clang), so every
 * call is checked against the real prototype. */
#define IBL__LIBRARY_FUNCTION(name) __typeof__(name) *name;

typedef struct ibl__embree {
    void *library;
    IBL__EMBREE_FUNCTIONS(IBL__LIBRARY_FUNCTION)
} ibl__embree;

typedef struct ibl__assimp {
    void *library;
    IBL__ASSIMP_FUNCTIONS(IBL__LIBRARY_FUNCTION)
} ibl__assimp;

/* Loads the library and fills the table; on failure a message naming the library and `what`
 * (the scene's name) and IBL_ERR_UNSUPPORTED, the table left empty. */
ibl_status ibl__embree_load(ibl_context *ctx, const char *what, ibl__embree *out);
ibl_status ibl__assimp_load(ibl_context *ctx, const char *what, ibl__assimp *out);
/* Gives the reference back (the library stays mapped); an empty table is fine. */
void ibl__embree_unload(ibl__embree *api);
void ibl__assimp_unload(ibl__assimp *api);

#endif
