// Rules every temporal reuse kernel applies (ReSTIRPTTemporal's gather, ReservoirSplatTemporal's
// scatter): whether last frame's reservoirs may be shifted at all, and which paths cannot cross
// frames once shapes have moved.
#ifndef LOOM_RESTIR_TEMPORAL_GLSL
#define LOOM_RESTIR_TEMPORAL_GLSL

#include "lib/restir/reservoir.glsl"
#include "lib/scene.glsl"

// History generated under other path rules (shift, thresholds, bounces, frame size) cannot be
// shifted consistently: it is dropped (the first frame after a parameter change).
bool restir_same_rules(RestirSettings a, RestirSettings b) {
    return a.max_bounces == b.max_bounces && a.shift == b.shift &&
           a.rough_threshold == b.rough_threshold && a.dist_threshold == b.dist_threshold &&
           all(equal(a.frame_size, b.frame_size)) && a.mis_heuristic == b.mis_heuristic &&
           a.area == b.area;
}

// What a shift cannot re-evaluate is the suffix after the reconnection vertex x_k (k < n): its
// radiance is cached (rc_Lo), valid only where nothing it saw has moved. So when shapes moved
// between the frames, the temporal shift of such a path fails in both directions
// (reject_moved_suffix, movingSuffix = reject): the history technique then does not cover these
// paths and the canonical technique keeps their whole weight, which is exact. Paths
// reconnecting at the light vertex (k = n) and pure replay (k = 0) are re-evaluated completely
// in either geometry.
bool restir_crosses_moved_suffix(PathSample s, bool reject_moved_suffix) {
    uint k = path_rc_index(s);
    return reject_moved_suffix && scene_info.previous_geometry.x != 0u && k != 0u &&
           k < path_length(s);
}

#endif
