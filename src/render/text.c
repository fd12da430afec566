/* Labels for `ibl render --compare`: a 5x7 bitmap font drawn straight into float images, and
 * the side-by-side composition. The glyphs are drawn for this project. */
#include "render_internal.h"
#include "core/context_internal.h"

#include <ctype.h>
#include <string.h>

typedef struct glyph {
    char c;
    const char *rows[7];
} glyph;

static const glyph font[] = {
    {'A', {" ### ", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"}},
    {'B', {"#### ", "#   #", "#   #", "#### ", "#   #", "#   #", "#### "}},
    {'C', {" ### ", "#   #", "#    ", "#    ", "#    ", "#   #", " ### "}},
    {'D', {"#### ", "#   #", "#   #", "#   #", "#   #", "#   #", "#### "}},
    {'E', {"#####", "#    ", "#    ", "#### ", "#    ", "#    ", "#####"}},
    {'F', {"#####", "#    ", "#    ", "#### ", "#    ", "#    ", "#    "}},
    {'G', {" ### ", "#   #", "#    ", "# ###", "#   #", "#   #", " ####"}},
    {'H', {"#   #", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"}},
    {'I', {" ### ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'J', {"  ###", "   # ", "   # ", "   # ", "   # ", "#  # ", " ##  "}},
    {'K', {"#   #", "#  # ", "# #  ", "##   ", "# #  ", "#  # ", "#   #"}},
    {'L', {"#    ", "#    ", "#    ", "#    ", "#    ", "#    ", "#####"}},
    {'M', {"#   #", "## ##", "# # #", "# # #", "#   #", "#   #", "#   #"}},
    {'N', {"#   #", "#   #", "##  #", "# # #", "#  ##", "#   #", "#   #"}},
    {'O', {" ### ", "#   #", "#   #", "#   #", "#   #", "#   #", " ### "}},
    {'P', {"#### ", "#   #", "#   #", "#### ", "#    ", "#    ", "#    "}},
    {'Q', {" ### ", "#   #", "#   #", "#   #", "# # #", "#  # ", " ## #"}},
    {'R', {"#### ", "#   #", "#   #", "#### ", "# #  ", "#  # ", "#   #"}},
    {'S', {" ####", "#    ", "#    ", " ### ", "    #", "    #", "#### "}},
    {'T', {"#####", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  "}},
    {'U', {"#   #", "#   #", "#   #", "#   #", "#   #", "#   #", " ### "}},
    {'V', {"#   #", "#   #", "#   #", "#   #", "#   #", " # # ", "  #  "}},
    {'W', {"#   #", "#   #", "#   #", "# # #", "# # #", "# # #", " # # "}},
    {'X', {"#   #", "#   #", " # # ", "  #  ", " # # ", "#   #", "#   #"}},
    {'Y', {"#   #", "#   #", " # # ", "  #  ", "  #  ", "  #  ", "  #  "}},
    {'Z', {"#####", "    #", "   # ", "  #  ", " #   ", "#    ", "#####"}},
    {'0', {" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "}},
    {'1', {"  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'2', {" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"}},
    {'3', {"#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "}},
    {'4', {"   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "}},
    {'5', {"#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "}},
    {'6', {"  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "}},
    {'7', {"#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "}},
    {'8', {" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "}},
    {'9', {" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "}},
    {'.', {"     ", "     ", "     ", "     ", "     ", " ##  ", " ##  "}},
    {',', {"     ", "     ", "     ", "     ", " ##  ", "  #  ", " #   "}},
    {':', {"     ", " ##  ", " ##  ", "     ", " ##  ", " ##  ", "     "}},
    {'-', {"     ", "     ", "     ", "#####", "     ", "     ", "     "}},
    {'_', {"     ", "     ", "     ", "     ", "     ", "     ", "#####"}},
    {'+', {"     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "}},
    {'=', {"     ", "     ", "#####", "     ", "#####", "     ", "     "}},
    {'/', {"     ", "    #", "   # ", "  #  ", " #   ", "#    ", "     "}},
    {'(', {"   # ", "  #  ", " #   ", " #   ", " #   ", "  #  ", "   # "}},
    {')', {" #   ", "  #  ", "   # ", "   # ", "   # ", "  #  ", " #   "}},
    {'%', {"##   ", "##  #", "   # ", "  #  ", " #   ", "#  ##", "   ##"}},
    {'#', {" # # ", " # # ", "#####", " # # ", "#####", " # # ", " # # "}},
    {'!', {"  #  ", "  #  ", "  #  ", "  #  ", "  #  ", "     ", "  #  "}},
    {'?', {" ### ", "#   #", "    #", "   # ", "  #  ", "     ", "  #  "}},
    {'\'', {"  #  ", "  #  ", " #   ", "     ", "     ", "     ", "     "}},
    {'<', {"    #", "   # ", "  #  ", " #   ", "  #  ", "   # ", "    #"}},
    {'>', {"#    ", " #   ", "  #  ", "   # ", "  #  ", " #   ", "#    "}},
    {'^', {"  #  ", " # # ", "#   #", "     ", "     ", "     ", "     "}},
    {'*', {"     ", "# # #", " ### ", "#####", " ### ", "# # #", "     "}},
};

static const glyph *find_glyph(char c)
{
    c = (char)toupper((unsigned char)c);
    for (size_t i = 0; i < sizeof font / sizeof font[0]; i++)
        if (font[i].c == c) return &font[i];
    return NULL;
}

static void fill_rect(ibl_image *im, int x0, int y0, int w, int h, const float rgba[4])
{
    for (int y = y0; y < y0 + h; y++) {
        if (y < 0 || y >= im->height) continue;
        for (int x = x0; x < x0 + w; x++) {
            if (x < 0 || x >= im->width) continue;
            memcpy(ibl_image_texel(im, x, y), rgba, 4 * sizeof(float));
        }
    }
}

void ibl__render_text(ibl_image *im, int x, int y, int scale, const char *text, const float rgba[4])
{
    if (scale < 1) scale = 1;
    static const float box[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    int len = (int)strlen(text);
    /* 6 font pixels per character (5 + 1 spacing), a 1-pixel margin around */
    fill_rect(im, x - scale, y - scale, (len * 6 + 1) * scale, 9 * scale, box);
    for (int i = 0; i < len; i++) {
        const glyph *g = find_glyph(text[i]);
        if (!g) continue;
        for (int r = 0; r < 7; r++)
            for (int c = 0; c < 5; c++)
                if (g->rows[r][c] == '#')
                    fill_rect(im, x + (i * 6 + c) * scale, y + r * scale, scale, scale, rgba);
    }
}

ibl_status ibl_render_side_by_side(ibl_context *ctx, const ibl_image *a, const char *label_a,
                                   const ibl_image *b, const char *label_b, ibl_image *out)
{
    memset(out, 0, sizeof *out);
    if (a->height != b->height)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "side by side: heights differ (%d and %d)",
                        a->height, b->height);
    int gap = a->width / 128 + 2;
    ibl_status st = ibl_image_alloc(ctx, a->width + gap + b->width, a->height, out);
    if (st != IBL_OK) return st;
    static const float black[4] = {0, 0, 0, 1}, white[4] = {1, 1, 1, 1};
    fill_rect(out, 0, 0, out->width, out->height, black);
    for (int y = 0; y < a->height; y++) {
        memcpy(ibl_image_texel(out, 0, y), ibl_image_texel(a, 0, y),
               (size_t)a->width * 4 * sizeof(float));
        memcpy(ibl_image_texel(out, a->width + gap, y), ibl_image_texel(b, 0, y),
               (size_t)b->width * 4 * sizeof(float));
    }
    int scale = a->height >= 512 ? 3 : (a->height >= 192 ? 2 : 1);
    if (label_a) ibl__render_text(out, 2 * scale, 2 * scale, scale, label_a, white);
    if (label_b) ibl__render_text(out, a->width + gap + 2 * scale, 2 * scale, scale, label_b, white);
    return IBL_OK;
}
