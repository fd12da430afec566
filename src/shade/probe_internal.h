/* Internal: the bake manifest reader, separate from the file system so it can be fuzzed. */
#ifndef IBL_PROBE_INTERNAL_H
#define IBL_PROBE_INTERNAL_H

#include "ibl/shade.h"

/* Reads the level mapping (and the AmbientBRDF shininess range) from the bytes of a bake's
 * manifest.json; name is used in messages. The file paths of *files are left NULL. */
ibl_status ibl__probe_parse_manifest(ibl_context *ctx, const void *bytes, size_t size,
                                     const char *name, ibl_probe_files *files);

#endif
