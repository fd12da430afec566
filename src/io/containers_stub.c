/* delete when src/io/ktx2.c lands
 *
 * Temporary stand-ins for the KTX2, KTX1 and DDS codecs (another branch implements them in
 * ktx2.c, ktx1.c and dds.c) so that the library links meanwhile. */
#include "io/io_internal.h"

static ibl_status not_yet(ibl_context *ctx, const char *name, const char *what)
{
    return ibl_fail(ctx, IBL_ERR_UNSUPPORTED, "%s: %s is not available in this build", name, what);
}

ibl_status ibl__ktx2_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info)
{
    (void)bytes, (void)size, (void)out, (void)info;
    return not_yet(ctx, name, "KTX2 reading");
}

ibl_status ibl__ktx2_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    (void)tex, (void)desc, (void)bytes, (void)size;
    return not_yet(ctx, name, "KTX2 writing");
}

ibl_status ibl__ktx1_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info)
{
    (void)bytes, (void)size, (void)out, (void)info;
    return not_yet(ctx, name, "KTX reading");
}

ibl_status ibl__ktx1_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    (void)tex, (void)desc, (void)bytes, (void)size;
    return not_yet(ctx, name, "KTX writing");
}

ibl_status ibl__dds_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    (void)bytes, (void)size, (void)out, (void)info;
    return not_yet(ctx, name, "DDS reading");
}

ibl_status ibl__dds_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    (void)tex, (void)desc, (void)bytes, (void)size;
    return not_yet(ctx, name, "DDS writing");
}
