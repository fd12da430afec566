/* stb_image compiled from Debian's header (libstb-dev) into the fuzz targets and replays, with
 * their instrumentation and sanitizers, in place of the prebuilt copy in libstb.a (which the
 * linker then leaves out: every stbi_ symbol the library uses is defined here first). */
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>
