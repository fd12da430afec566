/* Internal: the atlas coordinate table as JSON, shared by the public text functions
 * (src/shade/atlas_table.c), the bake manifest and the chain manifest of `ibl prefilter`. */
#ifndef IBL_SHADE_ATLAS_TABLE_H
#define IBL_SHADE_ATLAS_TABLE_H

#include "ibl/shade.h"
#include "io/json.h"

/* {"width", "height", "levels", "gutter", "face_order", "rects": [[x, y, face_size], ...]} */
json_t *ibl__atlas_layout_json(const ibl_atlas_layout *layout);
/* Reads and checks one (the object at path.key of parent); failures go to r. */
void ibl__atlas_layout_read(ibl__json_reader *r, json_t *object, const char *path,
                            ibl_atlas_layout *out);

#endif
