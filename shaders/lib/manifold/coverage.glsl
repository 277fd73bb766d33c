// Which light paths specular manifold sampling produces, in one place: the SMS estimators
// (manifold/sms.glsl) build exactly these chains, and a path tracer combined with them drops
// exactly these paths (integrator/path.glsl), so that nothing is counted twice or lost. The
// reference code (Zeltner et al. 2020) instead skips all caster-to-light transport after
// depth 1, which also loses caustics seen from non-receivers.
//
// A covered path, from the camera: a receiver vertex x0 (tagged caustic_receiver, not a
// caster or bouncer, with a diffuse or glossy lobe) that is one of the camera path's first
// MANIFOLD_MAX_RECEIVERS vertices with a smooth lobe (1 unless a pass defines more: SMS at
// receivers behind diffuse bounces, as the reference integrator runs it at every depth), with
// at most receiver_depth specular vertices since the camera or the smooth vertex before (0: seen
// directly; 1: through one purely specular surface, e.g. a pool floor under water), left through
// a smooth lobe, then 1..maxChain specular vertices that the walk models (on casters or
// bouncers, at least one a caster; refraction through smooth dielectrics, reflection off smooth
// conductors), then an emitter tagged caustic_emitter, reached directly by the last segment.
#ifndef LOOM_MANIFOLD_COVERAGE_GLSL
#define LOOM_MANIFOLD_COVERAGE_GLSL

#include "lib/bsdf.glsl"
#include "lib/lights.glsl"
#include "lib/manifold/walk.glsl"
#include "lib/shading.glsl"

#ifndef MANIFOLD_MAX_RECEIVERS
#define MANIFOLD_MAX_RECEIVERS 1
#endif

bool manifold_receiver(uint shape_flags, Material m) {
    return (shape_flags & SHAPE_CAUSTIC_RECEIVER) != 0u &&
           (shape_flags & SHAPE_CAUSTIC_CASTER) == 0u &&
           (bsdf_flags(m) & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u;
}

// Whether a surface can hold a chain vertex (a caster, or a bouncer: the slab's far face).
bool manifold_chain_surface(uint shape_flags, Material m) {
    return (shape_flags & (SHAPE_CAUSTIC_CASTER | SHAPE_CAUSTIC_BOUNCER)) != 0u &&
           manifold_material_specular(m);
}

// Whether a sampled lobe is the one the walk takes there (refraction through dielectrics,
// reflection off conductors): delta, or glossy at a rough vertex the walk samples an offset
// normal for (MANIFOLD_ROUGH_CASTERS).
bool manifold_chain_lobe(Material m, uint bsdf_sample_flags) {
    uint want = manifold_material_reflects(m) ? BSDF_REFLECTION : BSDF_TRANSMISSION;
    uint lobe = BSDF_DELTA;
#ifdef MANIFOLD_ROUGH_CASTERS
    if (manifold_material_rough(m)) lobe = BSDF_GLOSSY;
#endif
    return (bsdf_sample_flags & want) != 0u && (bsdf_sample_flags & lobe) != 0u;
}

// A light SMS samples (its entry's flags carry the shape's or the light's tags).
bool manifold_emitter_light(uint light) {
    return (scene_light(light).flags & SHAPE_CAUSTIC_EMITTER) != 0u;
}

// An environment light (map or constant): SMS chains to it end at infinity in a sampled
// direction (manifold/sms.glsl).
bool manifold_light_is_environment(uint light) {
    uint t = scene_light(light).type;
    return light_is(t, LIGHT_ENVIRONMENT) || light_is(t, LIGHT_CONSTANT);
}

// Tracks, along a camera path, which vertices are receivers and whether the vertices since the
// last receiver form a covered chain.
struct ManifoldCoverage {
    uint chain_length;  // specular chain vertices since the receiver
    bool open;          // the path since the receiver is receiver (+ chain): a covered prefix
    bool caster;        // the chain has a caster vertex
    uint smooth_count;  // vertices with a smooth lobe so far
    uint run;           // vertices without one since the camera or the last smooth vertex
};

ManifoldCoverage manifold_coverage_none() {
    ManifoldCoverage c;
    c.chain_length = 0u;
    c.open = false;
    c.caster = false;
    c.smooth_count = 0u;
    c.run = 0u;
    return c;
}

// Whether path vertex sh, reached after c, is a receiver: a caustic estimator runs there, and
// the paths it produces leave through it. Independent of the lobe the path samples there.
bool manifold_coverage_receiver(ManifoldCoverage c, ShadingPoint sh, uint receiver_depth) {
    return c.smooth_count < uint(MANIFOLD_MAX_RECEIVERS) && c.run <= receiver_depth &&
           (sh.shape_flags & SHAPE_CAUSTIC_BOUNCER) == 0u &&
           manifold_receiver(sh.shape_flags, sh.mat);
}

// At a path vertex sh that scatters with sample flags `sample_flags`: extends an open chain
// (a chain surface scattering as the walk does), else opens one at a receiver, else closes it.
// max_chain = 0: no paths are covered (the receivers are still counted).
ManifoldCoverage manifold_coverage_step(ManifoldCoverage c, ShadingPoint sh, uint receiver_depth,
                                        uint max_chain, uint sample_flags) {
    bool receiver = manifold_coverage_receiver(c, sh, receiver_depth);
    bool extends = c.open && c.chain_length < max_chain &&
                   manifold_chain_surface(sh.shape_flags, sh.mat) &&
                   manifold_chain_lobe(sh.mat, sample_flags);
    if ((bsdf_flags(sh.mat) & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u) {
        c.smooth_count += 1u;
        c.run = 0u;
    } else {
        c.run += 1u;
    }
    if (extends) {
        c.caster = c.caster || (sh.shape_flags & SHAPE_CAUSTIC_CASTER) != 0u;
        c.chain_length += 1u;
        return c;
    }
    // SMS evaluates the receiver's smooth lobes only: a delta lobe (a plastic's coat) leaving
    // it starts no covered path.
    c.open = max_chain > 0u && receiver && (sample_flags & BSDF_DELTA) == 0u;
    c.chain_length = 0u;
    c.caster = false;
    return c;
}

// Whether the emitter the path reached after c (a triangle of shape flags `emitter_flags`)
// closes a covered path.
bool manifold_coverage_covers(ManifoldCoverage c, uint emitter_flags) {
    return c.open && c.caster && (emitter_flags & SHAPE_CAUSTIC_EMITTER) != 0u;
}

// Whether a miss after c (the path reached the environment) closes a covered path: only where
// the estimator produces chains that end in the environment (MANIFOLD_ENVIRONMENT_CHAINS, set
// by the passes whose walks sample it); elsewhere the path tracer keeps these paths.
bool manifold_coverage_covers_miss(ManifoldCoverage c) {
#if defined(MANIFOLD_ENVIRONMENT_CHAINS) && !defined(LOOM_TEST_KEEP_ENVIRONMENT_PATHS)
    // (LOOM_TEST_KEEP_ENVIRONMENT_PATHS: the double counting the SMS tests must detect.)
    uint li = scene_info.counts.w;
    return li != ~0u && manifold_coverage_covers(c, scene_light(li).flags);
#else
    return false;
#endif
}

// Whether a light sample taken at sh (after c) towards light `light`
// closes a covered path: at a rough chain vertex the path tracer's light sample reaches the
// emitter as its BSDF sample does, so both leave the covered paths out (wo, wi: local
// directions of the vertex). Smooth chains have no light samples on their vertices.
bool manifold_coverage_covers_light_sample(ManifoldCoverage c, ShadingPoint sh,
                                           uint receiver_depth, uint max_chain, vec3 wo,
                                           vec3 wi, uint light) {
#if defined(MANIFOLD_ROUGH_CASTERS) && !defined(LOOM_TEST_ROUGH_LIGHT_SAMPLES_KEPT)
    // (LOOM_TEST_ROUGH_LIGHT_SAMPLES_KEPT: the double counting the SMS tests must detect.)
    if (!c.open) return false;
    uint lobe = BSDF_GLOSSY | (wo.z * wi.z > 0.0 ? BSDF_REFLECTION : BSDF_TRANSMISSION);
    ManifoldCoverage next = manifold_coverage_step(c, sh, receiver_depth, max_chain, lobe);
#ifndef MANIFOLD_ENVIRONMENT_CHAINS
    if (manifold_light_is_environment(light)) return false;
#endif
    return manifold_coverage_covers(next, scene_light(light).flags);
#else
    return false;
#endif
}

#endif
