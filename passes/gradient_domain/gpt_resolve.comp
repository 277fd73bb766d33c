#version 460
// The gradient estimators' images from their per-pixel sums (gradient_pixels.glsl; gpt.comp,
// G-PT, Kettunen et al. 2015, and gradient_after_restir.comp): the two-sided gradients
// (each pixel pair's two MIS-weighted one-sided estimates, summed), the primal (the pixel's own
// weighted share plus the shares its four neighbours' shifted paths brought), both without the
// emission seen at the primary hit, and that emission. Forward differences with the Neumann
// convention PoissonReconstruct expects: dx(p) = I(p + e_x) - I(p), 0 in the last column.
#include "passes/gradient_domain/gradient_pixels.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer GradientPixels { GradientPixel gradient_pixels[]; };
layout(rgba32f) uniform writeonly image2D primalImage;
layout(rgba32f) uniform writeonly image2D dxImage;
layout(rgba32f) uniform writeonly image2D dyImage;
layout(rgba32f) uniform writeonly image2D directImage;
#if HAS_COLOR
layout(rgba32f) uniform writeonly image2D colorImage;
#endif

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint samplesPerPixel;
} pc;

uint pixel_index(ivec2 p) { return uint(p.y) * pc.frameSize.x + uint(p.x); }

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(p), pc.frameSize))) return;
    float inv = 1.0 / float(pc.samplesPerPixel);
    GradientPixel here = gradient_pixels[pixel_index(p)];
    bool right = uint(p.x) + 1u < pc.frameSize.x, below = uint(p.y) + 1u < pc.frameSize.y;
    vec3 primal = here.primal.rgb;
    vec3 dx = vec3(0.0), dy = vec3(0.0);
    // The neighbour at +x shifted its path by -x (index 1) onto this pixel, and so on.
    if (right) {
        GradientPixel n = gradient_pixels[pixel_index(p + ivec2(1, 0))];
        primal += n.neighbour[1].rgb;
        dx = here.gradient[0].rgb - n.gradient[1].rgb;
    }
    if (p.x > 0) primal += gradient_pixels[pixel_index(p - ivec2(1, 0))].neighbour[0].rgb;
    if (below) {
        GradientPixel n = gradient_pixels[pixel_index(p + ivec2(0, 1))];
        primal += n.neighbour[3].rgb;
        dy = here.gradient[2].rgb - n.gradient[3].rgb;
    }
    if (p.y > 0) primal += gradient_pixels[pixel_index(p - ivec2(0, 1))].neighbour[2].rgb;
    imageStore(primalImage, p, vec4(primal * inv, 1.0));
    imageStore(dxImage, p, vec4(dx * inv, 0.0));
    imageStore(dyImage, p, vec4(dy * inv, 0.0));
    imageStore(directImage, p, vec4(here.direct.rgb * inv, 1.0));
#if HAS_COLOR
    imageStore(colorImage, p, vec4((primal + here.direct.rgb) * inv, 1.0));
#endif
}
