#version 460
// PoissonReconstruct: the row weights W^2 of the finest level. Uniform for L2 (and the first
// IRLS iteration); for L1, IRLS weights w^2 = 1 / (||e||_RGB + epsilon) from the residual e of
// each row at the current solution (Kettunen et al. 2015, Sec. 4.2). Also sums the weights
// and counts the rows, so that poisson_rhs can normalise them to mean 1.
#include "passes/gradient_domain/poisson_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform readonly image2D primalImage;
layout(rgba32f) uniform readonly image2D dxImage;
layout(rgba32f) uniform readonly image2D dyImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    float alpha;
    float epsilon;   // IRLS regulariser of this iteration
    uint reweight;   // 0: uniform weights; 1: IRLS weights from the solution at xOffset
    uint xOffset;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(uvec2(p), pc.frameSize));
    vec4 sums = vec4(0.0);
    if (inside) {
        uint i = poisson_index(p, pc.frameSize);
        bool right = uint(p.x) + 1u < pc.frameSize.x, below = uint(p.y) + 1u < pc.frameSize.y;
        vec3 wr = vec3(1.0, right ? 1.0 : 0.0, below ? 1.0 : 0.0);  // W^2 of the three rows
        if (pc.reweight != 0u) {
            vec3 x = vec[pc.xOffset + i].rgb;
            vec3 ep = pc.alpha * (imageLoad(primalImage, p).rgb - x);
            wr.x = 1.0 / (length(ep) + pc.epsilon);
            if (right) {
                vec3 ex = imageLoad(dxImage, p).rgb - (vec[pc.xOffset + i + 1u].rgb - x);
                wr.y = 1.0 / (length(ex) + pc.epsilon);
            }
            if (below) {
                vec3 ey = imageLoad(dyImage, p).rgb -
                          (vec[pc.xOffset + i + pc.frameSize.x].rgb - x);
                wr.z = 1.0 / (length(ey) + pc.epsilon);
            }
        }
        weight[i] = vec4(pc.alpha * pc.alpha * wr.x, wr.y, wr.z, 0.0);
        sums = vec4(wr.x + wr.y + wr.z, 1.0 + (right ? 1.0 : 0.0) + (below ? 1.0 : 0.0), 0, 0);
    }
    poisson_group_sum(sums, vec4(0.0));
}
