#pragma once
// Test scenes with glossy casters: a scene's smooth conductors and dielectrics made rough
// (microfacet distribution d, roughness alpha), as the SMS and partitioned-SMS tests use them.
#include "core/scene/Scene.h"

namespace loom::test {

inline void makeCastersRough(scene::Scene& scene, float alpha, scene::Microfacet d) {
    for (auto& m : scene.materials) {
        if (m.type == scene::BsdfType::Conductor)
            m.type = scene::BsdfType::RoughConductor;
        else if (m.type == scene::BsdfType::Dielectric)
            m.type = scene::BsdfType::RoughDielectric;
        else
            continue;
        m.alpha = alpha;
        m.distribution = d;
    }
}

}  // namespace loom::test
