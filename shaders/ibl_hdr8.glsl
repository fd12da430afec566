/*
 * ibl_hdr8.glsl - the decodes of ibl's 8-bit HDR encodings (RGBM, RGBD, RGBE), the twins of
 * ibl_rgbm_decode, ibl_rgbd_decode and ibl_rgbe_decode (src/compress/hdr8.c): the same
 * operations in the same order, so a texel decodes to the same float on the GPU as in C
 * (tested bit for bit on Mesa's llvmpipe for every code of every channel against every alpha
 * code: tests/test_shaders_hdr8.c). Formulas and error bounds: docs/FORMATS.md "8-bit HDR
 * encodings".
 *
 * Dialects: include after your own #version line (GLSL 4.50, ES 3.00 / WebGL2, Vulkan); it
 * needs nothing from ibl.glsl and may come before or after it. Sample the R8G8B8A8_UNORM
 * texture as unorm (never through an sRGB view) and pass the texel t as returned. Each decode
 * first recovers the stored bytes, q = floor(255 t + 0.5): exact for any unorm conversion
 * within half a step, so the result does not depend on how a GPU turns bytes into floats.
 * The bilinear filter blends encoded bytes, not radiance: fetch RGBE with nearest filtering
 * (its alpha is an exponent); RGBM and RGBD filter with an error that grows with the contrast
 * between neighbours.
 *
 * Precision: +, - and * are correctly rounded in GLSL, so RGBM and RGBE match the C bit for
 * bit on any conformant GPU (exp2 of an integer is exact on every driver we know of);
 * RGBD's one division is correctly rounded in C and within GLSL's 2.5 ulp elsewhere. A
 * decoded RGBE value below 2^-126 (alpha codes 1..10) may be flushed to 0 by a GPU that
 * does not keep denormals.
 */
#ifndef IBL_HDR8_GLSL
#define IBL_HDR8_GLSL

#ifdef GL_ES
precision highp float;
#endif

/* 1 / 255^2: RGBM's scale is alpha_code * range / 65025 */
const float IBL_HDR8_INV_65025 = 1.0 / 65025.0;

/* The stored bytes of a unorm texel, as floats 0..255. */
vec4 ibl_hdr8_codes(vec4 t)
{
    return floor(t * 255.0 + 0.5);
}

/* RGBM of range R: rgb = RGB8 * (A8 * (R / 65025)). */
vec3 ibl_decode_rgbm(vec4 t, float range)
{
    vec4 q = ibl_hdr8_codes(t);
    float scale = q.a * (range * IBL_HDR8_INV_65025);
    return q.rgb * scale;
}

/* RGBD: rgb = RGB8 / A8 (A8 = 0 read as 1). */
vec3 ibl_decode_rgbd(vec4 t)
{
    vec4 q = ibl_hdr8_codes(t);
    return q.rgb / max(q.a, 1.0);
}

/* RGBE (Ward, as in Radiance files): rgb = (RGB8 + 0.5) 2^(A8 - 136); black when A8 = 0.
 * The power of two is applied as two halves, 2^floor(e/2) then 2^(e - floor(e/2)), so no
 * factor is a denormal (2^-135 would be, and GPUs flush those) nor overflows; both products
 * are exact while the result is a normal float. */
vec3 ibl_decode_rgbe(vec4 t)
{
    vec4 q = ibl_hdr8_codes(t);
    float e = q.a - 136.0, e_low = floor(e * 0.5);
    return q.a == 0.0 ? vec3(0.0) : (q.rgb + 0.5) * exp2(e_low) * exp2(e - e_low);
}

#endif
