/* JPEG through libjpeg-turbo (Debian's libjpeg62-turbo, the libjpeg API) both ways.
 *
 * Read: baseline and progressive Huffman-coded files of 8-bit grey, YCbCr or RGB, decoded
 * as sRGB to linear float with the same curve as PNG (png.c). Everything libjpeg reports
 * fails the read, its warnings included: libjpeg warns where the data is corrupt or missing
 * (a marker inside a scan, the end of the file) and then goes on with zeros, which would
 * return an image whose missing part is grey. Refused before decoding: arithmetic coding,
 * where running out of data is legal and reads as zeros, so a cut file cannot be told from
 * a whole one; CMYK and YCCK, which libjpeg does not convert to RGB (without the file's
 * colour profile any conversion would be a guess).
 *
 * Write: previews, 8-bit sRGB RGB at quality 95, chroma at full resolution (4:4:4), with the
 * exposure, tone map and sRGB encoding of the 8-bit PNG previews. */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <setjmp.h>
#include <stdio.h> /* jpeglib.h needs FILE */
#include <string.h>

#include <jpeglib.h>
#include <jerror.h>

/* ---- libjpeg's errors and warnings --------------------------------------------------- */

/* libjpeg reports through these callbacks: an error (error_exit) and a warning (emit_message
 * at level -1) both jump back to the setjmp of the run that met them, with libjpeg's text. */
typedef struct jpeg_failure {
    struct jpeg_error_mgr mgr; /* first: libjpeg hands the callbacks &mgr */
    jmp_buf jump;
    int code;                  /* libjpeg's message code (JERR_*, JWRN_*) */
    int warning;               /* 1 for a warning: corrupt or missing data */
    char text[JMSG_LENGTH_MAX];
} jpeg_failure;

static void jpeg_on_error(j_common_ptr cinfo)
{
    jpeg_failure *f = (jpeg_failure *)cinfo->err;
    f->code = cinfo->err->msg_code;
    (*cinfo->err->format_message)(cinfo, f->text);
    longjmp(f->jump, 1);
}

static void jpeg_on_message(j_common_ptr cinfo, int level)
{
    if (level >= 0) return; /* trace messages */
    ((jpeg_failure *)cinfo->err)->warning = 1;
    jpeg_on_error(cinfo);
}

static void jpeg_on_output(j_common_ptr cinfo)
{
    (void)cinfo; /* the library never prints */
}

static struct jpeg_error_mgr *jpeg_failure_init(jpeg_failure *f)
{
    jpeg_std_error(&f->mgr);
    f->mgr.error_exit = jpeg_on_error;
    f->mgr.emit_message = jpeg_on_message;
    f->mgr.output_message = jpeg_on_output;
    return &f->mgr;
}

/* ---- JPEG reader --------------------------------------------------------------------- */

/* Each scan walks every block of its components again, and a scan coding nothing but runs of
 * empty blocks takes a few bytes: a 160 KB file of 1000 such scans over a 4096x4096 image
 * keeps libjpeg busy for 3 s. libjpeg's standard progressive script writes 10 scans, and the
 * scan scripts of its tools (cjpeg, jpegtran) hold at most 100: a file of more is refused. */
enum { JPEG_MAX_SCANS = 100 };

typedef struct jpeg_read_state {
    struct jpeg_decompress_struct cinfo;
    jpeg_failure failure;
    ibl_context *ctx;
    const char *name;
    const uint8_t *data;
    size_t size;
    ibl_texture *out;
    int header_only;         /* stop after the header's checks (ibl__jpeg_info) */
    uint64_t reserved;       /* budget reserved for libjpeg's own buffers */
    ibl_status status;       /* a failure already recorded with its message, or IBL_OK */
    unsigned components_coded; /* bit c: component c appeared in a scan */
    int scans;
} jpeg_read_state;

/* The fewest bytes of entropy-coded data that can hold the frame: every 8x8 block of every
 * component is coded, and a Huffman-coded block takes at least one bit (its DC difference's
 * code; a baseline block also needs an end-of-block code). The component with the most
 * blocks bounds it from below, whatever the other components hold. */
static uint64_t jpeg_min_coded_bytes(j_decompress_ptr cinfo)
{
    uint64_t most = 0;
    for (int c = 0; c < cinfo->num_components; c++) {
        const jpeg_component_info *comp = &cinfo->comp_info[c];
        uint64_t blocks = (uint64_t)comp->width_in_blocks * comp->height_in_blocks;
        if (blocks > most) most = blocks;
    }
    return most / 8;
}

static uint64_t round_up(uint64_t v, uint64_t step)
{
    return (v + step - 1) / step * step;
}

/* What libjpeg allocates itself to decode the frame to RGBA rows, from its source (2.1): with
 * several scans, the coefficients of every block (128 bytes each, the block rows and columns
 * padded to whole MCUs); the main controller's sample rows (ten row groups of each component,
 * with the context rows of smooth upsampling) and the upsampler's rows of output width (each
 * row padded to 64 samples); its tables and small pools rounded up into 1 MiB. Also given to
 * libjpeg as its limit, so an estimate below what it needs fails the read, never the budget. */
static uint64_t jpeg_library_bytes(j_decompress_ptr cinfo, int whole_image)
{
    uint64_t total = (uint64_t)1 << 20;
    uint64_t output_row = round_up(round_up(cinfo->image_width, (uint64_t)cinfo->max_h_samp_factor), 64);
    for (int c = 0; c < cinfo->num_components; c++) {
        const jpeg_component_info *comp = &cinfo->comp_info[c];
        uint64_t row = round_up((uint64_t)comp->width_in_blocks * DCTSIZE, 64);
        total += row * 10 * (uint64_t)comp->v_samp_factor + output_row * (uint64_t)cinfo->max_v_samp_factor;
        if (whole_image)
            total += round_up(comp->width_in_blocks, (uint64_t)comp->h_samp_factor) *
                     round_up(comp->height_in_blocks, (uint64_t)comp->v_samp_factor) * sizeof(JBLOCK);
    }
    return total;
}

static void jpeg_note_scan(jpeg_read_state *st)
{
    j_decompress_ptr cinfo = &st->cinfo;
    for (int i = 0; i < cinfo->comps_in_scan; i++)
        st->components_coded |= 1u << cinfo->cur_comp_info[i]->component_index;
    st->scans++;
}

/* A file of several scans is read whole before any output (libjpeg's buffered-image mode,
 * which costs nothing more: such a file needs every block's coefficients anyway), so that
 * it can be checked complete: a file cut between two scans, with an end marker appended, is
 * valid to libjpeg and decodes without a warning. Sequential: every component must have
 * been in a scan. Progressive: every coefficient of every component must have arrived with
 * all its bits (libjpeg's coef_bits: -1 before its first scan, then the bits still to come). */
static int jpeg_read_all_scans(jpeg_read_state *st)
{
    j_decompress_ptr cinfo = &st->cinfo;
    jpeg_note_scan(st); /* the first scan's header was read with the frame's */
    for (;;) {
        int r = jpeg_consume_input(cinfo);
        if (r == JPEG_REACHED_EOI) break;
        if (r == JPEG_SUSPENDED) {
            st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT, "%s: truncated JPEG", st->name);
            return 0;
        }
        if (r == JPEG_REACHED_SOS) {
            jpeg_note_scan(st);
            if (st->scans > JPEG_MAX_SCANS) {
                st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT, "%s: JPEG of more than %d scans refused",
                                       st->name, JPEG_MAX_SCANS);
                return 0;
            }
        }
    }
    for (int c = 0; c < cinfo->num_components; c++) {
        int complete = (st->components_coded >> c) & 1;
        if (cinfo->progressive_mode)
            for (int k = 0; k < DCTSIZE2; k++) complete &= cinfo->coef_bits[c][k] == 0;
        if (!complete) {
            st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT,
                                   "%s: incomplete JPEG (component %d is missing %s; the file is cut "
                                   "between two scans)",
                                   st->name, c + 1, cinfo->progressive_mode ? "coefficients" : "its scan");
            return 0;
        }
    }
    return 1;
}

/* libjpeg's jpeg_read_header and the refusals that need no more than the header; called
 * under jpeg_read_run's setjmp. */
static int jpeg_read_checked_header(jpeg_read_state *st)
{
    j_decompress_ptr cinfo = &st->cinfo;
    jpeg_mem_src(cinfo, st->data, (unsigned long)st->size);
    (void)jpeg_read_header(cinfo, TRUE);
    if (cinfo->arith_code) {
        st->status = ibl__fail(st->ctx, IBL_ERR_UNSUPPORTED,
                               "%s: arithmetic-coded JPEG is not supported (missing data reads as zeros "
                               "there, so a truncated file cannot be told from a whole one)",
                               st->name);
        return 0;
    }
    J_COLOR_SPACE space = cinfo->jpeg_color_space;
    if (space == JCS_CMYK || space == JCS_YCCK) {
        st->status = ibl__fail(st->ctx, IBL_ERR_UNSUPPORTED,
                               "%s: CMYK JPEG is not supported (libjpeg does not convert it to RGB, and "
                               "without its colour profile any conversion would be a guess)",
                               st->name);
        return 0;
    }
    if (!(space == JCS_GRAYSCALE || space == JCS_YCbCr || space == JCS_RGB)) {
        st->status = ibl__fail(st->ctx, IBL_ERR_UNSUPPORTED,
                               "%s: JPEG of %d components in an unknown colour space (grey, YCbCr or "
                               "RGB are read)",
                               st->name, cinfo->num_components);
        return 0;
    }
    return 1;
}

/* Runs libjpeg; everything it may touch after setjmp lives in *st (not in locals). The
 * caller destroys the decompressor and releases the reservation whatever happens. */
static int jpeg_read_run(jpeg_read_state *st)
{
    j_decompress_ptr cinfo = &st->cinfo;
    cinfo->err = jpeg_failure_init(&st->failure);
    if (setjmp(st->failure.jump)) return 0;
    jpeg_create_decompress(cinfo);
    if (!jpeg_read_checked_header(st)) return 0;
    if (st->header_only) return 1;
    int w = (int)cinfo->image_width, h = (int)cinfo->image_height;
    /* libjpeg decodes whatever the header declares and fills missing data with zeros, warning
     * only when it gets there: a few kilobytes claiming 16000x8000 would cost gigabytes first.
     * The file must be able to hold the declared size, and the decoding must fit the budget,
     * before anything is allocated. */
    uint64_t coded = jpeg_min_coded_bytes(cinfo), left = cinfo->src->bytes_in_buffer;
    if (left < coded) {
        st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT,
                               "%s: a %dx%d JPEG needs at least %llu bytes of coded data, the file has "
                               "%llu after its header (truncated, or a forged size)",
                               st->name, w, h, (unsigned long long)coded, (unsigned long long)left);
        return 0;
    }
    int several_scans = jpeg_has_multiple_scans(cinfo);
    uint64_t library = jpeg_library_bytes(cinfo, several_scans);
    uint64_t texels = (uint64_t)w * (uint64_t)h;
    ibl_status s = ibl__budget_check(st->ctx, library + texels * 4 * sizeof(float));
    if (s == IBL_OK) s = ibl_texture_alloc(st->ctx, IBL_TEXTURE_2D, w, h, 1, 1, st->out);
    if (s == IBL_OK) s = ibl__budget_reserve(st->ctx, library);
    if (s != IBL_OK) {
        st->status = ibl__fail_named(st->ctx, s, st->name);
        return 0;
    }
    st->reserved = library;
    cinfo->mem->max_memory_to_use = (long)library;
    /* RGBA rows straight into the tail of the float image (4 bytes of its 16 per texel),
     * converted in place afterwards: the image is the only large buffer. */
    uint8_t *samples = (uint8_t *)st->out->data + (size_t)texels * (4 * sizeof(float) - 4);
    cinfo->out_color_space = JCS_EXT_RGBA;
    cinfo->buffered_image = several_scans ? TRUE : FALSE;
    (void)jpeg_start_decompress(cinfo);
    if (several_scans) {
        if (!jpeg_read_all_scans(st)) return 0;
        (void)jpeg_start_output(cinfo, cinfo->input_scan_number);
    }
    if (cinfo->output_width != (JDIMENSION)w || cinfo->output_height != (JDIMENSION)h ||
        cinfo->output_components != 4) {
        st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT, "%s: JPEG decoded to an unexpected size", st->name);
        return 0;
    }
    while (cinfo->output_scanline < cinfo->output_height) {
        JSAMPROW row = samples + (size_t)cinfo->output_scanline * (size_t)w * 4;
        (void)jpeg_read_scanlines(cinfo, &row, 1);
    }
    if (several_scans) (void)jpeg_finish_output(cinfo);
    /* up to the end marker: a file cut after its last scan is refused too */
    (void)jpeg_finish_decompress(cinfo);
    return 1;
}

/* Runs jpeg_read_run on a new state and turns what it met into a status with a message
 * naming the file; header_only: *width and *height receive the frame's size. */
static ibl_status jpeg_read(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            int header_only, ibl_texture *out, int *width, int *height)
{
    jpeg_read_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->name = name;
    st->data = bytes;
    st->size = size;
    st->out = out;
    st->header_only = header_only;
    int ok = jpeg_read_run(st);
    if (ok && header_only) {
        *width = (int)st->cinfo.image_width;
        *height = (int)st->cinfo.image_height;
    }
    jpeg_destroy_decompress(&st->cinfo);
    ibl__budget_release(ctx, st->reserved);
    ibl_status s = st->status;
    if (!ok && s == IBL_OK) {
        const char *text = st->failure.text;
        if (st->failure.code == JERR_OUT_OF_MEMORY)
            s = ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory in libjpeg (%s)", name, text);
        else if (st->failure.warning)
            s = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated or corrupt JPEG (%s)", name, text);
        else
            s = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad JPEG (%s)", name, text);
    }
    ibl_free(ctx, st);
    return s;
}

ibl_status ibl__jpeg_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info)
{
    int w = 0, h = 0;
    ibl_status s = jpeg_read(ctx, bytes, size, name, 1, NULL, &w, &h);
    if (s != IBL_OK) return s;
    info->width = w;
    info->height = h;
    info->format = IBL_FORMAT_RGBA8_SRGB; /* as ibl__jpeg_decode reports */
    info->has_alpha = 0;
    return IBL_OK;
}

ibl_status ibl__jpeg_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info)
{
    ibl_status s = jpeg_read(ctx, bytes, size, name, 0, out, NULL, NULL);
    if (s == IBL_OK) {
        size_t texels = (size_t)out->width * (size_t)out->height;
        const uint8_t *samples = (const uint8_t *)out->data + texels * (4 * sizeof(float) - 4);
        s = ibl__rgba_samples_to_linear(ctx, samples, 0, 0.0, texels, out->data, name);
    }
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
        return s;
    }
    out->format = IBL_FORMAT_RGBA8_SRGB;
    info->format = out->format;
    info->has_alpha = 0;
    return IBL_OK;
}

/* ---- JPEG writer --------------------------------------------------------------------- */

typedef struct jpeg_write_state {
    struct jpeg_compress_struct cinfo;
    jpeg_failure failure;
    struct jpeg_destination_mgr dest;
    ibl_context *ctx;
    uint8_t *buf;            /* the file so far (ibl_alloc: file.c writes and frees it) */
    size_t cap, len;         /* buf's size; the file's length once finished */
    ibl_status grow_status;  /* why buf could not grow, or IBL_OK */
    uint8_t *row;            /* one row of RGB codes */
} jpeg_write_state;

/* Gives libjpeg the unused part of a buffer twice as large (64 KiB first). */
static void jpeg_grow_output(j_compress_ptr cinfo)
{
    jpeg_write_state *st = cinfo->client_data;
    size_t used = st->cap - cinfo->dest->free_in_buffer;
    size_t ncap = st->cap ? st->cap * 2 : 65536;
    uint8_t *grown = ncap > st->cap ? ibl_alloc(st->ctx, ncap) : NULL;
    if (!grown) {
        st->grow_status = ibl_context_status(st->ctx);
        ERREXIT1(cinfo, JERR_OUT_OF_MEMORY, 0);
    }
    if (used) memcpy(grown, st->buf, used);
    ibl_free(st->ctx, st->buf);
    st->buf = grown;
    st->cap = ncap;
    cinfo->dest->next_output_byte = grown + used;
    cinfo->dest->free_in_buffer = ncap - used;
}

static void jpeg_on_init_destination(j_compress_ptr cinfo)
{
    jpeg_grow_output(cinfo);
}

/* libjpeg's contract: the whole buffer holds output, whatever free_in_buffer says. */
static boolean jpeg_on_buffer_full(j_compress_ptr cinfo)
{
    cinfo->dest->free_in_buffer = 0;
    jpeg_grow_output(cinfo);
    return TRUE;
}

static void jpeg_on_term_destination(j_compress_ptr cinfo)
{
    jpeg_write_state *st = cinfo->client_data;
    st->len = st->cap - cinfo->dest->free_in_buffer;
}

/* Runs libjpeg; everything it may touch after setjmp lives in *st (not in locals). */
static int jpeg_write_run(jpeg_write_state *st, const ibl_image *im, const ibl__display_encoder *enc)
{
    j_compress_ptr cinfo = &st->cinfo;
    cinfo->err = jpeg_failure_init(&st->failure);
    if (setjmp(st->failure.jump)) return 0;
    jpeg_create_compress(cinfo);
    cinfo->client_data = st;
    st->dest.init_destination = jpeg_on_init_destination;
    st->dest.empty_output_buffer = jpeg_on_buffer_full;
    st->dest.term_destination = jpeg_on_term_destination;
    cinfo->dest = &st->dest;
    cinfo->image_width = (JDIMENSION)im->width;
    cinfo->image_height = (JDIMENSION)im->height;
    cinfo->input_components = 3;
    cinfo->in_color_space = JCS_RGB;
    jpeg_set_defaults(cinfo);
    jpeg_set_quality(cinfo, 95, TRUE);
    cinfo->comp_info[0].h_samp_factor = 1; /* libjpeg's default halves the chroma: keep it whole */
    cinfo->comp_info[0].v_samp_factor = 1;
    jpeg_start_compress(cinfo, TRUE);
    for (int y = 0; y < im->height; y++) {
        const float *src = im->pixels + (size_t)y * (size_t)im->width * 4;
        for (int x = 0; x < im->width; x++)
            for (int c = 0; c < 3; c++)
                st->row[(size_t)x * 3 + (size_t)c] = ibl__display_code(enc, src[(size_t)x * 4 + (size_t)c]);
        JSAMPROW row = st->row;
        (void)jpeg_write_scanlines(cinfo, &row, 1);
    }
    jpeg_finish_compress(cinfo);
    return 1;
}

ibl_status ibl__jpeg_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    if (desc->format != IBL_FORMAT_DEFAULT && desc->format != IBL_FORMAT_RGBA8_SRGB)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: JPEG stores only 8-bit sRGB, not %s", name,
                        ibl_format_name(desc->format));
    if (image->width > JPEG_MAX_DIMENSION || image->height > JPEG_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: JPEG is limited to %ld pixels a side", name,
                        (long)JPEG_MAX_DIMENSION);
    jpeg_write_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->row = ibl_alloc(ctx, (size_t)image->width * 3);
    if (!st->row) {
        ibl_free(ctx, st);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    ibl__display_encoder enc;
    ibl__display_encoder_init(&enc, desc);
    int ok = jpeg_write_run(st, image, &enc);
    jpeg_destroy_compress(&st->cinfo);
    ibl_free(ctx, st->row);
    ibl_status s = IBL_OK;
    if (ok) {
        *bytes = st->buf;
        *size = st->len;
    } else {
        ibl_free(ctx, st->buf);
        if (st->grow_status != IBL_OK) s = ibl__fail_named(ctx, st->grow_status, name);
        else
            s = ibl__fail(ctx, st->failure.code == JERR_OUT_OF_MEMORY ? IBL_ERR_OUT_OF_MEMORY : IBL_ERR_IO,
                          "%s: cannot encode JPEG (%s)", name, st->failure.text);
    }
    ibl_free(ctx, st);
    return s;
}
