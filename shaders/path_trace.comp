// The path tracer for scenes without glossy materials (path_trace_main.glsl): the glossy branch of
// path_tracer.glsl is not compiled in, so the pipeline's SPIR-V, and its creation time, stay those
// of the diffuse and specular path tracer.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "path_trace_main.glsl"
