/* Internal: the documented defaults of the desc structs, named once. A zero field of a desc
 * means "the default"; each module resolves its desc at the API boundary with these. */
#ifndef IBL_CORE_DEFAULTS_H
#define IBL_CORE_DEFAULTS_H

/* Blinn-to-Phong factor f of tri-Ace 2010's fit cos^n(t) ~ cos^(f n)(t/2): a Blinn lobe of
 * exponent s is close to a Phong lobe of exponent s / f around the reflection vector. cmft and
 * CubeMapGen use 4. */
#define IBL_DEFAULT_BLINN_FACTOR 4.2f

/* The specular chain's shininess range when none is given: tri-Ace 2010's 32x32
 * configurations (1 to 1000). */
#define IBL_DEFAULT_SHININESS_MIN 1.0f
#define IBL_DEFAULT_SHININESS_MAX 1000.0f

/* The AmbientBRDF table's shininess axis when `ibl lut` or a caller gives none: the talk's
 * widest configuration (1 to 2000). */
#define IBL_DEFAULT_AMBIENT_TABLE_MIN 1.0
#define IBL_DEFAULT_AMBIENT_TABLE_MAX 2000.0

/* A bake's AmbientBRDF axis when the caller gives none, whatever the chain: wide enough for
 * every Blinn-Phong material, up to mirror-like 100000. */
#define IBL_DEFAULT_AMBIENT_SHININESS_MIN 1.0
#define IBL_DEFAULT_AMBIENT_SHININESS_MAX 100000.0
/* The AmbientBRDF's rows (shininess texels) when the caller gives none. */
#define IBL_DEFAULT_AMBIENT_ROWS 32

/* The shininess that stands for a mirror (unfiltered) level in a probe's level table. */
#define IBL_MIRROR_SHININESS 1e6f

/* The smallest GGX alpha a punctual light or the reference renderer evaluates: at alpha = 0
 * the lobe is a delta; 1e-3 is far below what any cube level resolves. */
#define IBL_MIN_GGX_ALPHA 1e-3f

/* The bake's parts. */
#define IBL_DEFAULT_IRRADIANCE_SIZE 16
#define IBL_DEFAULT_SH_BANDS 3
#define IBL_DEFAULT_LUT_SIZE 128
#define IBL_DEFAULT_PREVIEW_WIDTH 1024

#endif
