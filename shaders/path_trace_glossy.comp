// The path tracer with the glossy materials (shared/bsdf.h glossy*) compiled in: chosen by the host
// for scenes that use any (SceneFeatures::bsdfFamilies); kSpecBsdfFamilies folds out the families
// the scene lacks.
#version 460
#extension GL_GOOGLE_include_directive : require
#define TELESCOPE_GLOSSY 1
#include "path_trace_main.glsl"
