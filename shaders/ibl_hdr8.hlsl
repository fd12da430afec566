/*
 * ibl_hdr8.hlsl - the decodes of ibl's 8-bit HDR encodings (RGBM, RGBD, RGBE) in HLSL,
 * function for function the same as shaders/ibl_hdr8.glsl (read its header: the C twins in
 * src/compress/hdr8.c, the order of operations that makes the results bit-identical to the
 * C, the filtering and precision notes). Pass the texel of an R8G8B8A8_UNORM texture (not an
 * _SRGB view) as sampled. Needs nothing from ibl.hlsl.
 */
#ifndef IBL_HDR8_HLSL
#define IBL_HDR8_HLSL

/* 1 / 255^2: RGBM's scale is alpha_code * range / 65025 */
static const float IBL_HDR8_INV_65025 = 1.0 / 65025.0;

/* The stored bytes of a unorm texel, as floats 0..255. */
float4 ibl_hdr8_codes(float4 t)
{
    return floor(t * 255.0 + 0.5);
}

/* RGBM of range R: rgb = RGB8 * (A8 * (R / 65025)). */
float3 ibl_decode_rgbm(float4 t, float range)
{
    float4 q = ibl_hdr8_codes(t);
    float scale = q.a * (range * IBL_HDR8_INV_65025);
    return q.rgb * scale;
}

/* RGBD: rgb = RGB8 / A8 (A8 = 0 read as 1). */
float3 ibl_decode_rgbd(float4 t)
{
    float4 q = ibl_hdr8_codes(t);
    return q.rgb / max(q.a, 1.0);
}

/* RGBE (Ward, as in Radiance files): rgb = (RGB8 + 0.5) 2^(A8 - 136); black when A8 = 0.
 * The power of two is applied as two halves, 2^floor(e/2) then 2^(e - floor(e/2)), so no
 * factor is a denormal (2^-135 would be, and GPUs flush those) nor overflows; both products
 * are exact while the result is a normal float. */
float3 ibl_decode_rgbe(float4 t)
{
    float4 q = ibl_hdr8_codes(t);
    float e = q.a - 136.0, e_low = floor(e * 0.5);
    return q.a == 0.0 ? float3(0.0, 0.0, 0.0) : (q.rgb + 0.5) * exp2(e_low) * exp2(e - e_low);
}

#endif
