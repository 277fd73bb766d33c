#version 460
// The coplanarity walk test kernel (coplanar_walk.glsl).
#include "passes/mnee_dr/tests/coplanar_walk.glsl"
