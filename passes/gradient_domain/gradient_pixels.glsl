// The per-pixel sums the gradient estimators of this family write (gpt.comp,
// gradient_after_restir.comp) and gpt_resolve.comp turns into the primal, gradient and emission
// images: for each direction d, a one-sided estimate of I(neighbour d) - I(here) and the share
// of the neighbour's primal that this pixel's shifted paths bring.
#ifndef LOOM_GRADIENT_PIXELS_GLSL
#define LOOM_GRADIENT_PIXELS_GLSL

struct GradientPixel {
    vec4 primal;        // this pixel's own (weighted) primal estimate
    vec4 neighbour[4];  // direction d's neighbour's primal share
    vec4 gradient[4];   // one-sided estimate of I(neighbour d) - I(here)
    vec4 direct;        // emission seen at the primary hit, kept out of the solve
};

// The directions d: +x, -x, +y, -y (image rows grow downwards).
const ivec2 kGradientOffsets[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));

bool gradient_inside(ivec2 q, uvec2 frame_size) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame_size)));
}

#endif
