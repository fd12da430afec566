/* The C interface of src/io/exr_cpp.cpp, the only C++ in the library: it drives the OpenEXR
 * C++ API (which, unlike OpenEXRCore 3.1, decodes DWAA/DWAB). Every function catches every
 * exception and reports it as a status (an ibl_status value) and a message in err. */
#ifndef IBL_EXR_BRIDGE_H
#define IBL_EXR_BRIDGE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ibl__exr_reader ibl__exr_reader;

enum { IBL__EXR_RGB = 1, IBL__EXR_GREY = 2, IBL__EXR_LUMA_CHROMA = 3 };

typedef struct ibl__exr_header {
    int data_min_x, data_min_y, data_max_x, data_max_y;
    int display_min_x, display_min_y, display_max_x, display_max_y;
    int layout;      /* IBL__EXR_* */
    int has_alpha;
    int all_half;    /* every channel read is HALF (else some FLOAT or UINT) */
    char layer[128]; /* "" or the layer whose R, G, B are read (e.g. "diffuse") */
} ibl__exr_header;

/* Opens a file held in memory (bytes must outlive the reader). Returns 0 or a status. */
int ibl__exr_open(const void *bytes, size_t size, ibl__exr_reader **out, ibl__exr_header *header,
                  char *err, size_t err_size);
/* The header of part 0 alone (Imf::Header::readFrom, then the checks InputFile makes of it):
 * what ibl__exr_open gives, without the chunk offset table or any pixel. Returns 0 or a
 * status. */
int ibl__exr_read_header(const void *bytes, size_t size, ibl__exr_header *header, char *err,
                         size_t err_size);
/* Reads the whole data window into rgba (data-window width x height texels, 4 floats each,
 * top row first); missing alpha becomes 1, grey is copied to R, G and B. */
int ibl__exr_read(ibl__exr_reader *reader, float *rgba, char *err, size_t err_size);
/* Reads rows y0..y1 (data-window coordinates) of a file whose header ibl__exr_open gave
 * (not for IBL__EXR_LUMA_CHROMA) into rgba, laid out as for ibl__exr_read. Opens its own
 * OpenEXR file over bytes: calls for different rows may run at the same time. */
int ibl__exr_read_rows(const void *bytes, size_t size, const ibl__exr_header *header, float *rgba,
                       int y0, int y1, char *err, size_t err_size);
void ibl__exr_close(ibl__exr_reader *reader);

/* compression: the Imf::Compression value. alloc returns the output buffer (or NULL). */
int ibl__exr_write(const float *rgba, int width, int height, int channels, int half,
                   int compression, void *(*alloc)(void *user, size_t bytes), void *alloc_user,
                   void **out, size_t *out_size, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
