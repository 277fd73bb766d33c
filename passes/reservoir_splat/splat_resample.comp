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
    uint mode;
    uint timePartitions;
    uint ablation;
} pc;

// Splats resampled per pixel at most (measured: about 1 on average, a few at most; zooming out
// by a factor z lands about z^2). Beyond it entries are dropped and counted (biased).
const uint MAX_SPLATS = 64u;

uint pixel_index(ivec2 q) { return uint(q.y) * pc.frameSize.x + uint(q.x); }

// Where a job's path starts in its destination frame: x1 found by tracing the camera ray of a
// film position (lens-vertex copy), or x1 kept (a splat) and checked visible from the lens point.
struct X1 {
    uint prim;
    vec2 bary;
    bool valid;
};

// Jobs, run in this order through one primary traversal and one restir_shift:
const uint JOB_CANONICAL_PRIMARY = 0u;  // Y*'s x1 here (no shift)
const uint JOB_CANONICAL_REVERSE = 1u;  // T^-1(Y*): x1 kept, into the previous frame
const uint JOB_CANONICAL_BACKUP = 2u;   // Y* copied into the backup pixel (previous frame)
const uint JOB_BACKUP_HERE = 3u;        // the backup pixel's sample copied here
const uint JOB_BACKUP_REVERSE = 4u;     // T^-1 of that copy: x1 kept, into the previous frame
const uint JOB_SPLATS = 5u;             // then per landed splat: here, and copied to the backup

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
    uvec2 fs = pc.frameSize;
    PrimaryHit hc = primary_in[idx];
    vec2 motion = imageLoad(motionImage, ivec2(pixel)).xy;
    // Multi-splat time partitions (Sec. 4.4), for samples that carry a time.
    uint K = pc.mode == MODE_MULTI_SCATTER && restir_has_time(cfg) ? pc.timePartitions : 1u;
    // The MIS weights leave multi-splatting's 1/K time Jacobian out, consistently for the splats
    // and the canonical sample's reverse splat (a valid choice of weights: they still sum to 1);
    // only the resampling weight carries it. With the 1/K in the MIS the canonical sample's weight
    // drops K-fold and the error grows with K (fine_geometry, 1-frame shutter, K = 4: relMSE
    // 0.93 against 0.66 without). time_jacobian undoes the 1/K the forward splat put into J.
    float time_jacobian = pc.ablation == ABLATION_NO_TIME_JACOBIAN ? 1.0 : float(K);

    // The backup technique (scatter_backup): the previous pixel at the rounded motion vector,
    // when its surface is similar to this pixel's (a choice independent of the samples).
    ivec2 qb = ivec2(floor(vec2(pixel) + 0.5 + motion));
    bool backup = pc.mode == MODE_SCATTER_BACKUP && all(greaterThanEqual(qb, ivec2(0))) &&
                  all(lessThan(qb, ivec2(fs))) &&
                  restir_similar(hc, primary_prev[pixel_index(qb)], true, pc.normalThreshold,
                                 pc.depthThreshold);
    PathReservoir rb = backup ? reservoirs_prev[pixel_index(qb)] : reservoir_empty();
    float c_b = backup ? min(rb.M, cap) : 0.0;
    // With a backup the prior frame is reached twice: scatter and backup confidences are halved.
    float half_prior = backup ? 0.5 : 1.0;

    uvec2 range = splat_ranges[idx];
    uint n_list = min(range.x, MAX_SPLATS);
    if (range.x > MAX_SPLATS) atomicAdd(splat_dropped, range.x - MAX_SPLATS);

    PathReservoir r = reservoir_empty();
    X1 x_canonical, x_backup;
    x_canonical.valid = false;
    x_backup.valid = false;
    float t_rev = 0.0, J_rev = 0.0, c_r = 0.0;       // the canonical sample's reverse splat
    float t_canonical_backup = 0.0;                  // its copy into the backup pixel
    vec3 F_backup = vec3(0.0);                       // the backup sample here
    PathSample s_backup = rb.s;
    float t_backup_rev = 0.0, J_backup_rev = 0.0, c_backup_r = 0.0;
    FilmProjection fp_canonical, fp_backup;          // footprints here of Y* and Y_b
    float area_canonical = 0.0, area_backup = 0.0;
    // The splat being resampled (jobs JOB_SPLATS + 2i and + 2i + 1).
    uint src = ~0u, last_src = 0u;
    PathSample s_splat;
    vec3 F_splat = vec3(0.0);
    float c_splats = 0.0;
    uint n_jobs = JOB_SPLATS + 2u * n_list;
    for (uint j = 0u; j < n_jobs; ++j) {
        // Set the job up: the sample (film offset in the destination once known), its frame, and
        // how x1 is found.
        PathSample s = rc.s;
        bool prev = true, copy = true, trace = true, shift = true, valid = true;
        vec2 film = vec2(0.0);
        X1 x;
        x.valid = false;
        FilmProjection to;
        float area_to = 0.0, area_from = 0.0;
        FilmProjection from = fp_canonical;
        bool splat_here = j >= JOB_SPLATS && ((j - JOB_SPLATS) & 1u) == 0u;
        if (j == JOB_CANONICAL_PRIMARY) {
            valid = rc.W > 0.0;
            prev = false;
            film = vec2(pixel) + rc.s.film_lens.xy;
            shift = false;
        } else if (j == JOB_CANONICAL_REVERSE || j == JOB_BACKUP_REVERSE) {
            x = j == JOB_CANONICAL_REVERSE ? x_canonical : x_backup;
            if (j == JOB_BACKUP_REVERSE) {
                s = s_backup;
                from = fp_backup;
                area_from = area_backup;
            } else {
                area_from = area_canonical;
            }
            copy = false;
            valid = x.valid;
        } else if (j == JOB_CANONICAL_BACKUP) {
            valid = backup && rc.W > 0.0;
            film = vec2(qb) + rc.s.film_lens.xy;
        } else if (j == JOB_BACKUP_HERE) {
            valid = backup && rb.W > 0.0;
            s = rb.s;
            prev = false;
            film = vec2(pixel) + rb.s.film_lens.xy;
        } else if (splat_here) {
            // The next landed splat in ascending source order (deterministic whatever order the
            // atomics filled the list in). Its x1 was found visible by splat_forward.comp.
            src = ~0u;
            for (uint e = 0u; e < range.x; ++e) {
                uint c = splat_lists[range.y + e];
                if ((j == JOB_SPLATS || c > last_src) && c < src) src = c;
            }
            last_src = src;
            SplatRecord rec = splat_records[src];
            s = reservoirs_prev[src / MAX_TIME_PARTITIONS].s;
            s.film_lens.xy = rec.dst_off;
            s.time = splat_time_forward(s.time, src % MAX_TIME_PARTITIONS, K);
            s_splat = s;
            prev = false;
            copy = false;
            trace = false;
            x.prim = rec.prim;
            x.bary = rec.bary;
            x.valid = true;
        } else {
            // The landed splat copied into the backup pixel (the backup technique's term).
            valid = backup;
            s = s_splat;
            film = vec2(qb) + s_splat.film_lens.xy;
        }
        if (!valid) continue;
        // Kept x1 into the previous frame: project it through the same lens sample.
        if (!copy && prev) {
            s.time = splat_time_backward(s.time, K);
            CameraPose pose_prev = restir_sample_pose(cfg, s, true);  // at the reverse time
            scene_select_frame(true);
            SurfacePoint xp = surface_point(x.prim, x.bary);
            area_to = xp.area;
            scene_select_frame(false);
            if (!splat_project(pose_prev, s.film_lens.zw, xp.p, xp.ng, fs, to) ||
                !film_on_screen(to.film, fs))
                continue;
            uvec2 rp = min(uvec2(floor(to.film)), fs - 1u);
            s.film_lens.xy = clamp(to.film - vec2(rp), vec2(0.0), vec2(1.0 - 1e-7));
            film = to.film;
        }
        // x1: one traversal for every job (closest hit of a copied camera ray, or the kept x1's
        // visibility from the destination's lens point).
        CameraPose pose = restir_sample_pose(cfg, s, prev);
        CameraFrame cam = camera_frame(pose, pose, 0.0);
        vec3 lens_point = camera_lens_point(cam, s.film_lens.zw);
        if (trace) {
            vec3 o, d;
            float tmax = 1e30;
            if (copy) {
                camera_ray(cam, film / vec2(fs), s.film_lens.zw, o, d);
            } else {
                scene_select_frame(prev);
                SurfacePoint xk = surface_point(x.prim, x.bary);
                ShadowRay sr = shadow_ray_between(lens_point, vec3(0.0), xk.p, xk.ng);
                o = sr.o;
                d = sr.d;
                tmax = sr.tmax;
            }
            scene_select_frame(prev);
            Hit hit;
            atomicAdd(shift_rays, 1u);
            bool found = bvh_traverse(o, d, 0.0, tmax, BVH_MASK_ALL, !copy, hit);
            scene_select_frame(false);
            if (copy) {
                x.prim = hit.prim;
                x.bary = hit.bary;
                x.valid = found;
            } else {
                x.valid = !found;
            }
        }
        if (j == JOB_CANONICAL_PRIMARY || j == JOB_BACKUP_HERE) {
            // Footprints here, for the reverse splat that follows.
            if (x.valid) {
                SurfacePoint xc = surface_point(x.prim, x.bary);
                FilmProjection fp;
                x.valid = splat_project(pose, s.film_lens.zw, xc.p, xc.ng, fs, fp);
                if (j == JOB_CANONICAL_PRIMARY) {
                    x_canonical = x;
                    fp_canonical = fp;
                    area_canonical = xc.area;
                } else {
                    x_backup = x;
                    fp_backup = fp;
                    area_backup = xc.area;
                    s_backup = s;
                    s_backup.film_lens.xy = rb.s.film_lens.xy;
                }
            }
            if (!shift) continue;
        }
        vec3 F = vec3(0.0);
        if (x.valid && !restir_crosses_moved_suffix(s, reject_moved)) {
            PrimaryHit dst;
            dst.camera = vec4(lens_point, 1.0);
            dst.hit = uvec4(x.prim, floatBitsToUint(x.bary), 0u);
            scene_select_frame(prev);
            F = restir_shift(cfg, s, dst);
            scene_select_frame(false);
        }
        float t = luminance(F);
        if (j == JOB_CANONICAL_REVERSE || j == JOB_BACKUP_REVERSE) {
            float Jr = splat_jacobian(from, area_from, to, area_to);
            uvec2 rp = min(uvec2(floor(to.film)), fs - 1u);
            float c = half_prior * min(reservoirs_prev[rp.y * fs.x + rp.x].M, cap);
            if (!(Jr > 0.0) || isinf(Jr)) t = 0.0;
            if (j == JOB_CANONICAL_REVERSE) {
                t_rev = t;
                J_rev = Jr;
                c_r = c;
                if (t > 0.0) atomicAdd(splat_reverse_success, 1u);
            } else {
                t_backup_rev = t;
                J_backup_rev = Jr;
                c_backup_r = c;
            }
        } else if (j == JOB_CANONICAL_BACKUP) {
            t_canonical_backup = t;
        } else if (j == JOB_BACKUP_HERE) {
            F_backup = F;
        } else if (splat_here) {
            F_splat = F;
            if (backup) continue;  // its backup term comes next
        }
        if (j >= JOB_SPLATS) {
            // Resample the splat (Eq. 11) once its backup term is known.
            float t_copy = splat_here ? 0.0 : t;
            atomicAdd(splat_resampled, 1u);
            PathReservoir rq = reservoirs_prev[src / MAX_TIME_PARTITIONS];
            float c_i = half_prior * min(rq.M, cap), t_here = luminance(F_splat);
            float J = splat_records[src].J;
            c_splats += min(rq.M, cap);
            // MIS with the film Jacobian only (J carries 1/K: times K); the resampling weight
            // keeps the 1/K.
            float m = splat_mis_prior(c_i, rq.target, Mc, t_here, J * time_jacobian, 0.5 * c_b * t_copy);
            reservoir_add(r, s_splat, F_splat, t_here, m * t_here * rq.W * J, rng_next(rng));
        }
    }
    if (rc.W > 0.0) atomicAdd(splat_reverse_attempts, 1u);
    if (backup && rb.W > 0.0) {
        atomicAdd(splat_backup_attempts, 1u);
        float t_here = luminance(F_backup);
        float m = splat_mis_backup(0.5 * c_b, rb.target, Mc, t_here, c_backup_r, t_backup_rev,
                                   J_backup_rev);
        reservoir_add(r, s_backup, F_backup, t_here, m * t_here * rb.W, rng_next(rng));
        if (t_here > 0.0) atomicAdd(splat_backup_success, 1u);
    }
    float m_c = splat_mis_canonical(Mc, rc.target, c_r,
                                    pc.ablation == ABLATION_NO_REVERSE_SPLAT ? 0.0 : t_rev, J_rev,
                                    0.5 * c_b * t_canonical_backup);
    reservoir_add(r, rc.s, rc.F, rc.target, m_c * rc.target * rc.W, rng_next(rng));

    // Confidence (Eq. 17): the canonical's (and the backup's) plus the previous confidences
    // bilinearly interpolated at this pixel centre's back-projection (taps of dissimilar surfaces
    // count 0), capped. Summing the splats' confidences instead (ablation) makes the confidence
    // depend on where the previous samples landed, which is biased.
    float M_prev = c_b;
    if (pc.ablation == ABLATION_SUM_SPLAT_CONFIDENCES) {
        M_prev += c_splats;
    } else {
        vec2 base = vec2(pixel) + motion;
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
