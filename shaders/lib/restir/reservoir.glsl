// Path reservoirs for ReSTIR PT (Lin et al. 2022): the stored path sample (what a shift needs to
// rebuild the path at another pixel), the reservoir around it, the per-pixel primary hit and the
// settings that travel with the reservoirs, so every stage shifts with the rules the sample was
// generated under. Layouts are mirrored by passes/ReSTIRPTInitial/PathReservoir.h.
#ifndef LOOM_RESTIR_RESERVOIR_GLSL
#define LOOM_RESTIR_RESERVOIR_GLSL

#include "lib/rng.glsl"

// Shift mappings (RestirSettings.shift): SHIFT_HYBRID (replay up to the reconnection vertex,
// then reconnect), SHIFT_RECONNECTION (reconnect at the secondary hit x2, else fail),
// SHIFT_REPLAY (random replay of the whole path). A registered shader enum: the values come
// from its declaration in passes/restir_pt/PathReservoir.cpp.

// How the reconnection vertex x_k is stored (PathSample.flags bits 9-10).
const uint RC_SURFACE = 0u;    // triangle (rc_id) + barycentrics: a scattering vertex or an emitter
const uint RC_DIRECTION = 1u;  // environment / directional light along rc_dir (k == n only)
const uint RC_POINT = 2u;      // point or spot light rc_id (k == n only)

// Settings written by the initial-sampling pass into the reservoir buffer header.
struct RestirSettings {
    uint max_bounces;        // scattering events per path, as PathTracer.maxBounces
    uint shift;              // SHIFT_*
    float rough_threshold;   // hybrid shift: both reconnection endpoints need alpha > this
    float dist_threshold;    // hybrid shift: reconnection segment length >= this
    uvec2 frame_size;
    uint mis_heuristic;      // NEE/BSDF MIS inside a path (MIS_HEURISTIC_*)
    uint area;               // Area ReSTIR: film and lens samples belong to the path sample
                             // (RESTIR_AREA), and with RESTIR_AREA_TIME the shutter time too
    // > 0: paths a caustic estimator produces are left out (manifold/coverage.glsl: chains of up
    // to covered_max_chain specular vertices after a receiver at most covered_depth deep), so
    // that ReSTIR PT composes with it without counting them twice. 0: every path.
    uint covered_max_chain;
    uint covered_depth;
};

const uint RESTIR_AREA = 1u;
const uint RESTIR_AREA_TIME = 2u;

// Whether samples carry a shutter time (camera motion blur).
bool restir_has_time(RestirSettings cfg) { return (cfg.area & RESTIR_AREA_TIME) != 0u; }

// A path x1 .. xn after the camera vertex x0 (x1 = the pixel's primary hit, n >= 2). Vertex xj
// uses the random numbers of counters 4j+1 .. 4j+4 of the replay stream `seed`.
// The integrand is stored in a mixed measure: primary sample space for the directions before
// x_{k-1}, area (or direction) at the reconnection vertex x_k, solid angle after it. Under the
// hybrid shift this measure is preserved, so its Jacobian is 1 (see hybrid_shift.glsl).
struct PathSample {
    uvec4 seed;       // replay stream (rng state with counter 0)
    uint flags;       // 0-3 n, 4-7 k (0 = no reconnection vertex), 8 last vertex by NEE,
                      // 9-10 RC_* kind, 11 last vertex is a delta light
    uint rc_id;       // RC_SURFACE: triangle; RC_POINT/RC_DIRECTION: light index
    vec2 rc_bary;     // RC_SURFACE barycentrics
    vec3 rc_dir;      // k < n: direction x_k -> x_{k+1}; RC_DIRECTION: direction to the light
    float light_pdf;  // k == n-1: light-sampling pdf (solid angle at x_k) of x_n, for MIS
    vec3 rc_Lo;       // f products after x_k times Le (times the last MIS weight when k < n-1)
    float time;       // Area ReSTIR with motion blur: shutter fraction in [0,1) of the camera ray
    vec4 film_lens;   // Area ReSTIR: subpixel offset xy in [0,1)^2, lens sample zw
};

struct PathReservoir {
    PathSample s;
    vec3 F;        // integrand of s at the pixel owning this reservoir
    float W;       // unbiased contribution weight: pixel estimate = F * W
    float M;       // confidence
    float target;  // luminance(F)
    float w_sum;   // streaming RIS weight sum
    uint pad;
};

// The pixel's primary hit: the camera vertex x0 (lens point) and x1.
struct PrimaryHit {
    vec4 camera;  // xyz x0
    uvec4 hit;    // x triangle (~0u = miss), yz barycentric bits, w unused
};

uint path_length(PathSample s) { return s.flags & 15u; }
uint path_rc_index(PathSample s) { return (s.flags >> 4) & 15u; }
bool path_last_nee(PathSample s) { return (s.flags & 256u) != 0u; }
uint path_rc_kind(PathSample s) { return (s.flags >> 9) & 3u; }
bool path_last_delta_light(PathSample s) { return (s.flags & 2048u) != 0u; }
uint path_pack_flags(uint n, uint k, bool last_nee, uint kind, bool delta_light) {
    return n | (k << 4) | (last_nee ? 256u : 0u) | (kind << 9) | (delta_light ? 2048u : 0u);
}

bool primary_valid(PrimaryHit h) { return h.hit.x != ~0u; }

PathReservoir reservoir_empty() {
    PathReservoir r;
    r.s.seed = uvec4(0u);
    r.s.flags = 0u;
    r.s.rc_id = 0u;
    r.s.rc_bary = vec2(0.0);
    r.s.rc_dir = vec3(0.0);
    r.s.light_pdf = 0.0;
    r.s.rc_Lo = vec3(0.0);
    r.s.time = 0.0;
    r.s.film_lens = vec4(0.5, 0.5, 0.5, 0.5);
    r.F = vec3(0.0);
    r.W = 0.0;
    r.M = 0.0;
    r.target = 0.0;
    r.w_sum = 0.0;
    r.pad = 0u;
    return r;
}

// Streaming RIS (Talbot et al. 2005; Bitterli et al. 2020, Alg. 2): add a candidate with
// resampling weight w whose integrand at this pixel is F. Returns true when it was selected.
bool reservoir_add(inout PathReservoir r, PathSample s, vec3 F, float target, float w, float u) {
    if (!(w > 0.0) || isinf(w)) return false;
    r.w_sum += w;
    if (u * r.w_sum < w) {
        r.s = s;
        r.F = F;
        r.target = target;
        return true;
    }
    return false;
}

// W = w_sum / p_hat(Y): the resampling weights already carry the MIS (or 1/M) normalisation.
void reservoir_finalize(inout PathReservoir r) {
    r.W = r.target > 0.0 ? r.w_sum / r.target : 0.0;
    if (r.W == 0.0) r.F = vec3(0.0);
    r.w_sum = 0.0;
}

#endif
