#version 460
// PathTracer's wavefront schedule: the paths of one sample per pixel advance a vertex per
// dispatch over a compacted list of the living ones (lib/work_list.glsl), and their shadow
// rays are traced by a dispatch of their own over a queue, so that an 8-lane SIMD group of
// lavapipe (or a GPU warp) runs one kind of work on paths that all still exist. After
// wavefrontDepth bounce dispatches, the last one runs the paths left to their end. Same
// path_vertex, same random numbers in the same order as the megakernel (path_tracer.comp).
// Stages (PT_STAGE): generate camera paths, bounce, shadow rays, finish into the images.
#define PT_WAVEFRONT
#include "passes/path_tracer/path_tracer_common.glsl"
#include "lib/work_list.glsl"

#define PT_STAGE_GENERATE 0
#define PT_STAGE_BOUNCE 1
#define PT_STAGE_SHADOW 2
#define PT_STAGE_FINISH 3

#if PT_STAGE == PT_STAGE_GENERATE || PT_STAGE == PT_STAGE_FINISH
layout(local_size_x = 8, local_size_y = 8) in;
#else
layout(local_size_x = WORK_LIST_GROUP) in;
#endif

// One pixel's path between dispatches, and its sums over the chunk's samples.
struct WavefrontPath {
    vec4 o;         // w: depth (bits)
    vec4 d;         // w: prev_pdf
    vec4 beta;      // w: flags (bits, PT_FLAG_*) | coverage: chain length << 8, smooth
                    // vertices << 16, specular run << 24
    vec4 prev_p;    // w: rays of this chunk (bits)
    vec4 L;         // w: given first hit: prim (bits)
    vec4 L_direct;  // w: given first hit: bary.x
    vec4 albedo;    // w: given first hit: bary.y
    vec4 normal;    // w: shutter time of the path
    uvec4 rng;
    vec4 shadow_o;  // w: tmax
    vec4 shadow_d;  // w: 1 when direct
    vec4 shadow_c;
    vec4 sum_color, sum_direct, sum_albedo, sum_normal;
};
layout(std430) buffer WavefrontPaths { WavefrontPath paths[]; };

// Two queues of paths with a pending shadow ray: bounce dispatch k fills queue k % 2, which
// the shadow dispatch after it traces; bounce k clears queue (k + 1) % 2 (traced by then).
layout(std430) buffer WavefrontShadows {
    uvec4 shadow_count;      // x, y: queue lengths
    uvec4 shadow_args[2];    // indirect dispatch arguments per queue
    uint shadow_items[];     // queue q at [q * pixels, (q + 1) * pixels)
};

const uint PT_FLAG_PREV_DELTA = 1u, PT_FLAG_COV_OPEN = 2u, PT_FLAG_COV_CASTER = 4u,
           PT_FLAG_GIVEN = 16u, PT_FLAG_FIRST_FOUND = 32u;

uint pixel_count() { return pc.frameSize.x * pc.frameSize.y; }

void load_path(uint i, out PathVertexState st, out PathRadiance r, out Rng rng, out uint flags) {
    // Member by member: a copy of the whole record would load all 16 vec4s every bounce.
    st.o = paths[i].o.xyz;
    st.depth = floatBitsToUint(paths[i].o.w);
    st.d = paths[i].d.xyz;
    st.prev_pdf = paths[i].d.w;
    st.beta = paths[i].beta.xyz;
    flags = floatBitsToUint(paths[i].beta.w);
    st.prev_delta = (flags & PT_FLAG_PREV_DELTA) != 0u;
    st.cov.open = (flags & PT_FLAG_COV_OPEN) != 0u;
    st.cov.caster = (flags & PT_FLAG_COV_CASTER) != 0u;
    st.cov.chain_length = (flags >> 8u) & 0xFFu;
    st.cov.smooth_count = (flags >> 16u) & 0xFFu;
    st.cov.run = flags >> 24u;
    st.prev_p = paths[i].prev_p.xyz;
    r = path_radiance_none();
    r.rays = floatBitsToUint(paths[i].prev_p.w);
    r.L = paths[i].L.xyz;
    r.L_direct = paths[i].L_direct.xyz;
    r.albedo = paths[i].albedo.xyz;
    r.normal = paths[i].normal.xyz;
    rng.state = paths[i].rng;
}

void store_path(uint i, PathVertexState st, PathRadiance r, Rng rng, uint keep_flags) {
    uint flags = keep_flags & (PT_FLAG_GIVEN | PT_FLAG_FIRST_FOUND);
    if (st.prev_delta) flags |= PT_FLAG_PREV_DELTA;
    if (st.cov.open) flags |= PT_FLAG_COV_OPEN;
    if (st.cov.caster) flags |= PT_FLAG_COV_CASTER;
    flags |= min(st.cov.chain_length, 255u) << 8u;
    flags |= min(st.cov.smooth_count, 255u) << 16u;
    flags |= min(st.cov.run, 255u) << 24u;
    paths[i].o = vec4(st.o, uintBitsToFloat(st.depth));
    paths[i].d = vec4(st.d, st.prev_pdf);
    paths[i].beta = vec4(st.beta, uintBitsToFloat(flags));
    paths[i].prev_p = vec4(st.prev_p, uintBitsToFloat(r.rays));
    paths[i].L.xyz = r.L;
    paths[i].L_direct.xyz = r.L_direct;
    paths[i].albedo.xyz = r.albedo;
    paths[i].normal.xyz = r.normal;
    paths[i].rng = rng.state;
}

#if PT_STAGE == PT_STAGE_GENERATE
void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (gl_GlobalInvocationID.x == 0u && gl_GlobalInvocationID.y == 0u) {
        shadow_count = uvec4(0u);
        shadow_args[0] = uvec4(0u, 1u, 1u, 0u);
        shadow_args[1] = uvec4(0u, 1u, 1u, 0u);
    }
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint i = pixel.y * pc.frameSize.x + pixel.x;
    Rng rng;
    if (pc.sampleIndex == 0u) {
        rng = pt_rng(pixel);
        paths[i].sum_color = vec4(0.0);
        paths[i].sum_direct = vec4(0.0);
        paths[i].sum_albedo = vec4(0.0);
        paths[i].sum_normal = vec4(0.0);
    } else {
        rng.state = paths[i].rng;
    }
    vec3 o, d;
    bool given, first_found;
    Hit first;
    float time = pt_camera_sample(pixel, pc.sampleIndex, rng, o, d, given, first, first_found);
    uint rays = pc.sampleIndex == 0u ? 0u : floatBitsToUint(paths[i].sum_color.w);
    PathRadiance r = path_radiance_none();
    r.rays = rays;
    uint flags = (given ? PT_FLAG_GIVEN : 0u) | (first_found ? PT_FLAG_FIRST_FOUND : 0u);
    store_path(i, path_start(o, d), r, rng, flags);
    paths[i].L.w = uintBitsToFloat(first.prim);
    paths[i].L_direct.w = first.bary.x;
    paths[i].albedo.w = first.bary.y;
    paths[i].normal.w = time;
    work_list_append(0u, i);
}

#elif PT_STAGE == PT_STAGE_BOUNCE
void main() {
    if (gl_GlobalInvocationID.x == 0u) {  // before any return: the list may be empty
        uint q = (pc.bounceRound + 1u) % 2u;
        shadow_count[q] = 0u;
        shadow_args[q] = uvec4(0u, 1u, 1u, 0u);
    }
    uint i;
    if (!work_list_item(pc.bounceRound, gl_GlobalInvocationID.x, i)) return;
    PathVertexState st;
    PathRadiance r;
    Rng rng;
    uint flags;
    load_path(i, st, r, rng, flags);
    scene_set_time(paths[i].normal.w);  // the path's shutter time
    PathSettings ps = pt_path_settings();
    bool more;
    do {
        Hit hit;
        bool found;
        if ((flags & PT_FLAG_GIVEN) != 0u && st.depth == 0u) {
            hit.t = 0.0;
            hit.prim = floatBitsToUint(paths[i].L.w);
            hit.bary = vec2(paths[i].L_direct.w, paths[i].albedo.w);
            found = (flags & PT_FLAG_FIRST_FOUND) != 0u;
        } else {
            ++r.rays;
            found = trace_closest(st.o, st.d, 0.0, 1e30, BVH_MASK_ALL, hit);
        }
        PendingShadow shadow;
        more = path_vertex(st, r, found, hit, ps, rng, shadow);
        if (shadow.valid) {
            ++r.rays;
            if (pc.finishPaths != 0u) {
                if (!trace_any(shadow.ray.o, shadow.ray.d, 0.0, shadow.ray.tmax, BVH_MASK_ALL))
                    path_add_shadow(r, shadow);
            } else {
                paths[i].shadow_o = vec4(shadow.ray.o, shadow.ray.tmax);
                paths[i].shadow_d = vec4(shadow.ray.d, shadow.direct ? 1.0 : 0.0);
                paths[i].shadow_c = vec4(shadow.c, 0.0);
                uint q = pc.bounceRound % 2u;
                uint slot = atomicAdd(shadow_count[q], 1u);
                shadow_items[q * pixel_count() + slot] = i;
                if (slot % WORK_LIST_GROUP == 0u) atomicAdd(shadow_args[q].x, 1u);
            }
        }
    } while (more && pc.finishPaths != 0u);
    store_path(i, st, r, rng, flags);
    if (more) work_list_append(pc.bounceRound + 1u, i);
    atomicMax(max_bvh_iterations, bvh_iterations);
}

#elif PT_STAGE == PT_STAGE_SHADOW
void main() {
    uint q = pc.bounceRound % 2u;
    if (gl_GlobalInvocationID.x >= shadow_count[q]) return;
    uint i = shadow_items[q * pixel_count() + gl_GlobalInvocationID.x];
    scene_set_time(paths[i].normal.w);
    vec4 so = paths[i].shadow_o, sd = paths[i].shadow_d;
    if (!trace_any(so.xyz, sd.xyz, 0.0, so.w, BVH_MASK_ALL)) {
        vec3 c = paths[i].shadow_c.xyz;
        paths[i].L.xyz += c;
        if (sd.w != 0.0) paths[i].L_direct.xyz += c;
    }
    atomicMax(max_bvh_iterations, bvh_iterations);
}

#elif PT_STAGE == PT_STAGE_FINISH
void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint i = pixel.y * pc.frameSize.x + pixel.x;
    PathRadiance r = path_radiance_none();
    r.L = paths[i].L.xyz;
    r.L_direct = paths[i].L_direct.xyz;
    r.albedo = paths[i].albedo.xyz;
    r.normal = paths[i].normal.xyz;
    PtPixelSums sums;
    sums.color = paths[i].sum_color.xyz;
    sums.direct = paths[i].sum_direct.xyz;
    sums.albedo = paths[i].sum_albedo.xyz;
    sums.normal = paths[i].sum_normal.xyz;
    pt_sums_add(sums, r);
    uint rays = floatBitsToUint(paths[i].prev_p.w);
    if (pc.sampleIndex + 1u < pc.dispatchSamples) {
        paths[i].sum_color = vec4(sums.color, uintBitsToFloat(rays));
        paths[i].sum_direct.xyz = sums.direct;
        paths[i].sum_albedo.xyz = sums.albedo;
        paths[i].sum_normal.xyz = sums.normal;
        return;
    }
    atomicAdd(ray_count, rays);
    pt_store(pixel, sums);
}
#endif
