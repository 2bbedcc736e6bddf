// Lets one header compile as GLSL and as C++ (pbrt-v4's PBRT_CPU_GPU habit).
//
// Shared headers write plain GLSL that C++ also accepts:
//   FN          before every function (inline in C++),
//   INOUT(T)    for inout parameters, OUT(T) for out parameters,
//   PRECISE     GLSL's `precise` (no reassociation; C++ does not reassociate without -ffast-math),
//   uint, vec3, ... are glm types in C++.
// C++ sees the shared code inside namespace telescope::shader.
#ifndef TELESCOPE_LANG_H
#define TELESCOPE_LANG_H

#ifdef __cplusplus
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>
#define FN inline
#define INOUT(T) T&
#define OUT(T) T&
#define CONST constexpr
#define PRECISE
#define SHADER_NAMESPACE_BEGIN namespace telescope { namespace shader { using namespace glm; using uint = uint32_t;
#define SHADER_NAMESPACE_END } }
#else
#define FN
#define INOUT(T) inout T
#define OUT(T) out T
#define CONST const
#define PRECISE precise
#define SHADER_NAMESPACE_BEGIN
#define SHADER_NAMESPACE_END
#endif

// LOOP_BUDGET_SPENT(n): counts n loop iterations of this lane against its loop budget and says
// whether the budget is spent (shared/gpu_types.h, "Lavapipe's loop cap"); LOOP_BUDGET_TICK(n)
// only counts. Long data-dependent loops stop when the budget is spent; short bounded ones only
// count. A shader with a budget (path_trace) defines both before its includes; everywhere else
// they fold away.
#ifndef LOOP_BUDGET_SPENT
#define LOOP_BUDGET_SPENT(n) false
#define LOOP_BUDGET_TICK(n)
#endif

SHADER_NAMESPACE_BEGIN
CONST float kPi = 3.14159265358979323846f;
CONST float kInvPi = 0.31830988618379067154f;
CONST float kInfinity = 3.0e38f;
SHADER_NAMESPACE_END

#endif
