#version 460
// Reservoir splatting, step 4 of the scatter (Liu et al. 2025, Sec. 4.2-4.3): per pixel, RIS over
// the canonical sample and every prior-frame sample that landed here. Each landed entry is
// shifted again (x1 kept, film offset where it landed, hybrid shift after x1) for its integrand
// here; MIS is Eq. 11 for splats and Eq. 13 for the canonical sample, whose reverse splat into
// the previous frame is evaluated for it; the confidence is Eq. 17.
#include "lib/bvh.glsl"
#include "lib/camera.glsl"
#include "lib/color.glsl"
#include "lib/restir/hybrid_shift.glsl"
#include "lib/restir/primary.glsl"
#include "lib/restir/reservoir.glsl"
#include "lib/restir/splat.glsl"
#include "lib/restir/temporal.glsl"
#include "lib/shading.glsl"
#include "passes/reservoir_splat/splat_buffers.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430) readonly buffer ReservoirsIn {
    RestirSettings settings_in;
    PathReservoir reservoirs_in[];
};
layout(std430) readonly buffer PrevReservoirs {
    RestirSettings settings_prev;
    PathReservoir reservoirs_prev[];
};
layout(std430) writeonly buffer ReservoirsOut {
    RestirSettings settings_out;
    PathReservoir reservoirs_out[];
};
layout(std430) readonly buffer PrimaryIn { PrimaryHit primary_in[]; };
layout(std430) readonly buffer PrevPrimary { PrimaryHit primary_prev[]; };
layout(rg32f) uniform readonly image2D motionImage;

layout(push_constant) uniform Params {
    uvec2 frameSize;
    uint frameIndex;
    uint seed;
    uint historyReset;
    float confidenceCap;
    float normalThreshold;
    float depthThreshold;
    uint movingSuffix;
    uint ablation;
} pc;

// Splats resampled per pixel at most (measured: about 1 on average, a few at most; zooming out
// by a factor z lands about z^2). Beyond it entries are dropped and counted (biased).
const uint MAX_SPLATS = 64u;

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.frameSize))) return;
    uint idx = pixel.y * pc.frameSize.x + pixel.x;
    RestirSettings cfg = settings_in;
    if (idx == 0u) settings_out = cfg;
    PathReservoir rc = reservoirs_in[idx];
    if (pc.historyReset != 0u || !restir_same_rules(settings_prev, cfg) || cfg.area == 0u) {
        if (cfg.area == 0u) atomicAdd(splat_not_area, 1u);
        reservoirs_out[idx] = rc;
        return;
    }
    atomicAdd(splat_pixels, 1u);
    Rng rng = rng_init(pixel, pc.frameIndex, pc.seed ^ 0x5B1A7C3Du);
    float Mc = rc.M, cap = max(pc.confidenceCap * Mc, Mc);
    bool reject_moved = pc.movingSuffix == MOVING_SUFFIX_REJECT;
    CameraFrame cam = camera_frame(scene_info.camera_open, scene_info.camera_open, 0.0);
    uvec2 fs = pc.frameSize;

    // The canonical sample's reverse splat T^-1(Y*): its x1 (its own primary ray here) projected
    // into the previous camera with the same lens sample and visible there. Two rays through one
    // traversal site, as in splat_forward.comp.
    PathSample s_rev = rc.s;
    PrimaryHit dst_rev;
    dst_rev.camera = vec4(0.0);
    dst_rev.hit = uvec4(~0u);
    float J_rev = 0.0, c_r = 0.0;
    bool rev_ok = false;
    if (rc.W > 0.0) {
        atomicAdd(splat_reverse_attempts, 1u);
        vec3 o, d;
        camera_ray(cam, (vec2(pixel) + rc.s.film_lens.xy) / vec2(fs), rc.s.film_lens.zw, o, d);
        float tmax = 1e30;
        bool any_hit = false;
        FilmProjection here, prev;
        float area_here = 0.0, area_prev = 0.0;
        for (uint step = 0u; step < 2u; ++step) {
            scene_select_frame(step == 1u);
            Hit hit;
            bool found = bvh_traverse(o, d, 0.0, tmax, BVH_MASK_ALL, any_hit, hit);
            if (step == 1u) {
                rev_ok = !found;
                break;
            }
            if (!found) break;
            SurfacePoint xc = surface_point(hit.prim, hit.bary);
            area_here = xc.area;
            bool front = splat_project(scene_info.camera_open, rc.s.film_lens.zw, xc.p, xc.ng, fs, here);
            scene_select_frame(true);
            SurfacePoint xp = surface_point(hit.prim, hit.bary);
            area_prev = xp.area;
            if (!front || !splat_project(scene_info.camera_prev, rc.s.film_lens.zw, xp.p, xp.ng, fs, prev) ||
                !film_on_screen(prev.film, fs))
                break;
            dst_rev.camera = vec4(prev.lens_point, 1.0);
            dst_rev.hit = uvec4(hit.prim, floatBitsToUint(hit.bary), 0u);
            ShadowRay sr = shadow_ray_between(prev.lens_point, vec3(0.0), xp.p, xp.ng);
            o = sr.o;
            d = sr.d;
            tmax = sr.tmax;
            any_hit = true;
        }
        scene_select_frame(false);
        J_rev = splat_jacobian(here, area_here, prev, area_prev);
        rev_ok = rev_ok && J_rev > 0.0 && !isinf(J_rev) && !restir_crosses_moved_suffix(rc.s, reject_moved);
        if (rev_ok) {
            uvec2 r = min(uvec2(floor(prev.film)), fs - 1u);
            s_rev.film_lens.xy = clamp(prev.film - vec2(r), vec2(0.0), vec2(1.0 - 1e-7));
            c_r = min(reservoirs_prev[r.y * fs.x + r.x].M, cap);
            atomicAdd(splat_reverse_success, 1u);
        }
    }

    // Shifts through one restir_shift: first the reverse splat (previous geometry), then the
    // splats that landed here in ascending source order, so the result does not depend on the
    // order the atomics filled the list in.
    uvec2 range = splat_ranges[idx];
    uint n_list = min(range.x, MAX_SPLATS);
    if (range.x > MAX_SPLATS) atomicAdd(splat_dropped, range.x - MAX_SPLATS);
    PathReservoir r = reservoir_empty();
    float t_rev = 0.0, c_splats = 0.0;
    uint last_src = 0u;
    for (uint j = 0u; j <= n_list; ++j) {
        PathSample s;
        PrimaryHit dst;
        uint src = ~0u;
        if (j == 0u) {
            if (!rev_ok) continue;
            s = s_rev;
            dst = dst_rev;
        } else {
            for (uint e = 0u; e < range.x; ++e) {
                uint c = splat_lists[range.y + e];
                if ((j == 1u || c > last_src) && c < src) src = c;
            }
            last_src = src;
            SplatRecord rec = splat_records[src];
            s = reservoirs_prev[src].s;
            s.film_lens.xy = rec.dst_off;
            dst.camera = vec4(camera_lens_point(cam, s.film_lens.zw), 1.0);
            dst.hit = uvec4(rec.prim, floatBitsToUint(rec.bary), 0u);
        }
        bool ok = !restir_crosses_moved_suffix(s, reject_moved);
        scene_select_frame(j == 0u);
        vec3 F = ok ? restir_shift(cfg, s, dst) : vec3(0.0);
        scene_select_frame(false);
        if (j == 0u) {
            t_rev = luminance(F);
            continue;
        }
        atomicAdd(splat_resampled, 1u);
        PathReservoir rq = reservoirs_prev[src];
        float c_i = min(rq.M, cap), t_here = luminance(F), J = splat_records[src].J;
        c_splats += c_i;
        float m = splat_mis_prior(c_i, rq.target, Mc, t_here, J);
        reservoir_add(r, s, F, t_here, m * t_here * rq.W * J, rng_next(rng));
    }
    float m_c = pc.ablation == ABLATION_NO_REVERSE_SPLAT
                    ? 1.0
                    : splat_mis_canonical(Mc, rc.target, c_r, t_rev, J_rev);
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));

    // Confidence (Eq. 17): the canonical's plus the previous confidences bilinearly interpolated
    // at this pixel centre's back-projection (taps of dissimilar surfaces count 0), capped. Summing
    // the splats' confidences instead (ablation) makes the confidence depend on where the
    // previous samples landed, which is biased.
    float M_prev = 0.0;
    if (pc.ablation == ABLATION_SUM_SPLAT_CONFIDENCES) {
        M_prev = c_splats;
    } else {
        PrimaryHit hc = primary_in[idx];
        vec2 base = vec2(pixel) + imageLoad(motionImage, ivec2(pixel)).xy;
        ivec2 q0 = ivec2(floor(base));
        vec2 f = base - vec2(q0);
        for (uint i = 0u; i < 4u; ++i) {
            ivec2 q = q0 + ivec2(i & 1u, i >> 1);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(fs)))) continue;
            if (!restir_similar(hc, primary_prev[pixel_index(q)], true, pc.normalThreshold,
                                pc.depthThreshold))
                continue;
            vec2 cover = mix(1.0 - f, f, vec2(i & 1u, i >> 1));
            M_prev += cover.x * cover.y * min(reservoirs_prev[pixel_index(q)].M, cap);
        }
    }
    r.M = min(Mc + M_prev, cap);
    reservoir_finalize(r);
    reservoirs_out[idx] = r;
}
