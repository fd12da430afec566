/*
 * ibl.h - umbrella header of libibl, a C library for physically based image-based lighting.
 *
 * Start with core.h (context, images, cubemaps, textures), then io.h (files), layout.h (2D
 * layouts <-> cubemaps), cubemap.h (geometry and sampling), compress.h (BC6H, RGBM/RGBD/RGBE). The bake stages (sh.h,
 * irradiance.h, specular.h, brdf.h, sky.h) take cubemaps and return plain data; shade.h
 * evaluates baked data at runtime, light.h punctual lights; shader.h gives shaders/ibl.glsl
 * and ibl.hlsl their uniform block. docs/ has the design, conventions and measurements.
 */
#ifndef IBL_IBL_H
#define IBL_IBL_H

#include "brdf.h"
#include "compress.h"
#include "core.h"
#include "cubemap.h"
#include "io.h"
#include "layout.h"
#include "light.h"
#include "probes.h"
#include "sh.h"
#include "irradiance.h"
#include "edge_fixup.h"
#include "render.h"
#include "scene.h"
#include "shade.h"
#include "shader.h"
#include "skin.h"
#include "sky.h"
#include "specular.h"
#include "target.h"

#endif
