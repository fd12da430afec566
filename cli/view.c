/* ibl view: a bake folder as one self-contained HTML page (WebGL2) that shows it on the
 * sphere grid of `ibl render` and a shader ball, shaded by shaders/ibl.glsl itself. A thin
 * client of bake.h and shader.h; the page is assembled by viewer_html.c. */
#include "cli.h"
#include "viewer_html.h"

#include "ibl/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char usage[] =
    "usage: ibl view BAKE -o OUT.html [options]\n"
    "\n"
    "Writes one HTML file that shows the bake in a browser (WebGL2): the environment at any\n"
    "level of its chain, the sphere grid of `ibl render` and a shader ball under an orbit\n"
    "camera, material, occlusion, energy, irradiance and tone-mapping controls, an A/B split\n"
    "view and the manifest's facts. Everything is inside the file (textures, script, the\n"
    "GLSL of shaders/ibl.glsl): it opens from disk with no server and can be mailed.\n"
    "docs/VIEWER.md describes the page.\n"
    "\n"
    "BAKE is a bake folder (what `ibl bake` writes) or its manifest.json; a missing,\n"
    "truncated or inconsistent file is refused with the file's name.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   the HTML file to write (required)\n"
    "  --title TEXT        the page's title (default: the bake folder's name)\n"
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

/* The manifest's path for a folder or a manifest path. */
static void manifest_path(const char *input, char *out, size_t size)
{
    struct stat st;
    if (stat(input, &st) == 0 && S_ISDIR(st.st_mode))
        snprintf(out, size, "%s/manifest.json", input);
    else
        snprintf(out, size, "%s", input);
}

/* The bake's name for the title: the folder's last component. */
static void bake_name(const char *input, char *out, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s", input);
    size_t n = strlen(path);
    while (n > 1 && path[n - 1] == '/') path[--n] = 0;
    if (n > 14 && strcmp(path + n - 14, "/manifest.json") == 0) path[n -= 14] = 0;
    const char *slash = strrchr(path, '/'), *name = slash && slash[1] ? slash + 1 : path;
    size_t len = strlen(name); /* a title: cut to fit */
    if (len >= size) len = size - 1;
    memcpy(out, name, len);
    out[len] = 0;
}

/* The exposure `ibl render` picks for this probe (ibl_image_auto_exposure of its default
 * image), from a small render: the page starts there. */
static float default_exposure(ibl_context *ctx, const ibl_probe *probe)
{
    ibl_render_desc d = {.width = 128, .height = 64};
    ibl_image image;
    if (ibl_render(ctx, probe, &d, &image, NULL) != IBL_OK) return 0.0f;
    float ev = ibl_image_auto_exposure(&image);
    ibl_image_free(ctx, &image);
    return ev;
}

/* Loads the bake, builds the page and writes it whole (or not at all). */
static int run(ibl_context *ctx, const cli_args *a, const char *input, const char *output,
               const char *title)
{
    ibl_bake_data bake = {0};
    ibl_probe probe;
    ibl_shader_probe block;
    char path[4096], name[256], err[256];
    void *manifest = NULL;
    size_t manifest_size = 0;
    char *html = NULL;
    size_t html_size = 0;
    double t0 = cli_seconds();
    const char *failed = input;
    ibl_read_desc rd = {.clamp_infinite = a->common.clamp};
    ibl_status st = ibl_bake_load(ctx, input, &rd, &bake);
    if (st == IBL_OK) st = ibl_bake_probe(ctx, &bake, &probe);
    if (st == IBL_OK) st = ibl_shader_probe_fill(ctx, &probe, &block);
    if (st == IBL_OK) {
        manifest_path(input, path, sizeof path);
        failed = path;
        st = ibl_read_file(ctx, path, &manifest, &manifest_size);
    }
    if (st == IBL_OK) {
        /* the text as a C string (the page parses it; ibl_bake_load has checked it) */
        char *text = malloc(manifest_size + 1);
        if (!text) {
            cli_error("%s: out of memory", path);
            st = IBL_ERR_OUT_OF_MEMORY;
        } else {
            memcpy(text, manifest, manifest_size);
            text[manifest_size] = 0;
            bake_name(input, name, sizeof name);
            viewer_input in = {&probe, &block, bake.sh.bands, text, title ? title : name,
                               default_exposure(ctx, &probe)};
            st = viewer_html_build(&in, &html, &html_size, err, sizeof err);
            if (st != IBL_OK) cli_error("%s: %s", output, err);
            free(text);
        }
        if (st != IBL_OK) failed = NULL; /* reported */
    }
    if (st == IBL_OK) {
        failed = output;
        st = ibl_write_file_atomic(ctx, output, html, html_size);
    }
    if (st == IBL_OK)
        cli_info(&a->common, "wrote %s (%.1f MiB) in %.2f s\n", output,
                 (double)html_size / (1024.0 * 1024.0), cli_seconds() - t0);
    else if (failed)
        cli_report_failure(ctx, failed, st);
    free(html);
    ibl_free(ctx, manifest);
    ibl_bake_free(ctx, &bake);
    return st == IBL_OK ? CLI_EXIT_OK : cli_exit_code(st);
}

int cli_cmd_view(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "view", usage, {0}, {0}, 0};
    const char *output = NULL, *title = NULL;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o")) output = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--title", NULL)) title = cli_value(&a, arg);
        else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count != 1) cli_usage_error(&a, "needs one BAKE folder");
    if (!output) cli_usage_error(&a, "needs -o OUT.html");
    ibl_context *ctx = cli_context(&a.common);
    int rc = run(ctx, &a, a.positional[0], output, title);
    ibl_context_destroy(ctx);
    return rc;
}
