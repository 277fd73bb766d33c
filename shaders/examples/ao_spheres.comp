#version 460
// Example ComputePass kernel (graphs/hello_compute.json): three analytic spheres on a plane,
// sun light plus sky, one cosine-weighted sky-visibility sample per pixel per frame. The
// Accumulate pass averages the frames into a converged image.
#include "lib/rng.glsl"
#include "lib/sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f) uniform writeonly image2D colorImage;
layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    vec3 sunDirection;
    float sunIntensity;
    float skyIntensity;
} pc;

const vec4 kSpheres[3] = vec4[3](vec4(-1.1, 0.5, 0.0, 0.5), vec4(0.0, 0.8, -0.4, 0.8),
                                 vec4(1.2, 0.35, 0.3, 0.35));
const vec3 kAlbedo[4] = vec3[4](vec3(0.8, 0.25, 0.2), vec3(0.25, 0.7, 0.3), vec3(0.2, 0.35, 0.8),
                                vec3(0.7));

// Closest hit against the spheres and the y=0 plane; returns t (or -1) and id/normal.
float intersect(vec3 o, vec3 d, out int id, out vec3 n) {
    float best = 1e30;
    id = -1;
    for (int i = 0; i < 3; ++i) {
        vec3 oc = o - kSpheres[i].xyz;
        float b = dot(oc, d), c = dot(oc, oc) - kSpheres[i].w * kSpheres[i].w;
        float disc = b * b - c;
        if (disc < 0.0) continue;
        float t = -b - sqrt(disc);
        if (t > 1e-4 && t < best) {
            best = t;
            id = i;
            n = normalize(o + t * d - kSpheres[i].xyz);
        }
    }
    if (d.y < 0.0) {
        float t = -o.y / d.y;
        if (t > 1e-4 && t < best) {
            best = t;
            id = 3;
            n = vec3(0, 1, 0);
        }
    }
    return id < 0 ? -1.0 : best;
}

vec3 sky(vec3 d) { return pc.skyIntensity * mix(vec3(0.9, 0.95, 1.0), vec3(0.4, 0.6, 1.0), max(d.y, 0.0)); }

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, pc.frameSize))) return;
    Rng rng = rng_init(p, pc.frameIndex, pc.seed);
    // Pinhole camera with per-frame jitter (antialiasing through accumulation).
    vec2 uv = (vec2(p) + rng_next2(rng)) / vec2(pc.frameSize);
    float aspect = float(pc.frameSize.x) / float(pc.frameSize.y);
    vec3 o = vec3(0.0, 1.2, 4.0);
    vec3 d = normalize(vec3((2.0 * uv.x - 1.0) * aspect * 0.45, (1.0 - 2.0 * uv.y) * 0.45 - 0.15, -1.0));
    int id;
    vec3 n;
    float t = intersect(o, d, id, n);
    vec3 color = sky(d);
    if (t > 0.0) {
        vec3 x = o + t * d;
        vec3 albedo = kAlbedo[id];
        vec3 l = normalize(pc.sunDirection);
        int sid;
        vec3 sn;
        float sun = intersect(x + 1e-3 * n, l, sid, sn) < 0.0 ? max(dot(n, l), 0.0) : 0.0;
        // One bounce of sky light: cosine sampling makes the estimator albedo * sky(wi) * V.
        vec3 wi = to_world(sample_cosine_hemisphere(rng_next2(rng)), n);
        vec3 skyLight = intersect(x + 1e-3 * n, wi, sid, sn) < 0.0 ? sky(wi) : vec3(0.0);
        color = albedo * (pc.sunIntensity * sun * INV_PI + skyLight);
    }
    imageStore(colorImage, ivec2(p), vec4(color, 1.0));
}
