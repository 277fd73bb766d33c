#pragma once
// Parameters every specular-manifold estimator declares alike (SpecularManifoldSampling,
// PartitionedSMS): the Newton walk's settings, and the chain length, clamp and path tracer that
// leaves out the paths the estimator covers. One declaration, so the names, ranges and docs
// that reach the GPU, Lua, JSON and the inspector cannot drift apart between the passes.
#include "core/graph/Pass.h"
#include "core/shader/ShaderEnums.h"

namespace loom {

// The walk (Zeltner et al. 2020 Sec. 5): constraint, Newton budget, convergence, uniqueness.
inline void reflectManifoldWalk(PassReflection& r) {
    r.paramEnum("constraint", "angle_difference", shaderEnum("MANIFOLD_CONSTRAINT"))
        .doc("specular constraint of the walk (Zeltner et al. Sec. 5.1)");
    r.paramEnum("stepControl", "reprojection", shaderEnum("MANIFOLD_STEP"))
        .doc(
            "Newton step size: halved when the re-traced chain leaves its shapes (reference), or "
            "also when max |C_i| does not fall (descent: half-vector walks out of a denser "
            "medium need it)");
    r.param("maxIterations", 20).range(1, 1000).doc("Newton steps per walk (halvings count)");
    r.param("solverThreshold", 1e-5).min(0).doc("convergence: every |C_i| below this");
    r.param("uniquenessThreshold", 1e-5)
        .min(0)
        .doc("two solutions are one when their first directions d satisfy |d.d' - 1| < this");
}

// The path tracer that runs beside a caustic estimator, without the paths the estimator covers
// (manifold/coverage.glsl).
inline void reflectCoveredPathTracer(PassReflection& r) {
    r.param("maxBounces", 9).range(0, 64).doc("path tracer: scattering events per path");
    r.param("rrDepth", 5).range(1, 64).doc("path tracer: Russian roulette after this many bounces");
    r.paramEnum("misHeuristic", "power", shaderEnum("MIS_HEURISTIC"))
        .doc("path tracer: NEE/BSDF MIS");
    r.param("excludeCovered", true)
        .doc(
            "leave the paths the caustic estimator produces out of the path tracer (false "
            "double counts them)");
}

// Where the caustic estimator runs: receivers the camera sees directly or through purely
// specular surfaces (a pool floor under water); the path tracer leaves out the same paths.
inline void reflectReceiverDepth(PassReflection& r) {
    r.param("receiverDepth", 2)
        .range(0, 8)
        .doc(
            "purely specular vertices the camera may see a receiver through (0: primary "
            "hits only; 1: a pool floor under water)");
}

// The chain, the generalized geometric term's clamp, the path tracer without the covered paths,
// and how far one frame's walks may run (trialDispatches: the pass's default).
inline void reflectCausticPath(PassReflection& r, int trialDispatches) {
    r.param("maxChain", 2)
        .range(1, 4)
        .doc("specular vertices of a chain (1: single scattering; 2: sphere, slab)");
    r.param("geometricTermClamp", 0.0)
        .min(0)
        .doc("clamp of the generalized geometric term (0 = off; biased)");
    reflectCoveredPathTracer(r);
    r.param("trialDispatches", trialDispatches)
        .range(1, 100000)
        .doc("dispatches per frame the walks may span; unfinished estimates count as capped");
    r.param("stepBudget", 32768)
        .range(1024, 60000)
        .doc("BVH steps per invocation and dispatch (lavapipe ends loops at 65535)");
}

}  // namespace loom
