#version 460
// The coplanarity walk test kernel with a deliberate bias: the focusing factor without the
// interpolated normal's derivative (the tests must see it).
#define COPLANAR_TEST_FOCUSING_WITHOUT_DN
#include "passes/mnee_dr/tests/coplanar_walk.glsl"
