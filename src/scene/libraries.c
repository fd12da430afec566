/* Embree and Assimp loaded on first use (libraries.h says why). */
#include "scene/libraries.h"
#include "core/context_internal.h"

#include <dlfcn.h>
#include <stddef.h>
#include <string.h>

#ifndef IBL_EMBREE_SONAME
#error "IBL_EMBREE_SONAME: the Embree library's soname, set by CMakeLists.txt"
#endif
#ifndef IBL_ASSIMP_SONAME
#error "IBL_ASSIMP_SONAME: the Assimp library's soname, set by CMakeLists.txt"
#endif

typedef struct library_symbol {
    const char *name;
    size_t offset; /* of its pointer in the table */
} library_symbol;

#define IBL__EMBREE_SYMBOL(name) {#name, offsetof(ibl__embree, name)},
#define IBL__ASSIMP_SYMBOL(name) {#name, offsetof(ibl__assimp, name)},
static const library_symbol embree_symbols[] = {IBL__EMBREE_FUNCTIONS(IBL__EMBREE_SYMBOL)};
static const library_symbol assimp_symbols[] = {IBL__ASSIMP_FUNCTIONS(IBL__ASSIMP_SYMBOL)};

/* dlopen's message, or a default: dlerror() may return NULL. */
static const char *load_error(void)
{
    const char *e = dlerror();
    return e ? e : "unknown reason";
}

/* Opens `soname` into *library and stores each symbol's address at its offset in `table`
 * (`table_bytes` long, *library inside it); on failure the table is left all zero. */
static ibl_status load(ibl_context *ctx, const char *what, const char *soname,
                       const library_symbol *symbols, size_t count, void **library, void *table,
                       size_t table_bytes)
{
    memset(table, 0, table_bytes);
    void *handle = dlopen(soname, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!handle)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: cannot load %s: %s", what, soname, load_error());
    for (size_t i = 0; i < count; i++) {
        void *address = dlsym(handle, symbols[i].name);
        if (!address) {
            ibl_status st = ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: %s has no %s", what, soname,
                                      symbols[i].name);
            dlclose(handle);
            memset(table, 0, table_bytes);
            return st;
        }
        /* POSIX: a function's address from dlsym is used through a copy of its bytes */
        memcpy((char *)table + symbols[i].offset, &address, sizeof address);
    }
    *library = handle;
    return IBL_OK;
}

ibl_status ibl__embree_load(ibl_context *ctx, const char *what, ibl__embree *out)
{
    return load(ctx, what, IBL_EMBREE_SONAME, embree_symbols,
                sizeof embree_symbols / sizeof embree_symbols[0], &out->library, out, sizeof *out);
}

ibl_status ibl__assimp_load(ibl_context *ctx, const char *what, ibl__assimp *out)
{
    return load(ctx, what, IBL_ASSIMP_SONAME, assimp_symbols,
                sizeof assimp_symbols / sizeof assimp_symbols[0], &out->library, out, sizeof *out);
}

void ibl__embree_unload(ibl__embree *api)
{
    if (api->library) dlclose(api->library);
    memset(api, 0, sizeof *api);
}

void ibl__assimp_unload(ibl__assimp *api)
{
    if (api->library) dlclose(api->library);
    memset(api, 0, sizeof *api);
}
